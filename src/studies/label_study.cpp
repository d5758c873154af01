#include "lanechange/studies/label_study.hpp"

#include <array>
#include <cstdio>
#include <memory>
#include <vector>

#include "lanechange/checks.hpp"
#include "lanechange/expert/planner.hpp"
#include "lanechange/run/markdown.hpp"
#include "lanechange/sampler.hpp"

namespace lanechange::studies {

namespace {

constexpr std::array kTolerances = {0.02, 0.05, 0.10, 0.20, 0.30};
constexpr std::array kReferences = {ReversalReference::TargetCenter, ReversalReference::RunningMax};

using Counts = std::array<long long, 3>;  // well-posed, ill-posed, failure

// Only the reversal test depends on the tolerance: a failure (no solution,
// lane not reached, collision) stays one under every reading.
Label label_under(const Trajectory& t, const Scenario& s, LabelTolerances tolerances) {
  if (t.label == Label::Failure) return Label::Failure;
  return label_trajectory(t.ys(), t.ego.back().theta, s.lane_width, tolerances).label;
}

std::string table(const std::vector<Counts>& counts, long long count) {
  run::Table t{{"reading", "tolerance", "well-posed", "ill-posed", "failure"}, {}};
  for (std::size_t r = 0; r < kReferences.size(); ++r) {
    for (std::size_t j = 0; j < kTolerances.size(); ++j) {
      const Counts& c = counts[r * kTolerances.size() + j];
      auto share = [&](int k) {
        char text[32];
        std::snprintf(text, sizeof text, "%.1f%%",
                      100.0 * static_cast<double>(c[k]) / static_cast<double>(count));
        return std::string(text);
      };
      char tolerance[32];
      std::snprintf(tolerance, sizeof tolerance, "%.2f m", kTolerances[j]);
      t.rows.push_back(
          {kReferences[r] == ReversalReference::TargetCenter ? "target_center" : "running_max",
           tolerance, share(0), share(1), share(2)});
    }
  }
  return run::markdown(t);
}

}  // namespace

std::string run_label_study(const LabelStudyOptions& o) {
  const ScenarioSampler sampler(o.config, o.seed);
  const expert::ExpertPlanner planner(o.config, std::make_shared<expert::FastLaneChangeSolver>());
  std::vector<Counts> counts(kTolerances.size() * kReferences.size(), Counts{});
  for (long long i = 0; i < o.count; ++i) {
    const Scenario s = sampler.sample(static_cast<std::uint64_t>(i));
    const Trajectory t = planner.to_trajectory(planner.plan(s), s);
    for (std::size_t r = 0; r < kReferences.size(); ++r) {
      for (std::size_t j = 0; j < kTolerances.size(); ++j) {
        LabelTolerances tolerances = o.config.labels;
        tolerances.reversal = kTolerances[j];
        tolerances.reference = kReferences[r];
        ++counts[r * kTolerances.size() + j][static_cast<int>(label_under(t, s, tolerances))];
      }
    }
  }
  return table(counts, o.count);
}

}  // namespace lanechange::studies
