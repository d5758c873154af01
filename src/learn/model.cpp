#include "lanechange/learn/model.hpp"

#include <filesystem>

#include "common/json_fields.hpp"
#include "data/manifest.hpp"
#include "lanechange/error.hpp"
#include "run/checksum.hpp"

namespace lanechange::learn {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

constexpr std::array<FeatureSet, 3> kFeatureSets = {FeatureSet::Plain, FeatureSet::WithBehavior,
                                                    FeatureSet::Gaps};

void verify_files(const std::string& dir, const json& files) {
  for (const auto& [name, crc] : files.items()) {
    const std::string path = (fs::path(dir) / name).string();
    if (!fs::exists(path)) throw InputError("", path + " is missing from the model");
    if (run::file_crc32(path) != crc.get<std::string>()) {
      throw InputError("", path + " does not match the model's checksum (damaged or truncated)");
    }
  }
}

void require_same(const std::vector<std::string>& wanted, const json& have, const char* what) {
  if (wanted.empty()) return;
  if (have.get<std::vector<std::string>>() != wanted) {
    throw InputError("", std::string("the model's ") + what + " differ from the caller's");
  }
}

void check_requirements(const json& d, const ModelRequirements& r) {
  require_same(r.classifier_features, d.at("features").at("classifier"), "classifier features");
  require_same(r.action_inputs, d.at("features").at("action_inputs"), "action inputs");
  if (r.expert_config &&
      expert_data_config(*r.expert_config) != expert_data_config(d.at("expert_config"))) {
    throw InputError("", "the model was trained on data made with another expert config");
  }
}

}  // namespace

std::string_view feature_set_name(FeatureSet set) {
  switch (set) {
    case FeatureSet::Plain: return "plain";
    case FeatureSet::WithBehavior: return "with_behavior";
    case FeatureSet::Gaps: return "gaps";
  }
  return "?";
}

Model Model::load(const std::string& dir, const ModelRequirements& requirements) {
  const std::string path = (fs::path(dir) / kModelFile).string();
  if (!fs::exists(path))
    throw InputError("", dir + " holds no model (" + std::string(kModelFile) + ")");
  Model m;
  m.dir_ = dir;
  m.description_ = lanechange::detail::read_json_file(path);
  const json& d = m.description_;
  try {
    if (d.value("format", std::string()) != kModelFormat) {
      throw InputError("", path + " is not a " + std::string(kModelFormat) + " model");
    }
    verify_files(dir, d.at("files"));
    check_requirements(d, requirements);
    for (FeatureSet set : kFeatureSets) {
      const std::string set_name(feature_set_name(set));
      // A model trained on data without gap features has no gap classifiers.
      if (set == FeatureSet::Gaps && !d.at("standardizers").contains(set_name)) continue;
      m.standardizers_[set] = Standardizer::from_json(d.at("standardizers").at(set_name));
      for (ClassifierKind kind : kClassifierKinds) {
        const json& entry = d.at("classifiers").at(set_name).at(std::string(classifier_name(kind)));
        auto classifier = make_classifier(kind, entry.at("hyperparameters"));
        classifier->load((fs::path(dir) / entry.at("file").get<std::string>()).string());
        m.classifiers_[{set, kind}] = std::move(classifier);
      }
    }
    const json policy = lanechange::detail::read_json_file(
        (fs::path(dir) / d.at("network").at("policy").get<std::string>()).string());
    m.policy_ = std::make_shared<const Policy>(policy_members_from_json(policy));
    m.metrics_ = lanechange::detail::read_json_file((fs::path(dir) / "metrics.json").string());
    if (d.contains("strategy")) {
      const std::string file = d.at("strategy").at("file").get<std::string>();
      m.strategy_ = std::make_shared<const StrategyModel>(StrategyModel::from_json(
          lanechange::detail::read_json_file((fs::path(dir) / file).string())));
    }
  } catch (const json::exception& e) {
    throw InputError("", path + " is malformed (" + e.what() + ")");
  }
  return m;
}

std::shared_ptr<const StrategyModel> Model::strategy() const {
  if (!strategy_) {
    std::string what = dir_;
    what += " holds no lane-strategy model (";
    what += kStrategyFile;
    what += "): it was trained before strategy-qp; run lanechange train again";
    throw InputError("--model", what);
  }
  return strategy_;
}

std::vector<int> Model::classify(ClassifierKind kind, FeatureSet set,
                                 const Eigen::MatrixXd& raw) const {
  if (!has(set)) {
    throw InputError("--model", dir_ + " has no " + std::string(feature_set_name(set)) +
                                    " classifiers: train it on data sets with gap features");
  }
  const Standardizer& s = standardizers_.at(set);
  if (raw.cols() != s.mean.size()) {
    throw InputError("", "the classifier takes " + std::to_string(s.mean.size()) + " inputs, not " +
                             std::to_string(raw.cols()));
  }
  return classifiers_.at({set, kind})->predict(s.apply(raw));
}

}  // namespace lanechange::learn
