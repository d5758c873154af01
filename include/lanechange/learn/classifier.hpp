#pragma once
// The five classifiers of the paper's Table I behind one interface. Each
// takes standardised inputs (rows = scenes) and labels 0..kClasses-1. The
// models come from OpenCV's ml module (decision tree, k-NN, random forest),
// libsvm (SVM) and our own kernel naive Bayes, which no library offers.
#include <Eigen/Dense>
#include <array>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>
#include <vector>

namespace lanechange::learn {

enum class ClassifierKind { DecisionTree, NaiveBayes, Svm, Knn, Ensemble };
inline constexpr std::array<ClassifierKind, 5> kClassifierKinds = {
    ClassifierKind::DecisionTree, ClassifierKind::NaiveBayes, ClassifierKind::Svm,
    ClassifierKind::Knn, ClassifierKind::Ensemble};

/// decision_tree, naive_bayes, svm, knn, ensemble (the metrics.json keys).
[[nodiscard]] std::string_view classifier_name(ClassifierKind kind);
/// The model file's name inside a model directory.
[[nodiscard]] std::string classifier_file(ClassifierKind kind);

/// Zero mean, unit spread per column, fitted on the training rows only. A
/// constant column (a one-hot that never fires) keeps scale 1.
struct Standardizer {
  Eigen::VectorXd mean;
  Eigen::VectorXd scale;
  static Standardizer fit(const Eigen::MatrixXd& x);
  [[nodiscard]] Eigen::MatrixXd apply(const Eigen::MatrixXd& x) const;
  [[nodiscard]] nlohmann::json to_json() const;
  static Standardizer from_json(const nlohmann::json& j);
};

class Classifier {
 public:
  virtual ~Classifier() = default;
  virtual void fit(const Eigen::MatrixXd& x, const std::vector<int>& y) = 0;
  [[nodiscard]] virtual std::vector<int> predict(const Eigen::MatrixXd& x) const = 0;
  /// Writes the fitted model to path (a file in the model directory).
  virtual void save(const std::string& path) const = 0;
  virtual void load(const std::string& path) = 0;
};

/// A classifier of the kind with the given hyperparameters (as chosen by
/// hyperparameter_grid; an empty object gives the defaults).
[[nodiscard]] std::unique_ptr<Classifier> make_classifier(ClassifierKind kind,
                                                          const nlohmann::json& hyper);

/// How the hyperparameters are searched.
struct SearchSettings {
  int folds = 5;
  int knn_k = 10;                  ///< fixed by the paper
  int ensemble_trees = 30;         ///< fixed by the paper
  bool naive_bayes_kernel = true;  ///< false: one normal per feature and class
  /// Smaller grids (tests): fewer candidates per classifier.
  bool quick = false;
};

/// The candidates 5-fold cross-validation chooses among.
[[nodiscard]] std::vector<nlohmann::json> hyperparameter_grid(ClassifierKind kind,
                                                              const SearchSettings& settings);

}  // namespace lanechange::learn
