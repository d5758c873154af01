#pragma once
// The action network at run time: the exported weights of the tanh network
// (10 hidden layers; 10 wide as the paper's, or wider), evaluated with Eigen
// (no training library, no heap after construction). Raw observation in,
// physical [a, omega] out. A policy may also be the mean action of several
// such networks (DAgger's rounds averaged, docs/strategy.md).
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

/// policy.json holds one network (PolicyWeights::to_json) or the networks
/// whose actions a policy averages: {"average_of": [network, ...]}.
[[nodiscard]] std::vector<PolicyWeights> policy_members_from_json(const nlohmann::json& j);
[[nodiscard]] nlohmann::json policy_members_to_json(const std::vector<PolicyWeights>& members);

using Observation = Eigen::Matrix<double, Eigen::Dynamic, 1, 0, kMaxPolicyInputs, 1>;

class Policy {
 public:
  explicit Policy(const PolicyWeights& weights);
  /// The mean action of the members, each under its own standardizers.
  /// InputError if there is none, or if their inputs or outputs differ.
  explicit Policy(const std::vector<PolicyWeights>& members);
  /// [a, omega] in SI units for one raw observation (the `inputs` columns).
  [[nodiscard]] Eigen::Vector2d act(const Observation& observation) const;
  [[nodiscard]] int inputs() const { return static_cast<int>(members_.front().in_mean.size()); }
  /// Neurons per hidden layer (of the widest member).
  [[nodiscard]] int width() const;
  /// Networks averaged; 1 for a single network.
  [[nodiscard]] int members() const { return static_cast<int>(members_.size()); }

 private:
  using Hidden = Eigen::Matrix<float, Eigen::Dynamic, 1, 0, kMaxHiddenWidth, 1>;
  struct Network {
    explicit Network(const PolicyWeights& weights);
    [[nodiscard]] Eigen::Vector2d act(const Observation& observation) const;
    [[nodiscard]] int width() const { return static_cast<int>(weights.back().cols()); }
    /// Input layer, the kHiddenLayers - 1 hidden-to-hidden layers, output layer.
    std::array<Eigen::MatrixXf, kHiddenLayers + 1> weights;
    std::array<Eigen::VectorXf, kHiddenLayers + 1> biases;
    Observation in_mean, in_inverse_scale;
    Eigen::Vector2d out_mean, out_scale;
  };
  std::vector<Network> members_;
};

}  // namespace lanechange::learn
