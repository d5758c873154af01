// Closed-loop step times of our planners: one act() of a planner session,
// measured inside whole rollouts of sampled scenes (the re-plan is
// warm-started from the last plan, so a step is only meaningful in its
// rollout); closed_loop_steps.hpp has the counters and the environment.
#include <benchmark/benchmark.h>

#include "closed_loop_steps.hpp"
#include "lanechange/planner/planner.hpp"

namespace {

void run_planner(benchmark::State& state, const char* name) {
  lanechange::Config config;
  config.closed_loop.step_budget_ms = 1e6;  // time every step, overrule none
  lanechange::bench::run_closed_loop_steps(state, *lanechange::planner::make_planner(name, config),
                                           config);
}

void BM_MiqpClosedLoopStep(benchmark::State& state) { run_planner(state, "miqp"); }
void BM_KeepLaneStep(benchmark::State& state) { run_planner(state, "keep-lane"); }

BENCHMARK(BM_MiqpClosedLoopStep)->Unit(benchmark::kMillisecond)->Iterations(1);
BENCHMARK(BM_KeepLaneStep)->Unit(benchmark::kMillisecond)->Iterations(1);

}  // namespace

BENCHMARK_MAIN();
