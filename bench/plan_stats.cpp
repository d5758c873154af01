// Where a plan's time goes, scene by scene: the expert plans sampled scenes
// (default config, seed 2026, as bench_expert) one after another on this
// thread and prints, per plan, its status, objective (to compare search
// variants' optima), rounds, node QPs (those spent on
// incumbents apart), interior-point iterations and CPU time, then the
// median and mean plan and the totals. Not a timing claim of its own (the
// benchmarks make those); it shows which plans and rounds carry the mean.
//   plan_stats [COUNT=100] [--quiet] [--config FILE] [--fixed-gap] [--target-lane-cars N]
// --config plans under a configuration file (docs/config.md) instead of the
// defaults, to compare search settings; --fixed-gap plans through Eq. 1's gap
// alone (expert.gap = fixed); --target-lane-cars samples dense scenes with N
// cars in the target lane.

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <map>
#include <memory>
#include <numeric>
#include <string>
#include <vector>

#include "lanechange/config.hpp"
#include "lanechange/expert/planner.hpp"
#include "lanechange/sampler.hpp"
#include "thread_cpu.hpp"

namespace {

namespace lc = lanechange;
namespace ex = lanechange::expert;

struct Totals {
  long rounds = 0, nodes = 0, incumbent_qps = 0, iterations = 0;
  std::vector<double> plan_ms;
  std::map<std::string, int> statuses;
};

}  // namespace

int main(int argc, char** argv) {
  const int count = argc > 1 ? std::atoi(argv[1]) : 100;
  bool quiet = false;
  lc::Config config;
  for (int i = 2; i + 1 < argc; ++i) {
    if (std::strcmp(argv[i], "--config") != 0) continue;
    try {
      config = lc::load_config(argv[i + 1]);
    } catch (const std::exception& e) {
      std::fprintf(stderr, "plan_stats: %s\n", e.what());
      return 2;
    }
  }
  for (int i = 2; i < argc; ++i) {
    quiet = quiet || std::strcmp(argv[i], "--quiet") == 0;
    if (std::strcmp(argv[i], "--fixed-gap") == 0) config.expert.gap = lc::GapChoice::Fixed;
    if (std::strcmp(argv[i], "--target-lane-cars") == 0 && i + 1 < argc) {
      const double cars = std::atof(argv[++i]);
      config.sampler.target_lane_cars = {cars, cars};
    }
  }
  if (count < 1) {
    std::fprintf(stderr, "plan_stats: COUNT must be a positive number of scenes\n");
    return 2;
  }
  const lc::ScenarioSampler sampler(config, 2026);
  const ex::ExpertPlanner planner(config, std::make_shared<ex::FastLaneChangeSolver>());
  Totals totals;
  // One workspace and memory for every plan, as a thread that plans one
  // scene after another keeps them.
  const auto workspace = planner.solver().make_workspace();
  ex::PlanMemory memory;
  ex::PlanHints hints;
  hints.workspace = workspace.get();
  hints.memory = &memory;
  for (int i = 0; i < count; ++i) {
    const lc::Scenario scene = sampler.sample(static_cast<std::uint64_t>(i));
    const double start = thread_cpu_ms();
    const ex::ExpertResult result = planner.plan(scene, {}, hints);
    const double ms = thread_cpu_ms() - start;
    long nodes = 0, incumbent_qps = 0, iterations = 0;
    std::string per_round;
    for (const ex::RoundReport& r : result.rounds) {
      nodes += r.nodes;
      incumbent_qps += r.incumbent_qps;
      iterations += r.qp_iterations;
      per_round += ' ' + std::to_string(r.nodes) + '/' + std::to_string(r.incumbent_qps);
    }
    const std::string status(ex::to_string(result.status));
    if (!quiet) {
      std::printf(
          "%4d %-15s objective %12.6f  rounds %2zu  QPs %5ld (incumbents %4ld)  iterations %6ld  "
          "%8.1f ms |%s\n",
          i, status.c_str(), result.objective, result.rounds.size(), nodes, incumbent_qps,
          iterations, ms, per_round.c_str());
    }
    totals.rounds += static_cast<long>(result.rounds.size());
    totals.nodes += nodes;
    totals.incumbent_qps += incumbent_qps;
    totals.iterations += iterations;
    totals.plan_ms.push_back(ms);
    ++totals.statuses[status];
  }
  std::vector<double> sorted = totals.plan_ms;
  std::sort(sorted.begin(), sorted.end());
  const double median = sorted.size() % 2 == 1
                            ? sorted[sorted.size() / 2]
                            : 0.5 * (sorted[sorted.size() / 2 - 1] + sorted[sorted.size() / 2]);
  const double total_ms = std::accumulate(sorted.begin(), sorted.end(), 0.0);
  std::printf(
      "plans %d: median %.1f ms, mean %.1f ms of CPU; rounds %ld, node QPs %ld (incumbents %ld), "
      "iterations %ld;",
      count, median, total_ms / count, totals.rounds, totals.nodes, totals.incumbent_qps,
      totals.iterations);
  for (const auto& [status, n] : totals.statuses) std::printf(" %s %d", status.c_str(), n);
  std::printf("\n");
  return 0;
}
