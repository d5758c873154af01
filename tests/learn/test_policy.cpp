#include <gtest/gtest.h>

#include <algorithm>
#include <random>

#include "lanechange/error.hpp"
#include "lanechange/learn/network.hpp"
#include "lanechange/learn/policy.hpp"

namespace lanechange::learn {
namespace {

struct Toy {
  Eigen::MatrixXd x, y;
  std::vector<int> train, validation;
};

Toy toy(int inputs, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  Toy t;
  t.x.resize(600, inputs);
  t.y.resize(600, kActions);
  for (int r = 0; r < 600; ++r) {
    for (int c = 0; c < inputs; ++c) t.x(r, c) = normal(rng);
    t.y(r, 0) = std::sin(t.x(r, 0)) + 0.5 * t.x(r, 1);
    t.y(r, 1) = t.x(r, 2) * t.x(r, 0) * 0.3;
    (r % 5 == 0 ? t.validation : t.train).push_back(r);
  }
  return t;
}

NetworkSettings few_epochs() {
  NetworkSettings s;
  s.max_epochs = 8;
  s.batch_size = 32;
  s.seed = 3;
  return s;
}

// The paper's width and a wider one: the run-time policy sizes itself from
// the exported layers.
class ExportedPolicy : public ::testing::TestWithParam<int> {};

TEST_P(ExportedPolicy, MatchesDlibTo1e5OnRandomInputs) {
  const int inputs = 28;
  const Toy t = toy(inputs, 1);
  NetworkSettings settings = few_epochs();
  settings.hidden_width = GetParam();
  const TrainedNetwork net = train_network(t.x, t.y, t.train, t.validation, settings);
  ASSERT_FALSE(net.curve.empty());
  // Normalisation that is not the identity, to test it is applied.
  PolicyWeights w;
  for (int i = 0; i < inputs; ++i) w.inputs.push_back(std::to_string(i));
  w.outputs = {"a", "omega"};
  w.input_mean = Eigen::VectorXd::LinSpaced(inputs, -2.0, 3.0);
  w.input_scale = Eigen::VectorXd::LinSpaced(inputs, 0.5, 4.0);
  w.output_mean = Eigen::Vector2d(0.3, -0.1);
  w.output_scale = Eigen::Vector2d(2.0, 0.25);
  net.export_layers(w.weights, w.biases);
  const Policy policy(PolicyWeights::from_json(nlohmann::json::parse(w.to_json().dump())));
  EXPECT_EQ(policy.width(), GetParam());

  std::mt19937_64 rng(9);
  std::uniform_real_distribution<double> u(-10.0, 10.0);
  Eigen::MatrixXd raw(200, inputs);
  for (Eigen::Index i = 0; i < raw.size(); ++i) raw.data()[i] = u(rng);
  const Eigen::MatrixXd z = (raw.rowwise() - w.input_mean.transpose()).array().rowwise() /
                            w.input_scale.transpose().array();
  const Eigen::MatrixXd dlib_out = net.forward(z);
  for (Eigen::Index r = 0; r < raw.rows(); ++r) {
    const Eigen::Vector2d want =
        w.output_mean + dlib_out.row(r).transpose().cwiseProduct(w.output_scale);
    const Eigen::Vector2d got = policy.act(raw.row(r).transpose());
    EXPECT_NEAR(got(0), want(0), 1e-5);
    EXPECT_NEAR(got(1), want(1), 1e-5);
  }
}

INSTANTIATE_TEST_SUITE_P(Widths, ExportedPolicy, ::testing::Values(kHiddenWidth, 24));

TEST(ActionNetwork, AWarmStartOfAnotherWidthOrAnImpossibleWidthIsRefused) {
  const Toy t = toy(6, 6);
  NetworkSettings s = few_epochs();
  s.max_epochs = 1;
  s.hidden_width = 12;
  const std::string file = ::testing::TempDir() + "/width12.dlib";
  train_network(t.x, t.y, t.train, t.validation, s).save(file);
  EXPECT_NO_THROW((void)train_network(t.x, t.y, t.train, t.validation, s, nullptr, file));
  s.hidden_width = kHiddenWidth;
  EXPECT_THROW((void)train_network(t.x, t.y, t.train, t.validation, s, nullptr, file), InputError);
  for (const int width : {0, kMaxHiddenWidth + 1}) {
    s.hidden_width = width;
    EXPECT_THROW((void)train_network(t.x, t.y, t.train, t.validation, s), InputError) << width;
  }
}

TEST(ActionNetwork, TrainingIsRepeatableAndLowersTheLoss) {
  const Toy t = toy(6, 2);
  const TrainedNetwork a = train_network(t.x, t.y, t.train, t.validation, few_epochs());
  const TrainedNetwork b = train_network(t.x, t.y, t.train, t.validation, few_epochs());
  ASSERT_EQ(a.curve.size(), b.curve.size());
  EXPECT_EQ(a.curve.back().validation_mse, b.curve.back().validation_mse);
  EXPECT_LT(a.curve[static_cast<std::size_t>(a.best_epoch - 1)].validation_mse,
            a.curve.front().validation_mse);
}

TEST(ActionNetwork, EarlyStoppingEndsAfterPatienceEpochsWithoutProgress) {
  const Toy t = toy(6, 4);
  NetworkSettings s = few_epochs();
  s.max_epochs = 400;
  s.patience = 2;
  s.learning_rate = 1e-30;  // updates vanish in float: no progress, so it stops
  const TrainedNetwork net = train_network(t.x, t.y, t.train, t.validation, s);
  EXPECT_LE(static_cast<int>(net.curve.size()), net.best_epoch + s.patience);
  EXPECT_LT(static_cast<int>(net.curve.size()), s.max_epochs);
}

TEST(Policy, RefusesWeightsOfAnotherShapeAndObservationsOfAnotherSize) {
  const Toy t = toy(4, 5);
  NetworkSettings s = few_epochs();
  s.max_epochs = 1;
  const TrainedNetwork net = train_network(t.x, t.y, t.train, t.validation, s);
  PolicyWeights w{{"a0", "a1", "a2", "a3"},
                  {"a", "omega"},
                  Eigen::VectorXd::Zero(4),
                  Eigen::VectorXd::Ones(4),
                  Eigen::Vector2d::Zero(),
                  Eigen::Vector2d::Ones(),
                  {},
                  {}};
  net.export_layers(w.weights, w.biases);
  const Policy policy(w);
  EXPECT_THROW((void)policy.act(Eigen::VectorXd::Zero(5)), InputError);
  PolicyWeights too_wide = w;
  too_wide.weights[0] = Eigen::MatrixXf::Zero(kMaxHiddenWidth + 1, 4);
  EXPECT_THROW(Policy{too_wide}, InputError);
  PolicyWeights uneven = w;
  uneven.weights[3] = Eigen::MatrixXf::Zero(kHiddenWidth + 1, kHiddenWidth);
  EXPECT_THROW(Policy{uneven}, InputError);
  w.weights.pop_back();
  EXPECT_THROW(Policy{w}, InputError);
}

PolicyWeights trained_weights(const Toy& t, std::uint64_t seed, double output_mean) {
  NetworkSettings s = few_epochs();
  s.max_epochs = 2;
  s.seed = seed;
  const TrainedNetwork net = train_network(t.x, t.y, t.train, t.validation, s);
  const auto n = static_cast<Eigen::Index>(t.x.cols());
  PolicyWeights w;
  for (Eigen::Index i = 0; i < n; ++i) w.inputs.push_back(std::to_string(i));
  w.outputs = {"a", "omega"};
  w.input_mean = Eigen::VectorXd::Constant(n, 0.1 * static_cast<double>(seed));
  w.input_scale = Eigen::VectorXd::Constant(n, 1.0 + static_cast<double>(seed));
  w.output_mean = Eigen::Vector2d(output_mean, -output_mean);
  w.output_scale = Eigen::Vector2d(2.0, 0.5);
  net.export_layers(w.weights, w.biases);
  return w;
}

// An averaged policy acts as the mean of its networks, each under its own
// standardizers, and keeps that through its file.
TEST(Policy, AnAverageActsAsTheMeanOfItsNetworksAndReadsBackAsWritten) {
  const Toy t = toy(5, 7);
  const std::vector<PolicyWeights> members = {
      trained_weights(t, 1, 0.0), trained_weights(t, 2, 1.0), trained_weights(t, 3, -0.5)};
  const nlohmann::json file = nlohmann::json::parse(policy_members_to_json(members).dump());
  ASSERT_TRUE(file.contains("average_of"));
  const Policy average(policy_members_from_json(file));
  EXPECT_EQ(average.members(), 3);
  EXPECT_EQ(average.inputs(), 5);
  // One network is written as before, so older readers read it.
  EXPECT_FALSE(policy_members_to_json({members[0]}).contains("average_of"));
  EXPECT_EQ(Policy(policy_members_from_json(members[0].to_json())).members(), 1);
  double spread = 0.0;
  for (int r = 0; r < 40; ++r) {
    const Observation x = t.x.row(r).transpose();
    Eigen::Vector2d mean = Eigen::Vector2d::Zero();
    for (const PolicyWeights& m : members) mean += Policy(m).act(x) / 3.0;
    const Eigen::Vector2d got = average.act(x);
    EXPECT_NEAR(got(0), mean(0), 1e-9);
    EXPECT_NEAR(got(1), mean(1), 1e-9);
    spread = std::max(spread, (Policy(members[1]).act(x) - got).cwiseAbs().maxCoeff());
  }
  EXPECT_GT(spread, 1e-3);  // the members differ, so the mean is not any one of them
}

TEST(Policy, AnAverageOfNoNetworkOrOfNetworksWithOtherInputsIsRefused) {
  const Toy t = toy(5, 8);
  EXPECT_THROW(Policy{std::vector<PolicyWeights>{}}, InputError);
  PolicyWeights renamed = trained_weights(t, 2, 0.0);
  renamed.inputs[4] = "another";
  EXPECT_THROW((Policy{std::vector<PolicyWeights>{trained_weights(t, 1, 0.0), renamed}}),
               InputError);
}

}  // namespace
}  // namespace lanechange::learn
