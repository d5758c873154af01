// Closed-loop step times of our planners (see step_timing.hpp for what is
// measured and how).
#include "step_timing.hpp"

namespace lc = lanechange;

namespace {

void run_planner(benchmark::State& state, const char* name) {
  lc::Config config;
  config.closed_loop.step_budget_ms = 1e6;  // time every step, overrule none
  lc::bench::time_planner_steps(state, *lc::planner::make_planner(name, config), config);
}

void BM_MiqpClosedLoopStep(benchmark::State& state) { run_planner(state, "miqp"); }
void BM_KeepLaneStep(benchmark::State& state) { run_planner(state, "keep-lane"); }

BENCHMARK(BM_MiqpClosedLoopStep)->Unit(benchmark::kMillisecond)->Iterations(1);
BENCHMARK(BM_KeepLaneStep)->Unit(benchmark::kMillisecond)->Iterations(1);

}  // namespace

BENCHMARK_MAIN();
