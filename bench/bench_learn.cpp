// Learning-stage timings (docs/performance.md): one policy evaluation (raw
// observation in, physical [a, omega] out), one classifier decision per
// Table I model, and one training epoch of the action network. Synthetic
// weights and data: the costs depend on the shapes, not on the values.
#include <benchmark/benchmark.h>

#include <random>
#include <vector>

#include "lanechange/learn/classifier.hpp"
#include "lanechange/learn/learn_data.hpp"
#include "lanechange/learn/network.hpp"
#include "lanechange/learn/policy.hpp"

namespace lc = lanechange::learn;

namespace {

constexpr int kInputs = 28;  // the data set's action_inputs
constexpr int kFeatures = 13;

Eigen::MatrixXd random_matrix(Eigen::Index rows, Eigen::Index cols, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  Eigen::MatrixXd m(rows, cols);
  for (Eigen::Index i = 0; i < m.size(); ++i) m.data()[i] = normal(rng);
  return m;
}

lc::PolicyWeights random_policy(int width) {
  lc::PolicyWeights w;
  for (int i = 0; i < kInputs; ++i) w.inputs.push_back(std::to_string(i));
  w.outputs = {"a", "omega"};
  w.input_mean = Eigen::VectorXd::Zero(kInputs);
  w.input_scale = Eigen::VectorXd::Ones(kInputs);
  w.output_mean = Eigen::Vector2d::Zero();
  w.output_scale = Eigen::Vector2d::Ones();
  for (int l = 0; l <= lc::kHiddenLayers; ++l) {
    const int rows = l == lc::kHiddenLayers ? lc::kActions : width;
    const int cols = l == 0 ? kInputs : width;
    w.weights.push_back((0.3 * random_matrix(rows, cols, 10 + l)).cast<float>());
    w.biases.push_back((0.1 * random_matrix(rows, 1, 40 + l)).cast<float>());
  }
  return w;
}

// One act per iteration, on an observation that changes a little each time.
void time_act(benchmark::State& state, const lc::Policy& policy) {
  lc::Observation obs = random_matrix(kInputs, 1, 3);
  for (auto _ : state) {
    benchmark::DoNotOptimize(obs.data());
    const Eigen::Vector2d a = policy.act(obs);
    benchmark::DoNotOptimize(a.data());
    obs(0) += 1e-9;
  }
}

// The argument is the hidden layers' width: the paper's 10 first (the
// performance report reads that line), then wider ones (train --network-width).
void BM_PolicyAct(benchmark::State& state) {
  const lc::Policy policy(random_policy(static_cast<int>(state.range(0))));
  time_act(state, policy);
}
BENCHMARK(BM_PolicyAct)
    ->Arg(lc::kHiddenWidth)
    ->Arg(32)
    ->Arg(lc::kMaxHiddenWidth)
    ->Repetitions(5)
    ->ReportAggregatesOnly(true);

// A policy averaging the networks of DAgger's rounds 0..r (--dagger-average):
// the argument is how many 10-wide networks it holds (15: the experiments'
// round 4, five rounds' ensembles of 3).
void BM_PolicyActAverage(benchmark::State& state) {
  std::vector<lc::PolicyWeights> members;
  for (int m = 0; m < state.range(0); ++m) {
    lc::PolicyWeights w = random_policy(lc::kHiddenWidth);
    w.output_mean(0) = 0.1 * m;  // members that differ
    members.push_back(w);
  }
  const lc::Policy policy(members);
  time_act(state, policy);
}
BENCHMARK(BM_PolicyActAverage)
    ->Arg(1)
    ->Arg(3)
    ->Arg(5)
    ->Arg(15)
    ->Repetitions(5)
    ->ReportAggregatesOnly(true);

void BM_ClassifierDecision(benchmark::State& state) {
  const auto kind = lc::kClassifierKinds[static_cast<std::size_t>(state.range(0))];
  const Eigen::MatrixXd x = random_matrix(4000, kFeatures, 5);
  std::vector<int> y;
  for (Eigen::Index r = 0; r < x.rows(); ++r) {
    y.push_back(x(r, 0) + 0.5 * x(r, 3) > 0.5 ? 0 : (x(r, 1) > 0 ? 1 : 2));
  }
  auto model = lc::make_classifier(kind, lc::hyperparameter_grid(kind, {}).front());
  model->fit(x, y);
  const Eigen::MatrixXd scene = random_matrix(1, kFeatures, 6);
  for (auto _ : state) benchmark::DoNotOptimize(model->predict(scene));
  state.SetLabel(std::string(lc::classifier_name(kind)));
}
BENCHMARK(BM_ClassifierDecision)
    ->DenseRange(0, 4)
    ->Unit(benchmark::kMicrosecond)
    ->Repetitions(3)
    ->ReportAggregatesOnly(true);

// One epoch over 100k rows (about 625 well-posed plans of N = 160) at batch 256.
void BM_NetworkEpoch(benchmark::State& state) {
  const Eigen::MatrixXd x = random_matrix(100'000, kInputs, 7);
  const Eigen::MatrixXd y = random_matrix(100'000, lc::kActions, 8);
  std::vector<int> train, validation;
  for (int r = 0; r < x.rows(); ++r) (r % 10 == 0 ? validation : train).push_back(r);
  lc::NetworkSettings s;
  s.max_epochs = 1;
  for (auto _ : state) {
    const lc::TrainedNetwork net = lc::train_network(x, y, train, validation, s);
    benchmark::DoNotOptimize(net.best_epoch);
  }
}
BENCHMARK(BM_NetworkEpoch)
    ->Unit(benchmark::kMillisecond)
    ->Iterations(1)
    ->Repetitions(3)
    ->ReportAggregatesOnly(true);

}  // namespace

BENCHMARK_MAIN();
