// strategy-qp's time per plan (predict the top-k strategies, one QP per
// round for each) against the exact expert's, open loop, on the same
// held-out sampled scenes. The strategy model comes from the model directory
// in LANECHANGE_STRATEGY_MODEL (lanechange train), or else is fitted here on
// the exact plans of scenes drawn with another seed (their starts only).
#include <benchmark/benchmark.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <string>
#include <vector>

#include "lanechange/learn/model.hpp"
#include "lanechange/run/quantile.hpp"
#include "lanechange/sampler.hpp"
#include "planner/strategy_qp_planner.hpp"
#include "thread_cpu.hpp"

namespace lc = lanechange;

namespace {

constexpr std::uint64_t kTrainSeed = 2025;
constexpr std::uint64_t kTestSeed = 2026;

int env_int(const char* name, int fallback) {
  const char* v = std::getenv(name);
  return v != nullptr ? std::atoi(v) : fallback;
}

std::vector<lc::Scenario> sample(std::uint64_t seed, int count) {
  const lc::ScenarioSampler sampler(lc::Config{}, seed);
  std::vector<lc::Scenario> out;
  out.reserve(static_cast<std::size_t>(std::max(count, 0)));
  for (int i = 0; i < count; ++i) out.push_back(sampler.sample(static_cast<std::uint64_t>(i)));
  return out;
}

std::shared_ptr<const lc::learn::StrategyModel> fitted_here() {
  const lc::expert::ExpertPlanner exact(lc::planner::closed_loop_expert(lc::Config{}),
                                        std::make_shared<lc::expert::FastLaneChangeSolver>());
  lc::learn::StrategyRows rows;
  const double cap = lc::Config{}.traffic_max_speed.value();
  rows.traffic_speed_cap = cap;
  for (const lc::Scenario& s : sample(kTrainSeed, env_int("LANECHANGE_BENCH_TRAIN", 300))) {
    const lc::expert::ExpertResult r = exact.plan(s);
    if (r.status != lc::expert::PlanStatus::Converged) continue;
    std::vector<int> modes;
    for (const auto& o : r.occupancy) modes.push_back(o ? static_cast<int>(*o) : -1);
    rows.features.push_back(lc::learn::strategy_features(s, cap));
    rows.labels.push_back(lc::learn::strategy_of(modes));
  }
  return std::make_shared<const lc::learn::StrategyModel>(
      lc::learn::StrategyModel::fit(rows, lc::learn::StrategySettings{}));
}

const lc::planner::StrategyQpPlanner& planner() {
  static const lc::planner::StrategyQpPlanner p = [] {
    const char* dir = std::getenv("LANECHANGE_STRATEGY_MODEL");
    auto model = dir != nullptr ? lc::learn::Model::load(dir).strategy() : fitted_here();
    return lc::planner::StrategyQpPlanner(lc::Config{}, std::move(model));
  }();
  return p;
}

const std::vector<lc::Scenario>& scenes() {
  static const std::vector<lc::Scenario> all =
      sample(kTestSeed, env_int("LANECHANGE_BENCH_SCENARIOS", 100));
  return all;
}

// Each plan's CPU time, for the median and tail the targets are stated in
// (Google Benchmark's own column is the mean).
template <class Plan>
void time_plans(benchmark::State& state, Plan&& plan) {
  std::vector<double> ms;
  std::size_t i = 0;
  for (auto _ : state) {
    const double start = thread_cpu_ms();
    auto r = plan(scenes()[i++ % scenes().size()]);
    ms.push_back(thread_cpu_ms() - start);
    benchmark::DoNotOptimize(r);
  }
  state.counters["plan_ms_median"] = lc::run::nearest_rank(ms, 0.5);
  state.counters["plan_ms_p99"] = lc::run::nearest_rank(ms, 0.99);
}

void BM_StrategyQpPlan(benchmark::State& state) {
  time_plans(state, [](const lc::Scenario& s) { return planner().plan(s); });
}
BENCHMARK(BM_StrategyQpPlan)->Iterations(300)->Unit(benchmark::kMillisecond);

const std::shared_ptr<const lc::learn::StrategyModel>& strategy_model() {
  static const auto model =
      std::getenv("LANECHANGE_STRATEGY_MODEL") != nullptr
          ? lc::learn::Model::load(std::getenv("LANECHANGE_STRATEGY_MODEL")).strategy()
          : fitted_here();
  return model;
}

using Vote = std::vector<lc::learn::Strategy> (lc::learn::StrategyModel::*)(const lc::Scenario&,
                                                                            int) const;

void run_vote(benchmark::State& state, Vote vote) {
  const auto& model = strategy_model();
  std::size_t i = 0;
  for (auto _ : state) {
    auto r = ((*model).*vote)(scenes()[i++ % scenes().size()], 5);
    benchmark::DoNotOptimize(r);
  }
  state.counters["rows"] = model->rows();
}

// The kNN vote alone: the learned part of a plan. Its neighbours skip the
// behaviors the one-hot features rule out.
void BM_StrategyPredict(benchmark::State& state) {
  run_vote(state, &lc::learn::StrategyModel::predict);
}
BENCHMARK(BM_StrategyPredict)->Iterations(1000)->Unit(benchmark::kMicrosecond);

// The same vote with every row's distance computed: the skip's speedup is
// the ratio of the two medians in one run.
void BM_StrategyPredictScan(benchmark::State& state) {
  run_vote(state, &lc::learn::StrategyModel::predict_by_scan);
}
BENCHMARK(BM_StrategyPredictScan)->Iterations(1000)->Unit(benchmark::kMicrosecond);

void BM_ExactPlan(benchmark::State& state) {
  time_plans(state, [](const lc::Scenario& s) { return planner().exact().plan(s); });
}
BENCHMARK(BM_ExactPlan)->Iterations(300)->Unit(benchmark::kMillisecond);

}  // namespace

int main(int argc, char** argv) try {
  benchmark::Initialize(&argc, argv);
  (void)planner();  // the model's fit is setup, not a plan
  benchmark::RunSpecifiedBenchmarks();
  char host[256] = "?";
  (void)gethostname(host, sizeof host);
  std::printf("== strategy benchmark ==\ntest seed %llu, %zu scenes (N = 50), host %s, model %s\n",
              static_cast<unsigned long long>(kTestSeed), scenes().size(), host,
              std::getenv("LANECHANGE_STRATEGY_MODEL") != nullptr ? "from the model directory"
                                                                  : "fitted on exact plans here");
  benchmark::Shutdown();
  return 0;
} catch (const std::exception& e) {
  // A model directory that does not load, say.
  std::fprintf(stderr, "bench_strategy: %s\n", e.what());
  return 2;
}
