// Closed-loop step times of the MPC baseline (docs/baselines.md, "mpc"),
// measured as for our planners (closed_loop_steps.hpp). The step's budget of
// work (mpc.step_iterations) stays on, as in evaluate: a solve stopped by it
// counts with its time.
#include "closed_loop_steps.hpp"
#include "lanechange/baselines/baselines.hpp"

namespace lc = lanechange;

namespace {

void BM_MpcClosedLoopStep(benchmark::State& state) {
  lc::Config config;
  // Time every step, overrule none; the budgets of work bind as in evaluate.
  config.closed_loop.step_budget_ms = 1e6;
  lc::bench::run_closed_loop_steps(state, *lc::baselines::make_planner("mpc", config), config);
}

BENCHMARK(BM_MpcClosedLoopStep)->Unit(benchmark::kMillisecond)->Iterations(1);

}  // namespace

BENCHMARK_MAIN();
