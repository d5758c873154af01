#pragma once
// Training the action network (10 hidden layers of tanh, 10 wide as the
// paper's unless `hidden_width` says otherwise; Adam, MSE) with dlib. Inputs and outputs are
// normalised by the caller's statistics; training stops early when the validation loss has not
// improved for `patience` epochs, and the best epoch's weights are kept. dlib stays behind this
// header: the run-time policy (policy.hpp) does not need it.
#include <Eigen/Dense>
#include <cstdint>
#include <memory>
#include <ostream>
#include <string>
#include <string_view>
#include <vector>

#include "lanechange/learn/policy.hpp"

namespace lanechange::learn {

/// What the action network reads (docs/learning.md): the paper's scene and
/// three cars by role (the data sets' `action_inputs`), or the ego and the
/// gap it drives to (`gap_action_inputs`: any number of cars, format 4).
enum class NetworkInputs { Paper, Gap };
[[nodiscard]] std::string_view to_string(NetworkInputs inputs);
/// The data sets' manifest key of the input column names.
[[nodiscard]] const char* manifest_key(NetworkInputs inputs);

/// An ensemble's size bound: a policy's act() runs every member.
inline constexpr int kMaxNetworks = 16;

struct NetworkSettings {
  int hidden_width = kHiddenWidth;  ///< neurons per hidden layer, 1..kMaxHiddenWidth
  int max_epochs = 300;
  int patience = 20;  ///< epochs without a better validation loss before stopping
  int batch_size = 256;
  double learning_rate = 1e-3;
  double validation_share = 0.1;  ///< of the training scenarios
  std::uint64_t seed = 1;
  /// An ensemble (Lakshminarayanan et al. 2017): this many networks, each from its own
  /// initial weights and batch order (member_seed), trained on the same rows; the policy
  /// acts as their mean. 1: the paper's single network.
  int networks = 1;
  NetworkInputs inputs = NetworkInputs::Paper;
};

/// The seed of an ensemble's k-th network; member 0 keeps `seed`, so that a one-network
/// model is what it was before ensembles.
[[nodiscard]] std::uint64_t member_seed(std::uint64_t seed, int member);

struct LossPoint {
  int epoch = 0;
  double train_mse = 0.0;       ///< normalised units, over the training rows
  double validation_mse = 0.0;  ///< normalised units
};

class TrainedNetwork {
 public:
  TrainedNetwork();
  ~TrainedNetwork();
  TrainedNetwork(TrainedNetwork&&) noexcept;
  TrainedNetwork& operator=(TrainedNetwork&&) noexcept;
  /// dlib's own output for normalised inputs (rows), normalised outputs.
  [[nodiscard]] Eigen::MatrixXd forward(const Eigen::MatrixXd& normalised_inputs) const;
  /// The layers' weights, for PolicyWeights.
  void export_layers(std::vector<Eigen::MatrixXf>& weights,
                     std::vector<Eigen::VectorXf>& biases) const;
  /// dlib's serialisation (to resume or inspect training).
  void save(const std::string& path) const;

  std::vector<LossPoint> curve;
  int best_epoch = 0;
  double train_s = 0.0;
  [[nodiscard]] double seconds_per_epoch() const;

  struct Impl;
  std::unique_ptr<Impl> impl;
};

/// Trains on normalised rows; `train` and `validation` index them.
[[nodiscard]] TrainedNetwork train_network(const Eigen::MatrixXd& x, const Eigen::MatrixXd& y,
                                           const std::vector<int>& train,
                                           const std::vector<int>& validation,
                                           const NetworkSettings& settings,
                                           std::ostream* progress = nullptr,
                                           const std::string& warm_start = "");

}  // namespace lanechange::learn
