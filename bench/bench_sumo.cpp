// SUMO's share of a co-simulated step (docs/sumo.md): moving the ego into
// SUMO and advancing SUMO one step, per step of whole episodes on the
// built-in highway (seeds 1..LANECHANGE_BENCH_SUMO_EPISODES, default 5),
// beside the planner's own step. The planner is the lane keeper's cheap
// `keep-lane` and the expert `miqp`. Counters in ms of wall time: median,
// 90th percentile and largest of SUMO's steps, and the planner's median.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include "lanechange/baselines/baselines.hpp"
#include "lanechange/run/quantile.hpp"
#include "lanechange/sumo/cosim.hpp"

namespace {

namespace lc = lanechange;

int episodes() {
  const char* v = std::getenv("LANECHANGE_BENCH_SUMO_EPISODES");
  return v != nullptr ? std::max(1, std::atoi(v)) : 5;
}

void run_episodes(benchmark::State& state, const char* planner_name) {
  const lc::Config config;
  const auto planner = lc::baselines::make_planner(planner_name, config);
  lc::sumo::HighwaySettings highway;
  highway.density = static_cast<double>(state.range(0));
  lc::sumo::CoSimSettings settings;
  settings.work_dir = (std::filesystem::temp_directory_path() / "lanechange_bench_sumo").string();
  std::vector<double> sumo_ms;
  std::vector<double> planner_ms;
  for (auto _ : state) {
    for (int seed = 1; seed <= episodes(); ++seed) {
      highway.seed = seed;
      const lc::sumo::CoSimResult r = lc::sumo::run_highway(*planner, config, highway, settings);
      sumo_ms.insert(sumo_ms.end(), r.sumo_step_ms.begin(), r.sumo_step_ms.end());
      for (const auto& s : r.rollout.steps) {
        if (!s.lane_keeping) planner_ms.push_back(s.compute_ms);
      }
    }
  }
  std::filesystem::remove_all(settings.work_dir);
  state.counters["sumo_step_ms_median"] = lc::run::nearest_rank(sumo_ms, 0.5);
  state.counters["sumo_step_ms_p90"] = lc::run::nearest_rank(sumo_ms, 0.9);
  state.counters["sumo_step_ms_max"] = lc::run::nearest_rank(sumo_ms, 1.0);
  state.counters["planner_step_ms_median"] =
      planner_ms.empty() ? 0.0 : lc::run::nearest_rank(planner_ms, 0.5);
  state.counters["steps"] = static_cast<double>(sumo_ms.size());
}

void BM_SumoStepKeepLane(benchmark::State& state) { run_episodes(state, "keep-lane"); }
void BM_SumoStepMiqp(benchmark::State& state) { run_episodes(state, "miqp"); }

// Light and dense traffic: cars per lane and km.
BENCHMARK(BM_SumoStepKeepLane)->Arg(15)->Arg(40)->Unit(benchmark::kMillisecond)->Iterations(1);
BENCHMARK(BM_SumoStepMiqp)->Arg(15)->Arg(40)->Unit(benchmark::kMillisecond)->Iterations(1);

}  // namespace

BENCHMARK_MAIN();
