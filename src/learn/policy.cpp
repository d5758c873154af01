#include "lanechange/learn/policy.hpp"

#include <algorithm>

#include "lanechange/error.hpp"

namespace lanechange::learn {

namespace {

using nlohmann::json;

constexpr int kLazyWidth = 16;

std::vector<double> to_vector(const Eigen::VectorXd& v) { return {v.begin(), v.end()}; }

Eigen::VectorXd vector_at(const json& j, const char* key) {
  const auto v = j.at(key).get<std::vector<double>>();
  return Eigen::Map<const Eigen::VectorXd>(v.data(), static_cast<Eigen::Index>(v.size()));
}

void require_shape(bool ok, const std::string& what) {
  if (!ok) {
    throw InputError("network", what + " does not fit a network of " +
                                    std::to_string(kHiddenLayers) + " tanh layers of 1 to " +
                                    std::to_string(kMaxHiddenWidth) + " neurons");
  }
}

}  // namespace

json PolicyWeights::to_json() const {
  json layers = json::array();
  for (std::size_t l = 0; l < weights.size(); ++l) {
    const Eigen::MatrixXf& w = weights[l];
    json rows = json::array();
    for (Eigen::Index r = 0; r < w.rows(); ++r) {
      rows.push_back(std::vector<float>(w.row(r).begin(), w.row(r).end()));
    }
    layers.push_back(
        {{"weights", rows}, {"bias", std::vector<float>(biases[l].begin(), biases[l].end())}});
  }
  return {{"inputs", inputs},
          {"outputs", outputs},
          {"input_mean", to_vector(input_mean)},
          {"input_scale", to_vector(input_scale)},
          {"output_mean", to_vector(output_mean)},
          {"output_scale", to_vector(output_scale)},
          {"layers", layers}};
}

PolicyWeights PolicyWeights::from_json(const json& j) {
  PolicyWeights p;
  p.inputs = j.at("inputs").get<std::vector<std::string>>();
  p.outputs = j.at("outputs").get<std::vector<std::string>>();
  p.input_mean = vector_at(j, "input_mean");
  p.input_scale = vector_at(j, "input_scale");
  p.output_mean = vector_at(j, "output_mean");
  p.output_scale = vector_at(j, "output_scale");
  for (const json& layer : j.at("layers")) {
    const auto rows = layer.at("weights").get<std::vector<std::vector<float>>>();
    const auto cols = rows.empty() ? 0 : rows[0].size();
    Eigen::MatrixXf w(static_cast<Eigen::Index>(rows.size()), static_cast<Eigen::Index>(cols));
    for (std::size_t r = 0; r < rows.size(); ++r) {
      require_shape(rows[r].size() == cols, "a ragged weight matrix");
      for (std::size_t c = 0; c < cols; ++c) {
        w(static_cast<Eigen::Index>(r), static_cast<Eigen::Index>(c)) = rows[r][c];
      }
    }
    const auto b = layer.at("bias").get<std::vector<float>>();
    p.weights.push_back(w);
    p.biases.push_back(
        Eigen::Map<const Eigen::VectorXf>(b.data(), static_cast<Eigen::Index>(b.size())));
  }
  return p;
}

std::vector<PolicyWeights> policy_members_from_json(const json& j) {
  if (!j.contains("average_of")) return {PolicyWeights::from_json(j)};
  std::vector<PolicyWeights> members;
  for (const json& member : j.at("average_of")) members.push_back(PolicyWeights::from_json(member));
  return members;
}

json policy_members_to_json(const std::vector<PolicyWeights>& members) {
  if (members.size() == 1) return members.front().to_json();
  json all = json::array();
  for (const PolicyWeights& member : members) all.push_back(member.to_json());
  return {{"average_of", all}};
}

Policy::Network::Network(const PolicyWeights& p) {
  const auto n = static_cast<Eigen::Index>(p.inputs.size());
  require_shape(n > 0 && n <= kMaxPolicyInputs && p.input_mean.size() == n &&
                    p.input_scale.size() == n && p.output_mean.size() == kActions &&
                    p.output_scale.size() == kActions,
                "the normalisation");
  require_shape(p.weights.size() == kHiddenLayers + 1 && p.biases.size() == kHiddenLayers + 1,
                "the layer count");
  const Eigen::Index width = p.weights[0].rows();
  require_shape(width >= 1 && width <= kMaxHiddenWidth, "the width " + std::to_string(width));
  for (int l = 0; l <= kHiddenLayers; ++l) {
    const auto& w = p.weights[static_cast<std::size_t>(l)];
    const Eigen::Index rows = l == kHiddenLayers ? kActions : width;
    const Eigen::Index cols = l == 0 ? n : width;
    require_shape(w.rows() == rows && w.cols() == cols &&
                      p.biases[static_cast<std::size_t>(l)].size() == rows,
                  "layer " + std::to_string(l));
    weights[static_cast<std::size_t>(l)] = w;
    biases[static_cast<std::size_t>(l)] = p.biases[static_cast<std::size_t>(l)];
  }
  in_mean = p.input_mean;
  in_inverse_scale = p.input_scale.cwiseInverse();
  out_mean = p.output_mean;
  out_scale = p.output_scale;
}

Policy::Policy(const PolicyWeights& weights) : members_{Network(weights)} {}

Policy::Policy(const std::vector<PolicyWeights>& members) {
  if (members.empty()) throw InputError("network", "a policy needs at least one network");
  for (const PolicyWeights& m : members) {
    if (m.inputs != members.front().inputs || m.outputs != members.front().outputs) {
      throw InputError("network", "the averaged networks take other inputs or give other outputs");
    }
    members_.emplace_back(m);
  }
}

int Policy::width() const {
  int widest = 0;
  for (const Network& n : members_) widest = std::max(widest, n.width());
  return widest;
}

Eigen::Vector2d Policy::act(const Observation& observation) const {
  if (observation.size() != members_.front().in_mean.size()) {
    throw InputError("observation", "has " + std::to_string(observation.size()) +
                                        " values; the policy takes " + std::to_string(inputs()));
  }
  if (members_.size() == 1) return members_.front().act(observation);
  Eigen::Vector2d sum = Eigen::Vector2d::Zero();
  for (const Network& n : members_) sum += n.act(observation);
  return sum / static_cast<double>(members_.size());
}

Eigen::Vector2d Policy::Network::act(const Observation& observation) const {
  // Single precision as in training; Eigen vectorises tanh for floats.
  // Into bounded vectors: no heap. Up to kLazyWidth the coefficient-wise
  // (lazy) product is faster, since the GEMV kernel's set-up costs as much
  // as such a layer; above it the kernel wins (BM_PolicyAct/10, /32, /64).
  const Observation z = (observation - in_mean).cwiseProduct(in_inverse_scale);
  const bool lazy = width() <= kLazyWidth;
  auto multiply = [lazy](const Eigen::MatrixXf& w, const auto& in, Hidden& out) {
    if (lazy) {
      out.noalias() = w.lazyProduct(in);
    } else {
      out.noalias() = w * in;
    }
  };
  Hidden h(width());
  Hidden next(width());
  multiply(weights[0], z.cast<float>(), h);
  h = (h + biases[0]).array().tanh().matrix();
  for (std::size_t l = 1; l < kHiddenLayers; ++l) {
    multiply(weights[l], h, next);
    h = (next + biases[l]).array().tanh().matrix();
  }
  Eigen::Vector2f out;
  out.noalias() = weights.back().lazyProduct(h);
  const Eigen::Vector2d y = (out + biases.back()).cast<double>();
  return out_mean + y.cwiseProduct(out_scale);
}

}  // namespace lanechange::learn
