#include <gtest/gtest.h>

#include <random>

#include "../foundation/test_helpers.hpp"
#include "lanechange/error.hpp"
#include "lanechange/learn/classifier.hpp"
#include "lanechange/learn/evaluation.hpp"
#include "lanechange/learn/learn_data.hpp"

namespace lanechange::learn {
namespace {

// Three classes by the sign pattern of two of five features, with noise.
Eigen::MatrixXd three_classes(std::vector<int>& y, int n, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  Eigen::MatrixXd x(n, 5);
  y.resize(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) {
    const int c = i % 3;
    y[static_cast<std::size_t>(i)] = c;
    for (int f = 0; f < 5; ++f) x(i, f) = normal(rng);
    x(i, 0) += c == 0 ? 3.0 : -1.5;
    x(i, 1) += c == 1 ? 3.0 : (c == 2 ? -3.0 : 0.0);
  }
  return x;
}

class EveryClassifier : public ::testing::TestWithParam<ClassifierKind> {};

TEST_P(EveryClassifier, LearnsSeparableClassesAndReloadsToTheSamePredictions) {
  std::vector<int> y, y_test;
  const Eigen::MatrixXd x = three_classes(y, 450, 1), x_test = three_classes(y_test, 300, 2);
  const auto grid = hyperparameter_grid(GetParam(), {});
  ASSERT_FALSE(grid.empty());
  auto model = make_classifier(GetParam(), grid.front());
  model->fit(x, y);
  const std::vector<int> predicted = model->predict(x_test);
  EXPECT_GT(score(y_test, predicted, kClasses).accuracy, 0.9);

  testing::TempDir dir;
  const std::string path = dir.file("model." + classifier_file(GetParam()));
  model->save(path);
  auto back = make_classifier(GetParam(), grid.front());
  back->load(path);
  EXPECT_EQ(back->predict(x_test), predicted);
}

TEST_P(EveryClassifier, RefusesAFileThatIsNotItsModel) {
  testing::TempDir dir;
  const std::string path = dir.file("junk." + classifier_file(GetParam()));
  testing::write_text(path, "not a model\n");
  auto model = make_classifier(GetParam(), nlohmann::json::object());
  EXPECT_THROW(model->load(path), std::exception);
}

INSTANTIATE_TEST_SUITE_P(TableI, EveryClassifier, ::testing::ValuesIn(kClassifierKinds),
                         [](const auto& info) { return std::string(classifier_name(info.param)); });

TEST(Selection, ChoosesByCrossValidationOnAllFolds) {
  std::vector<int> y;
  const Eigen::MatrixXd x = three_classes(y, 300, 3);
  SearchSettings s;
  s.quick = true;
  const Selection sel = select_hyperparameters(ClassifierKind::DecisionTree, x, y, s, 7, 2);
  ASSERT_EQ(sel.candidates.size(), hyperparameter_grid(ClassifierKind::DecisionTree, s).size());
  for (const auto& c : sel.candidates) {
    ASSERT_EQ(c.fold_accuracy.size(), 5u);
    EXPECT_LE(c.mean(), sel.chosen().mean());
  }
  EXPECT_GT(sel.chosen().mean(), 0.8);
  // The same seed gives the same folds and scores.
  const Selection again = select_hyperparameters(ClassifierKind::DecisionTree, x, y, s, 7, 1);
  EXPECT_EQ(again.chosen().fold_accuracy, sel.chosen().fold_accuracy);
}

TEST(Scores, MatchAHandCountedConfusionMatrix) {
  const std::vector<int> truth = {0, 0, 0, 1, 1, 2};
  const std::vector<int> predicted = {0, 0, 1, 1, 2, 2};
  const ClassScores s = score(truth, predicted, 3);
  EXPECT_DOUBLE_EQ(s.accuracy, 4.0 / 6.0);
  EXPECT_DOUBLE_EQ(s.precision(1), 0.5);
  EXPECT_DOUBLE_EQ(s.recall(0), 2.0 / 3.0);
  EXPECT_DOUBLE_EQ(s.row_normalised()(1, 2), 0.5);
  EXPECT_DOUBLE_EQ(s.macro_f1, (0.8 + 0.5 + 2.0 / 3.0) / 3.0);
}

TEST(Split, IsSeededDisjointAndOfTheAskedShare) {
  const Split a = split_scenarios(1000, 0.2, 11), b = split_scenarios(1000, 0.2, 11);
  EXPECT_EQ(a.test, b.test);
  EXPECT_EQ(a.test.size(), 200u);
  EXPECT_EQ(a.train.size(), 800u);
  std::vector<char> seen = mask_of(a.test, 1000);
  for (int r : a.train) EXPECT_FALSE(seen[static_cast<std::size_t>(r)]);
  EXPECT_NE(split_scenarios(1000, 0.2, 12).test, a.test);
  EXPECT_THROW((void)split_scenarios(10, 1.0, 1), InputError);
}

TEST(Standardizer, GivesZeroMeanUnitSpreadAndKeepsConstantColumns) {
  Eigen::MatrixXd x(4, 2);
  x << 1, 5, 2, 5, 3, 5, 4, 5;
  const Standardizer s = Standardizer::fit(x);
  const Eigen::MatrixXd z = s.apply(x);
  EXPECT_NEAR(z.col(0).mean(), 0.0, 1e-12);
  EXPECT_NEAR((z.col(0).array().square().sum()) / 3.0, 1.0, 1e-12);
  EXPECT_DOUBLE_EQ(s.scale(1), 1.0);
}

}  // namespace
}  // namespace lanechange::learn
