#pragma once
// A trained model directory (docs/learning.md): the classifiers with and
// without the behavior input, the action network's policy, normalisation,
// feature lists, split, seeds, data-set identities, config and metrics.
// model.json lists every file with its CRC-32, so a damaged file is found
// at load time; a model that does not fit the caller is refused.
#include <Eigen/Dense>
#include <map>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "lanechange/learn/classifier.hpp"
#include "lanechange/learn/policy.hpp"
#include "lanechange/learn/strategy.hpp"

namespace lanechange::learn {

inline constexpr std::string_view kModelFormat = "lanechange.model/1";
inline constexpr std::string_view kModelFile = "model.json";

/// The classifier sets in a model: the scene classifiers without and with
/// the behavior one-hot, and the gap classifiers (data sets of format 3 on),
/// which name a gap slot or none from the gap features.
enum class FeatureSet { Plain, WithBehavior, Gaps };
[[nodiscard]] std::string_view feature_set_name(FeatureSet set);

/// What the caller will feed the model; a model that does not fit is refused
/// (InputError). Empty fields are not checked.
struct ModelRequirements {
  std::vector<std::string> classifier_features;  ///< the 13 raw features, in order
  std::vector<std::string> action_inputs;
  std::optional<nlohmann::json> expert_config;  ///< the config the data came from
};

// The implicit noexcept move sees nlohmann::json's invariant check
// (JSON_ASSERT) as a possible throw.
// NOLINTNEXTLINE(bugprone-exception-escape)
class Model {
 public:
  /// Reads dir, verifying the format, every file's checksum and the
  /// requirements. InputError on any mismatch or damage.
  static Model load(const std::string& dir, const ModelRequirements& requirements = {});

  /// Classes of raw (unstandardised) rows: the classifier features, followed
  /// by the behavior one-hot for FeatureSet::WithBehavior.
  [[nodiscard]] std::vector<int> classify(ClassifierKind kind, FeatureSet set,
                                          const Eigen::MatrixXd& raw) const;
  /// Whether the model has the set (every model has the scene classifiers;
  /// the gap classifiers need gap features in the data).
  [[nodiscard]] bool has(FeatureSet set) const { return standardizers_.contains(set); }
  [[nodiscard]] const Policy& policy() const { return *policy_; }
  /// The lane-strategy model (strategy.json). Models trained before it
  /// existed load without one: InputError only when it is asked for.
  [[nodiscard]] std::shared_ptr<const StrategyModel> strategy() const;
  [[nodiscard]] const nlohmann::json& description() const { return description_; }
  /// metrics.json as written by train_models.
  [[nodiscard]] const nlohmann::json& metrics() const { return metrics_; }

 private:
  nlohmann::json description_;
  nlohmann::json metrics_;
  std::map<std::pair<FeatureSet, ClassifierKind>, std::unique_ptr<Classifier>> classifiers_;
  std::map<FeatureSet, Standardizer> standardizers_;
  std::shared_ptr<const Policy> policy_;
  std::shared_ptr<const StrategyModel> strategy_;
  std::string dir_;
};

}  // namespace lanechange::learn
