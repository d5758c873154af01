#pragma once
// Scoring a classifier, and choosing its hyperparameters by k-fold
// cross-validation on the training part only.
#include <Eigen/Dense>
#include <cstdint>
#include <functional>
#include <nlohmann/json.hpp>
#include <vector>

#include "lanechange/learn/classifier.hpp"

namespace lanechange::learn {

struct ClassScores {
  double accuracy = 0.0;
  Eigen::MatrixXd confusion;              ///< counts, rows = true class, columns = predicted
  Eigen::VectorXd precision, recall, f1;  ///< per class (0 where undefined)
  double macro_f1 = 0.0;
  /// Each row divided by its sum (the paper's Fig. 3); rows without scenes are 0.
  [[nodiscard]] Eigen::MatrixXd row_normalised() const;
  [[nodiscard]] nlohmann::json to_json() const;
};

[[nodiscard]] ClassScores score(const std::vector<int>& truth, const std::vector<int>& predicted,
                                int classes);

/// Rows 0..n-1 dealt into k folds after a seeded shuffle.
[[nodiscard]] std::vector<std::vector<int>> make_folds(int n, int k, std::uint64_t seed);

struct CandidateScore {
  nlohmann::json hyper;
  std::vector<double> fold_accuracy;
  [[nodiscard]] double mean() const;
  [[nodiscard]] double sd() const;  ///< sample standard deviation over folds
};

struct Selection {
  std::vector<CandidateScore> candidates;
  std::size_t best = 0;  ///< highest mean accuracy; the first on ties
  [[nodiscard]] const CandidateScore& chosen() const { return candidates[best]; }
};

/// Scores every candidate of the grid on the same folds, on `jobs` threads.
[[nodiscard]] Selection select_hyperparameters(ClassifierKind kind, const Eigen::MatrixXd& x,
                                               const std::vector<int>& y,
                                               const SearchSettings& settings, std::uint64_t seed,
                                               int jobs);

/// Runs task(i) for i in [0, n) on up to `jobs` threads (0: one per core).
void parallel_for(int n, int jobs, const std::function<void(int)>& task);

}  // namespace lanechange::learn
