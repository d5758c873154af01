#include <vector>

#include "lanechange/learn/evaluation.hpp"

namespace lanechange::learn {

namespace {

double ratio(double a, double b) { return b > 0.0 ? a / b : 0.0; }

nlohmann::json matrix_json(const Eigen::MatrixXd& m) {
  nlohmann::json out = nlohmann::json::array();
  for (Eigen::Index r = 0; r < m.rows(); ++r) {
    std::vector<double> row(static_cast<std::size_t>(m.cols()));
    for (Eigen::Index c = 0; c < m.cols(); ++c) row[static_cast<std::size_t>(c)] = m(r, c);
    out.push_back(row);
  }
  return out;
}

}  // namespace

ClassScores score(const std::vector<int>& truth, const std::vector<int>& predicted, int classes) {
  ClassScores s;
  s.confusion = Eigen::MatrixXd::Zero(classes, classes);
  for (std::size_t i = 0; i < truth.size(); ++i) s.confusion(truth[i], predicted[i]) += 1.0;
  s.accuracy = ratio(s.confusion.trace(), s.confusion.sum());
  s.precision = s.recall = s.f1 = Eigen::VectorXd::Zero(classes);
  for (int c = 0; c < classes; ++c) {
    s.precision(c) = ratio(s.confusion(c, c), s.confusion.col(c).sum());
    s.recall(c) = ratio(s.confusion(c, c), s.confusion.row(c).sum());
    s.f1(c) = ratio(2.0 * s.precision(c) * s.recall(c), s.precision(c) + s.recall(c));
  }
  s.macro_f1 = s.f1.mean();
  return s;
}

Eigen::MatrixXd ClassScores::row_normalised() const {
  Eigen::MatrixXd out = confusion;
  for (Eigen::Index r = 0; r < out.rows(); ++r) {
    const double sum = out.row(r).sum();
    if (sum > 0.0) out.row(r) /= sum;
  }
  return out;
}

nlohmann::json ClassScores::to_json() const {
  return {{"test_accuracy", accuracy},
          {"precision", std::vector<double>(precision.begin(), precision.end())},
          {"recall", std::vector<double>(recall.begin(), recall.end())},
          {"f1", std::vector<double>(f1.begin(), f1.end())},
          {"macro_f1", macro_f1},
          {"confusion_counts", matrix_json(confusion)},
          {"confusion_row_normalised", matrix_json(row_normalised())}};
}

}  // namespace lanechange::learn
