// Closed-loop step times of our planners: one act() of a planner session,
// measured inside whole rollouts of sampled scenes (the re-plan is
// warm-started from the last plan, so a step is only meaningful in its
// rollout); closed_loop_steps.hpp has the counters and the environment,
// LANECHANGE_BENCH_CONFIG below a config file.
#include <benchmark/benchmark.h>

#include <cstdlib>
#include <exception>
#include <string>

#include "closed_loop_steps.hpp"
#include "lanechange/config.hpp"
#include "lanechange/planner/planner.hpp"

namespace {

void run_planner(
    benchmark::State& state, const char* name, const std::string& model = "",
    double lookahead_tolerance = lanechange::Config{}.closed_loop.lookahead_tolerance) {
  // LANECHANGE_BENCH_CONFIG: a config file (lanechange --config) instead of the defaults.
  const char* path = std::getenv("LANECHANGE_BENCH_CONFIG");
  lanechange::Config config;
  try {
    if (path != nullptr) config = lanechange::load_config(path);
  } catch (const std::exception& e) {
    state.SkipWithError(e.what());
    return;
  }
  // Time every step, overrule none; the budgets of work bind as in evaluate.
  config.closed_loop.step_budget_ms = 1e6;
  config.closed_loop.lookahead_tolerance = lookahead_tolerance;
  lanechange::bench::run_closed_loop_steps(
      state, *lanechange::planner::make_planner(name, config, model), config);
}

void BM_MiqpClosedLoopStep(benchmark::State& state) { run_planner(state, "miqp"); }
void BM_KeepLaneStep(benchmark::State& state) { run_planner(state, "keep-lane"); }

// The learned planners need a trained model (lanechange train):
// LANECHANGE_BENCH_MODEL names its directory; without it they are skipped.
void run_learned(
    benchmark::State& state, const char* name,
    double lookahead_tolerance = lanechange::Config{}.closed_loop.lookahead_tolerance) {
  const char* model = std::getenv("LANECHANGE_BENCH_MODEL");
  if (model == nullptr) {
    state.SkipWithError("set LANECHANGE_BENCH_MODEL to a model directory (lanechange train)");
    return;
  }
  run_planner(state, name, model, lookahead_tolerance);
}

// mlp-miqp's step target (2 us median) counts the network's steps,
// planned_step_ms_median; the second run rolls the look-ahead out every
// step, for the ratio in the same run.
void run_mlp_miqp(benchmark::State& state, double lookahead_tolerance) {
  run_learned(state, "mlp-miqp", lookahead_tolerance);
}
void BM_MlpMiqpStep(benchmark::State& state) {
  run_mlp_miqp(state, lanechange::Config{}.closed_loop.lookahead_tolerance);
}
void BM_MlpMiqpStepRolledOutEveryStep(benchmark::State& state) { run_mlp_miqp(state, 0.0); }

// strategy-qp's re-plans (target: 0.5 ms per plan): the same model
// directory, its strategy part.
void BM_StrategyQpStep(benchmark::State& state) { run_learned(state, "strategy-qp"); }

BENCHMARK(BM_MiqpClosedLoopStep)->Unit(benchmark::kMillisecond)->Iterations(1);
BENCHMARK(BM_KeepLaneStep)->Unit(benchmark::kMillisecond)->Iterations(1);
BENCHMARK(BM_MlpMiqpStep)->Unit(benchmark::kMillisecond)->Iterations(1);
BENCHMARK(BM_StrategyQpStep)->Unit(benchmark::kMillisecond)->Iterations(1);
BENCHMARK(BM_MlpMiqpStepRolledOutEveryStep)->Unit(benchmark::kMillisecond)->Iterations(1);

}  // namespace

BENCHMARK_MAIN();
