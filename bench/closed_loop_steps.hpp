#pragma once
// Closed-loop step times of one planner, shared by the benchmarks of our
// planners and the baselines: the compute time of each act() the simulator
// measured (the same for every planner), inside whole rollouts of sampled
// scenes of seed 2026. Counters: the median, 90th percentile and largest of
// the steps the planner itself served (not the lane keeper's once the
// manoeuvre is over), in ms of wall time; rollouts per second.
// Environment: LANECHANGE_BENCH_LOOP_COUNT scenes (default 12).
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cstdlib>
#include <vector>

#include "lanechange/planner/planner.hpp"
#include "lanechange/sampler.hpp"
#include "lanechange/sim/simulator.hpp"

namespace lanechange::bench {

inline int scene_count() {
  const char* v = std::getenv("LANECHANGE_BENCH_LOOP_COUNT");
  return v != nullptr ? std::max(1, std::atoi(v)) : 12;
}

inline double percentile(std::vector<double> v, double q) {
  if (v.empty()) return 0.0;
  std::sort(v.begin(), v.end());
  return v[static_cast<std::size_t>(q * static_cast<double>(v.size() - 1))];
}

inline void run_closed_loop_steps(benchmark::State& state,
                                  const planner::ClosedLoopPlanner& planner, const Config& config) {
  const ScenarioSampler sampler(config, 2026);
  std::vector<double> steps;
  std::vector<double> planned;  // the planner's own steps, not its fallback's
  long long rollouts = 0;
  for (auto _ : state) {
    for (int i = 0; i < scene_count(); ++i) {
      const sim::Rollout r =
          sim::simulate(sampler.sample(static_cast<std::uint64_t>(i)), planner, config);
      for (const auto& s : r.steps) {
        if (s.lane_keeping) continue;
        steps.push_back(s.compute_ms);
        if (s.status == planner::ActStatus::Planned) planned.push_back(s.compute_ms);
      }
      ++rollouts;
    }
  }
  state.counters["step_ms_median"] = percentile(steps, 0.5);
  state.counters["step_ms_p90"] = percentile(steps, 0.9);
  state.counters["step_ms_max"] = percentile(steps, 1.0);
  state.counters["planned_step_ms_median"] = percentile(planned, 0.5);
  state.counters["rollouts_per_s"] =
      benchmark::Counter(static_cast<double>(rollouts), benchmark::Counter::kIsRate);
}

}  // namespace lanechange::bench
