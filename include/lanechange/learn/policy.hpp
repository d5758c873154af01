#pragma once
// The action network at run time: the exported weights of the 10x10 tanh
// network, evaluated with fixed-size Eigen (no training library, no heap
// after construction). Raw observation in, physical [a, omega] out.
#include <Eigen/Dense>
#include <array>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace lanechange::learn {

inline constexpr int kHiddenLayers = 10;
inline constexpr int kHiddenWidth = 10;
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
  /// InputError if the layer shapes are not those of the 10x10 network.
  static PolicyWeights from_json(const nlohmann::json& j);
};

using Observation = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxPolicyInputs, 1>;

class Policy {
 public:
  explicit Policy(const PolicyWeights& weights);
  /// [a, omega] in SI units for one raw observation (the `inputs` columns).
  [[nodiscard]] Eigen::Vector2d act(const Observation& observation) const;
  [[nodiscard]] int inputs() const { return static_cast<int>(in_mean_.size()); }

 private:
  using Hidden = Eigen::Matrix<float, kHiddenWidth, 1>;
  Eigen::Matrix<float, kHiddenWidth, Eigen::Dynamic, 0, kHiddenWidth, kMaxPolicyInputs> first_;
  std::array<Eigen::Matrix<float, kHiddenWidth, kHiddenWidth>, kHiddenLayers - 1> hidden_;
  std::array<Hidden, kHiddenLayers> bias_;
  Eigen::Matrix<float, kActions, kHiddenWidth> last_;
  Eigen::Matrix<float, kActions, 1> last_bias_;
  Observation in_mean_, in_inverse_scale_;
  Eigen::Vector2d out_mean_, out_scale_;
};

}  // namespace lanechange::learn
