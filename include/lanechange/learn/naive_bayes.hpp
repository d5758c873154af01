#pragma once
// Naive Bayes with a Gaussian kernel density per feature and class (the
// paper's "NB with Gaussian kernel", MATLAB's fitcnb 'kernel'): no library
// we use has it. The plain variant fits one normal per feature and class.
#include <Eigen/Dense>
#include <nlohmann/json.hpp>
#include <vector>

namespace lanechange::learn {

/// A one-dimensional Gaussian kernel density estimate.
class KernelDensity {
 public:
  KernelDensity() = default;
  KernelDensity(std::vector<double> samples, double bandwidth);
  /// log f(x) with f(x) = 1/(n h) sum_i phi((x - x_i) / h). Kernels farther
  /// than 8 h add under 1e-14 of the nearest one's weight and are skipped
  /// (the samples are sorted); with none that near, the nearest alone counts.
  [[nodiscard]] double log_density(double x) const;
  [[nodiscard]] double bandwidth() const { return h_; }
  [[nodiscard]] const std::vector<double>& samples() const { return samples_; }

 private:
  std::vector<double> samples_;  ///< sorted
  double h_ = 1.0;
};

/// Silverman's rule of thumb: 0.9 min(sd, IQR / 1.34) n^(-1/5); a positive
/// floor keeps a constant feature usable.
[[nodiscard]] double silverman_bandwidth(std::vector<double> samples);

struct NaiveBayesSettings {
  bool kernel = true;
  double bandwidth_scale = 1.0;  ///< times Silverman's bandwidth; chosen by CV
};

class NaiveBayes {
 public:
  explicit NaiveBayes(NaiveBayesSettings settings = {}) : settings_(settings) {}
  void fit(const Eigen::MatrixXd& x, const std::vector<int>& y, int classes);
  /// log p(class) + sum_f log p(x_f | class), for every class.
  [[nodiscard]] Eigen::VectorXd log_posterior(const Eigen::RowVectorXd& x) const;
  [[nodiscard]] int predict(const Eigen::RowVectorXd& x) const;
  [[nodiscard]] nlohmann::json to_json() const;
  static NaiveBayes from_json(const nlohmann::json& j);

 private:
  NaiveBayesSettings settings_;
  Eigen::VectorXd log_prior_;
  std::vector<std::vector<KernelDensity>> density_;  ///< [class][feature] (kernel)
  Eigen::MatrixXd mean_, sd_;                        ///< classes x features (plain)
};

}  // namespace lanechange::learn
