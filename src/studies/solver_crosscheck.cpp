#include "lanechange/studies/solver_crosscheck.hpp"

#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <stdexcept>

#include "lanechange/error.hpp"
#include "lanechange/expert/crosscheck.hpp"
#include "lanechange/expert/planner.hpp"
#include "lanechange/sampler.hpp"
#include "lanechange/scenario.hpp"
#include "run/json_numbers.hpp"

namespace lanechange::studies {

namespace {

using nlohmann::json;

json case_row(const expert::CrossCheckCase& c, std::uint64_t seed, int steps) {
  return {{"index", c.index},
          {"seed", seed},
          {"steps", steps},
          {"behavior", c.behavior},
          {"fast_status", expert::to_string(c.fast_status)},
          {"reference_status", expert::to_string(c.reference_status)},
          {"fast_objective", run::number_or_null(c.fast_objective)},
          {"reference_objective", run::number_or_null(c.reference_objective)},
          {"relative_difference", c.relative_difference},
          {"fast_ms", c.fast_ms},
          {"reference_ms", c.reference_ms},
          {"fast_nodes", c.fast_nodes},
          {"reference_nodes", c.reference_nodes},
          {"agree", c.agree}};
}

// A case to solve: sampled (no stored side) or read from an earlier output.
struct Case {
  std::uint64_t index = 0;
  std::uint64_t seed = 0;
  int steps = 0;
  std::optional<json> scenario;
  std::optional<Config> config;
  std::optional<expert::StoredReference> reference;
  /// Of the scene's target_lane_gaps(best), from the back; none: Eq. 1's gap.
  std::optional<std::size_t> gap;
};

Case parse_stored_case(const std::string& line, long long line_number, std::uint64_t seed,
                       int steps) {
  const std::string where = "cross-check line " + std::to_string(line_number);
  try {
    const auto row = json::parse(line);
    Case c;
    if (row.contains("scenario")) c.scenario = row.at("scenario");
    // A replay checks what the stored verdict was made for, whatever today's
    // defaults are: a case without its config cannot be replayed faithfully.
    if (!row.contains("config")) {
      throw InputError(where, "carries no \"config\" (the config the case was made with)");
    }
    // Only the expert's part: a planner's options do not touch the MIQP.
    c.config = config_from_json(expert_data_config(row.at("config")));
    c.index = row.at("index").get<std::uint64_t>();
    c.seed = row.value("seed", seed);
    c.steps = row.value("steps", steps);
    if (row.contains("gap")) c.gap = row.at("gap").get<std::size_t>();
    expert::StoredReference reference;
    reference.status = expert::parse_miqp_status(row.at("reference_status").get<std::string>());
    const auto& objective = row.at("reference_objective");
    reference.objective = objective.is_null() ? expert::kInfinity : objective.get<double>();
    reference.ms = row.value("reference_ms", 0.0);
    reference.nodes = row.value("reference_nodes", 0L);
    c.reference = reference;
    return c;
  } catch (const json::exception& e) {
    throw InputError(where, e.what());
  }
}

class Checker {
 public:
  explicit Checker(const CrossCheckOptions& options) : o_(options) {}

  // A sampled scene: its one case, or one per gap.
  void run_sampled(std::uint64_t index) {
    const Case sampled{index, o_.seed, o_.steps, {}, {}, {}, {}};
    if (!o_.every_gap) {
      run(sampled);
      return;
    }
    const Scenario scenario = ScenarioSampler(config_of(sampled), o_.seed).sample(index);
    const auto gaps = expert::target_lane_gaps(scenario, GapChoice::Best);
    for (std::size_t g = 0; g < gaps.size(); ++g) {
      Case one = sampled;
      one.gap = g;
      run(one);
    }
  }

  void run(const Case& stored) {
    const Config config = config_of(stored);
    const Scenario scenario = stored.scenario
                                  ? scenario_from_json(*stored.scenario, config)
                                  : ScenarioSampler(config, stored.seed).sample(stored.index);
    std::optional<expert::Gap> gap;
    if (stored.gap) {
      const auto gaps = expert::target_lane_gaps(scenario, GapChoice::Best);
      if (*stored.gap >= gaps.size()) {
        throw InputError("gap", "case " + std::to_string(stored.index) + " names gap " +
                                    std::to_string(*stored.gap) + " of a scene with " +
                                    std::to_string(gaps.size()));
      }
      gap = gaps[*stored.gap];
    }
    const auto qp = gap ? expert::first_round_problem(scenario, config, *gap)
                        : expert::first_round_problem(scenario, config);
    expert::CrossCheckCase c;
    if (stored.reference) {
      c = expert::compare_with_reference(fast_.solve(qp, {}), *stored.reference, o_.tolerance);
    } else {
      const expert::ReferenceLaneChangeSolver reference(config.expert.big_m);
      c = expert::cross_check(qp, fast_, reference, {}, o_.tolerance);
    }
    c.index = stored.index;
    c.behavior = std::string(to_string(scenario.behavior));
    // A reference that hit its limit decides nothing: count agreement on the rest.
    const bool decided = c.reference_status == expert::MiqpStatus::Optimal ||
                         c.reference_status == expert::MiqpStatus::Infeasible;
    report_.total += decided || !stored.reference ? 1 : 0;
    report_.agreed += c.agree ? 1 : 0;
    json row = case_row(c, stored.seed, stored.steps);
    if (gap) {
      row["gap"] = *stored.gap;
      row["gap_cars"] = expert::describe(scenario, *gap);
    }
    row["scenario"] = scenario_to_json(scenario);
    row["config"] = config;
    if (o_.cases != nullptr) *o_.cases << row.dump() << std::endl;
    if (o_.progress != nullptr) *o_.progress << row.dump() << "\n";
  }

  [[nodiscard]] CrossCheckReport report() const { return report_; }

 private:
  [[nodiscard]] Config config_of(const Case& c) const {
    Config config = c.config ? *c.config : o_.config;
    if (c.steps > 0) config.expert.steps = c.steps;
    return config;
  }

  const CrossCheckOptions& o_;
  const expert::FastLaneChangeSolver fast_;
  CrossCheckReport report_;
};

}  // namespace

CrossCheckReport run_crosscheck(const CrossCheckOptions& o) {
  Checker checker(o);
  if (!o.replay_path.empty()) {
    std::ifstream in(o.replay_path);
    if (!in) throw InputError("--replay", o.replay_path + " cannot be read");
    std::string line;
    long long line_number = 0;
    while (std::getline(in, line)) {
      ++line_number;
      if (!line.empty()) checker.run(parse_stored_case(line, line_number, o.seed, o.steps));
    }
    return checker.report();
  }
  for (long long i = o.first; i < o.first + o.count; ++i) {
    checker.run_sampled(static_cast<std::uint64_t>(i));
  }
  return checker.report();
}

}  // namespace lanechange::studies
