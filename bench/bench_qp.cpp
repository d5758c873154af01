// The node QP's interior-point iteration against the stage-wise Riccati
// limit. The QPs are the fast solver's own: for each sampled scene, the root
// relaxation of its first round and the QP of the round's optimal lane modes
// (default configuration). The limit is one dense Riccati factorization and
// one solve of the same stages' LQ problem: the core of every Newton step,
// which an iteration repeats with the rows' weights added (HPIPM's scheme).
// After the runs the program prints the medians per iteration and the ratio
// measured in this run.
#include <benchmark/benchmark.h>

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <vector>

#include "expert/fast_solver_internal.hpp"
#include "lanechange/expert/crosscheck.hpp"
#include "lanechange/run/quantile.hpp"
#include "lanechange/sampler.hpp"
#include "run_then_summarize.hpp"
#include "thread_cpu.hpp"

namespace lc = lanechange;
namespace ex = lanechange::expert;

namespace {

constexpr std::uint64_t kSeed = 2026;
constexpr int kRepeats = 20;  // solves per QP and sample: a solve takes about 0.2 ms

int scene_count() {
  const char* v = std::getenv("LANECHANGE_BENCH_SCENARIOS");
  return v != nullptr ? std::atoi(v) : 60;
}

// The root relaxation and the optimal modes' QP of each scene's first round.
const std::vector<ex::StructuredQp>& node_qps() {
  static const std::vector<ex::StructuredQp> all = [] {
    const lc::Config config;
    const lc::ScenarioSampler sampler(config, kSeed);
    const ex::FastLaneChangeSolver solver;
    std::vector<ex::StructuredQp> out;
    for (int i = 0; i < scene_count(); ++i) {
      const auto problem =
          ex::first_round_problem(sampler.sample(static_cast<std::uint64_t>(i)), config);
      ex::detail::FastWorkspace ws;
      ex::detail::prepare_round(problem, {}, ws);
      const std::vector<int> free(static_cast<std::size_t>(problem.steps) + 1,
                                  ex::detail::kFreeMode);
      if (ex::detail::solve_node(problem, free, ws).feasible) out.push_back(ws.node);
      const auto optimum = solver.solve(problem, {}, {});
      if (!optimum.has_solution()) continue;
      if (ex::detail::solve_node(problem, optimum.modes, ws).feasible) out.push_back(ws.node);
    }
    return out;
  }();
  return all;
}

struct Samples {
  std::vector<double> iteration_us, riccati_us, iterations, rows;
};
Samples g_samples;

void BM_NodeQpIteration(benchmark::State& state) {
  const auto& qps = node_qps();
  ex::QpWorkspace ws;
  std::size_t i = 0;
  for (auto _ : state) {
    const ex::StructuredQp& qp = qps[i++ % qps.size()];
    const std::vector<Eigen::Vector2d> start(static_cast<std::size_t>(qp.steps()),
                                             Eigen::Vector2d::Zero());
    int iterations = 0;
    const double t0 = thread_cpu_ms();
    for (int r = 0; r < kRepeats; ++r) {
      ws.setup(qp);
      ws.set_initial_controls(start);
      const auto result = ex::solve_structured_qp(qp, ws, {});
      iterations += result.iterations;
      benchmark::DoNotOptimize(result);
    }
    const double ms = thread_cpu_ms() - t0;
    if (iterations == 0) continue;
    g_samples.iteration_us.push_back(1e3 * ms / iterations);
    g_samples.iterations.push_back(static_cast<double>(iterations) / kRepeats);
    std::size_t rows = 0;
    for (const auto& stage : qp.stages) rows += stage.rows.size();
    g_samples.rows.push_back(static_cast<double>(rows));
  }
}

using StateMatrix = Eigen::Matrix<double, ex::kQpStates, ex::kQpStates>;
using Gain = Eigen::Matrix<double, ex::kQpControls, ex::kQpStates>;

// One Newton step's core on the QP's stages without rows: the backward
// Riccati recursion (dense 7 x 7 stage matrices, the 2 x 2 control block
// factored) and the forward pass of the step.
struct RiccatiLimit {
  std::vector<Gain> gain;
  std::vector<Eigen::Vector2d> feedforward;
  std::vector<ex::QpStageVector> step;

  double run(const ex::StructuredQp& qp) {
    const int n = qp.steps();
    gain.resize(static_cast<std::size_t>(n));
    feedforward.resize(static_cast<std::size_t>(n));
    step.resize(static_cast<std::size_t>(n) + 1);
    StateMatrix P = qp.stages[n].H.topLeftCorner<ex::kQpStates, ex::kQpStates>();
    ex::QpStateVector p = qp.stages[n].h.head<ex::kQpStates>();
    for (int k = n - 1; k >= 0; --k) {
      const ex::QpStage& st = qp.stages[k];
      const Eigen::Matrix<double, ex::kQpStates, ex::kQpControls> PB = P * st.B;
      const Eigen::Matrix2d R =
          st.H.bottomRightCorner<ex::kQpControls, ex::kQpControls>() + st.B.transpose() * PB;
      const Gain S =
          st.H.bottomLeftCorner<ex::kQpControls, ex::kQpStates>() + PB.transpose() * st.A;
      const Eigen::LLT<Eigen::Matrix2d> factor(R);
      gain[k] = -factor.solve(S);
      const Eigen::Vector2d r = st.h.tail<ex::kQpControls>() + st.B.transpose() * p;
      feedforward[k] = -factor.solve(r);
      P = st.H.topLeftCorner<ex::kQpStates, ex::kQpStates>() + st.A.transpose() * P * st.A +
          S.transpose() * gain[k];
      p = st.h.head<ex::kQpStates>() + st.A.transpose() * p + S.transpose() * feedforward[k];
    }
    ex::QpStateVector s = ex::QpStateVector::Zero();
    for (int k = 0; k < n; ++k) {
      const Eigen::Vector2d u = gain[k] * s + feedforward[k];
      step[k] << s, u;
      s = qp.stages[k].A * s + qp.stages[k].B * u;
    }
    step[n] << s, Eigen::Vector2d::Zero();
    return s.sum();
  }
};

void BM_RiccatiLimit(benchmark::State& state) {
  const auto& qps = node_qps();
  RiccatiLimit limit;
  std::size_t i = 0;
  for (auto _ : state) {
    const ex::StructuredQp& qp = qps[i++ % qps.size()];
    const double t0 = thread_cpu_ms();
    for (int r = 0; r < kRepeats; ++r) benchmark::DoNotOptimize(limit.run(qp));
    g_samples.riccati_us.push_back(1e3 * (thread_cpu_ms() - t0) / kRepeats);
  }
}

double median(const std::vector<double>& v) {
  return v.empty() ? 0.0 : lc::run::nearest_rank(v, 0.5);
}

void print_summary() {
  const double iteration = median(g_samples.iteration_us);
  const double riccati = median(g_samples.riccati_us);
  std::printf("\n== node QP benchmark summary ==\n");
  std::printf("seed %llu, %zu node QPs (N = %d), median %.0f rows and %.1f iterations per QP\n",
              static_cast<unsigned long long>(kSeed), node_qps().size(),
              node_qps().empty() ? 0 : node_qps().front().steps(), median(g_samples.rows),
              median(g_samples.iterations));
  std::printf(
      "interior-point iteration: median %.2f us, 90th percentile %.2f us\n", iteration,
      g_samples.iteration_us.empty() ? 0.0 : lc::run::nearest_rank(g_samples.iteration_us, 0.9));
  std::printf("stage-wise Riccati limit (dense factorization and solve, no rows): median %.2f us\n",
              riccati);
  if (riccati > 0.0) {
    std::printf("ratio iteration / Riccati limit (medians, this run): %.2f\n", iteration / riccati);
  }
}

}  // namespace

BENCHMARK(BM_NodeQpIteration)->Unit(benchmark::kMillisecond)->Iterations(200);
BENCHMARK(BM_RiccatiLimit)->Unit(benchmark::kMillisecond)->Iterations(200);

int main(int argc, char** argv) { return run_then_summarize(argc, argv, print_summary); }
