#pragma once
// The action network at run time: the exported weights of the tanh network
// (10 hidden layers; 10 wide as the paper's, or wider), evaluated with Eigen
// (no training library, no heap after construction). Raw observation in,
// physical [a, omega] out.
#include <Eigen/Dense>
#include <array>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace lanechange::learn {

inline constexpr int kHiddenLayers = 10;
/// The paper's width, the default.
inline constexpr int kHiddenWidth = 10;
/// The widest hidden layer a policy may have (its activations live on the stack).
inline constexpr int kMaxHiddenWidth = 64;
inline constexpr int kActions = 2;
/// The most inputs a policy takes (the data set lists 28 today).
inline constexpr int kMaxPolicyInputs = 40;

/// Everything the policy needs, as exported from the trained network.
struct PolicyWeights {
  std::vector<std::string> inputs;   ///< column names, in order
  std::vector<std::string> outputs;  ///< a, omega
  Eigen::VectorXd input_mean, input_scale, output_mean, output_scale;
  /// layers[l] maps layer l's input to its output: kHiddenLayers tanh
  /// layers, then a linear one with kActions outputs.
  std::vector<Eigen::MatrixXf> weights;
  std::vector<Eigen::VectorXf> biases;
  [[nodiscard]] nlohmann::json to_json() const;
  /// InputError if the layer shapes are not those of a 10-layer network
  /// (Policy's constructor checks them).
  static PolicyWeights from_json(const nlohmann::json& j);
};

using Observation = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxPolicyInputs, 1>;

class Policy {
 public:
  explicit Policy(const PolicyWeights& weights);
  /// [a, omega] in SI units for one raw observation (the `inputs` columns).
  [[nodiscard]] Eigen::Vector2d act(const Observation& observation) const;
  [[nodiscard]] int inputs() const { return static_cast<int>(in_mean_.size()); }
  /// Neurons per hidden layer.
  [[nodiscard]] int width() const { return static_cast<int>(weights_.back().cols()); }

 private:
  using Hidden = Eigen::Matrix<float, Eigen::Dynamic, 1, 0, kMaxHiddenWidth, 1>;
  /// Input layer, the kHiddenLayers - 1 hidden-to-hidden layers, output layer.
  std::array<Eigen::MatrixXf, kHiddenLayers + 1> weights_;
  std::array<Eigen::VectorXf, kHiddenLayers + 1> biases_;
  Observation in_mean_, in_inverse_scale_;
  Eigen::Vector2d out_mean_, out_scale_;
};

}  // namespace lanechange::learn
