// Closed-loop step times of the sampling baselines, dwa and lattice (issue
// 12's target: at most 1 ms median per step), measured as
// bench_closed_loop measures ours (closed_loop_steps.hpp).
#include <benchmark/benchmark.h>

#include "closed_loop_steps.hpp"
#include "lanechange/baselines/baselines.hpp"

namespace {

void run_baseline(benchmark::State& state, const char* name) {
  lanechange::Config config;
  // Time every step, overrule none; the budgets of work bind as in evaluate.
  config.closed_loop.step_budget_ms = 1e6;
  lanechange::bench::run_closed_loop_steps(
      state, *lanechange::baselines::make_planner(name, config), config);
}

void BM_DwaStep(benchmark::State& state) { run_baseline(state, "dwa"); }
void BM_LatticeStep(benchmark::State& state) { run_baseline(state, "lattice"); }

BENCHMARK(BM_DwaStep)->Unit(benchmark::kMillisecond)->Iterations(1);
BENCHMARK(BM_LatticeStep)->Unit(benchmark::kMillisecond)->Iterations(1);

}  // namespace

BENCHMARK_MAIN();
