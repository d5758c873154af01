#include "lanechange/learn/train.hpp"

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <map>
#include <set>
#include <utility>

#include "common/json_fields.hpp"
#include "data/manifest.hpp"
#include "lanechange/error.hpp"
#include "lanechange/learn/evaluation.hpp"
#include "lanechange/learn/learn_data.hpp"
#include "lanechange/learn/model.hpp"
#include "lanechange/run/quantile.hpp"
#include "learn/outputs.hpp"
#include "run/checksum.hpp"

namespace lanechange::learn {

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

// Sub-seeds, so that changing one part (say the CV folds) leaves the others.
struct Seeds {
  std::uint64_t split, folds, network, validation;
  explicit Seeds(std::uint64_t s) : split(s), folds(s + 1), network(s + 2), validation(s + 3) {}
  [[nodiscard]] json to_json() const {
    return {{"split", split}, {"folds", folds}, {"network", network}, {"validation", validation}};
  }
};

std::vector<int> labels_of(const std::vector<int>& all, const std::vector<int>& rows) {
  std::vector<int> out;
  out.reserve(rows.size());
  for (int r : rows) out.push_back(all[static_cast<std::size_t>(r)]);
  return out;
}

void check_out_dir(const std::string& out) {
  if (out.empty()) throw InputError("--out", "must not be empty");
  if (!fs::exists(out)) return;
  if (!fs::is_directory(out)) throw InputError("--out", out + " exists and is not a directory");
  if (!fs::is_empty(out) && !fs::exists(fs::path(out) / kModelFile)) {
    throw InputError("--out", out + " is not empty and holds no model; refusing to replace it");
  }
}

// The finished directory replaces the old one only once it is complete.
void publish(const fs::path& staging, const fs::path& out) {
  const fs::path old = out.string() + ".old." + std::to_string(::getpid());
  if (fs::exists(out)) fs::rename(out, old);
  fs::rename(staging, out);
  fs::remove_all(old);
}

// The output directory and the sibling it is built in before publish().
std::pair<fs::path, fs::path> staging_for(const std::string& out_dir) {
  fs::path out = fs::path(out_dir).lexically_normal();
  if (out.filename().empty()) out = out.parent_path();  // "model/": the staging dir is a sibling
  fs::path staging = out.string() + ".tmp." + std::to_string(::getpid());
  fs::remove_all(staging);
  return {out, staging};
}

struct Context {
  const TrainOptions& options;
  const LearningData& data;
  const Split& split;
  Seeds seeds;
  fs::path dir;  // staging directory
  json model;    // model.json in the making
  json metrics;
  std::vector<char> validation_pool;  // rows that may validate; empty: every one
  std::string warm_start;             // model directory to start the network from; empty: none
  std::string average_with;           // model directory whose policy's networks the new one joins

  void say(const std::string& line) const {
    if (options.progress != nullptr) *options.progress << "train: " << line << std::endl;
  }
};

json accuracy_by_behavior(const Context& c, const std::vector<int>& truth,
                          const std::vector<int>& predicted) {
  json out = json::object();
  for (int b = 0; b < kBehaviors; ++b) {
    long long n = 0, right = 0;
    for (std::size_t i = 0; i < truth.size(); ++i) {
      if (c.data.scenarios.behavior[static_cast<std::size_t>(c.split.test[i])] != b) continue;
      ++n;
      right += truth[i] == predicted[i] ? 1 : 0;
    }
    if (n > 0)
      out[std::string(kBehaviorNames[static_cast<std::size_t>(b)])] = double(right) / double(n);
  }
  return out;
}

// What one classifier is trained on: standardized rows and their classes.
struct ClassifierData {
  Eigen::MatrixXd x, x_test;
  std::vector<int> y, y_test;
  int classes = kClasses;
};

json train_classifier(Context& c, ClassifierKind kind, FeatureSet set, const ClassifierData& d,
                      std::vector<int>& predicted) {
  const Eigen::MatrixXd& x = d.x;
  const std::vector<int>& y = d.y;
  const std::vector<int>& y_test = d.y_test;
  const std::string name(classifier_name(kind));
  const std::string set_name(feature_set_name(set));
  const Selection selection =
      select_hyperparameters(kind, x, y, c.options.search, c.seeds.folds, c.options.jobs);
  const auto start = Clock::now();
  auto model = make_classifier(kind, selection.chosen().hyper);
  model->fit(x, y);
  const double train_s = seconds_since(start);
  const auto predict_start = Clock::now();
  predicted = model->predict(d.x_test);
  const double predict_us =
      1e6 * seconds_since(predict_start) / double(std::max<std::size_t>(y_test.size(), 1));

  const std::string file = "classifiers/" + set_name + "/" + classifier_file(kind);
  fs::create_directories(c.dir / "classifiers" / set_name);
  model->save((c.dir / file).string());
  c.model["classifiers"][set_name][name] = {{"file", file},
                                            {"hyperparameters", selection.chosen().hyper}};

  const ClassScores scores = score(y_test, predicted, d.classes);
  json m = scores.to_json();
  m["cv_accuracy_mean"] = selection.chosen().mean();
  m["cv_accuracy_sd"] = selection.chosen().sd();
  m["cv_fold_accuracy"] = selection.chosen().fold_accuracy;
  m["cv_candidates"] = json::array();
  for (const auto& cand : selection.candidates) {
    m["cv_candidates"].push_back(
        {{"hyperparameters", cand.hyper}, {"cv_accuracy_mean", cand.mean()}});
  }
  m["hyperparameters"] = selection.chosen().hyper;
  m["train_s"] = train_s;
  m["predict_us_per_scene"] = predict_us;
  m["accuracy_by_behavior"] = accuracy_by_behavior(c, y_test, predicted);

  const std::string stem = "confusion_" + set_name + "_" + name;
  // The confusion files name the scene classes; a gap classifier's are in metrics.json.
  if (d.classes == kClasses) {
    detail::write_confusion_csv(scores.row_normalised(), (c.dir / (stem + ".csv")).string());
  }
  if (c.options.plots && d.classes == kClasses) {
    detail::plot_confusion(scores.row_normalised(), name + " (" + set_name + ")",
                           (c.dir / (stem + ".png")).string());
  }
  c.say(name + " (" + set_name + "): test accuracy " + std::to_string(scores.accuracy) + ", CV " +
        std::to_string(selection.chosen().mean()) + ", trained in " + std::to_string(train_s) +
        " s");
  return m;
}

void train_classifier_set(Context& c, FeatureSet set) {
  const bool with_behavior = set == FeatureSet::WithBehavior;
  const ScenarioTable& t = c.data.scenarios;
  const Standardizer standardizer =
      Standardizer::fit(classifier_inputs(t, c.split.train, with_behavior));
  ClassifierData d;
  d.x = standardizer.apply(classifier_inputs(t, c.split.train, with_behavior));
  d.x_test = standardizer.apply(classifier_inputs(t, c.split.test, with_behavior));
  d.y = labels_of(t.label, c.split.train);
  d.y_test = labels_of(t.label, c.split.test);
  const std::string set_name(feature_set_name(set));
  c.model["standardizers"][set_name] = standardizer.to_json();
  c.model["features"]["classifier_" + set_name] = classifier_input_names(c.data, with_behavior);
  json& out = c.metrics[with_behavior ? "classifiers_with_behavior" : "classifiers"];
  std::vector<int> predicted;
  for (ClassifierKind kind : kClassifierKinds) {
    out[std::string(classifier_name(kind))] = train_classifier(c, kind, set, d, predicted);
  }
}

Eigen::MatrixXd rows_of(const Eigen::MatrixXd& all, const std::vector<int>& rows) {
  Eigen::MatrixXd out(static_cast<Eigen::Index>(rows.size()), all.cols());
  for (std::size_t i = 0; i < rows.size(); ++i)
    out.row(static_cast<Eigen::Index>(i)) = all.row(rows[i]);
  return out;
}

// The share of test scenes whose predicted gap the expert is known to
// complete well-posed, or that are rightly refused (no such gap known).
double completable_share(const ScenarioTable& t, const std::vector<int>& test,
                         const std::vector<int>& predicted) {
  long long right = 0;
  for (std::size_t i = 0; i < test.size(); ++i) {
    const unsigned ok = t.completable_slots[static_cast<std::size_t>(test[i])];
    const int p = predicted[i];
    right += (p == kNoGap ? ok == 0U : ((ok >> p) & 1U) != 0U) ? 1 : 0;
  }
  return test.empty() ? 0.0 : double(right) / double(test.size());
}

// The gap classifiers (docs/learning.md, "Gap classifiers"): from the gap
// features, the slot whose gap the expert completes, or none.
void train_gap_classifiers(Context& c) {
  const ScenarioTable& t = c.data.scenarios;
  if (c.data.gap_classifier_features.empty()) return;
  const Eigen::MatrixXd train_rows = rows_of(t.gap_features, c.split.train);
  const Standardizer standardizer = Standardizer::fit(train_rows);
  ClassifierData d;
  d.x = standardizer.apply(train_rows);
  d.x_test = standardizer.apply(rows_of(t.gap_features, c.split.test));
  d.y = labels_of(t.gap_class, c.split.train);
  d.y_test = labels_of(t.gap_class, c.split.test);
  d.classes = kGapClasses;
  const std::string set_name(feature_set_name(FeatureSet::Gaps));
  c.model["standardizers"][set_name] = standardizer.to_json();
  c.model["features"]["classifier_" + set_name] = c.data.gap_classifier_features;
  c.metrics["gap_labels"] = c.data.gap_labels;
  json& out = c.metrics["gap_classifiers"];
  std::vector<int> predicted;
  for (ClassifierKind kind : kClassifierKinds) {
    json m = train_classifier(c, kind, FeatureSet::Gaps, d, predicted);
    m["completable_share"] = completable_share(t, c.split.test, predicted);
    out[std::string(classifier_name(kind))] = std::move(m);
  }
}

json majority_class(const Context& c) {
  const auto& label = c.data.scenarios.label;
  std::vector<long long> count(kClasses, 0);
  for (int r : c.split.train) ++count[static_cast<std::size_t>(label[static_cast<std::size_t>(r)])];
  const int majority =
      static_cast<int>(std::max_element(count.begin(), count.end()) - count.begin());
  long long right = 0;
  for (int r : c.split.test) right += label[static_cast<std::size_t>(r)] == majority ? 1 : 0;
  return {{"class", kLabelNames[static_cast<std::size_t>(majority)]},
          {"test_accuracy", double(right) / double(c.split.test.size())}};
}

// Physical errors of the exported policy on the test samples.
json policy_errors(const Policy& policy, const SampleTable& s, const std::vector<int>& rows,
                   const std::vector<std::string>& names) {
  std::vector<std::vector<double>> abs_error(kActions);
  for (int r : rows) {
    const Eigen::Vector2d a = policy.act(s.inputs.row(r).transpose());
    for (int k = 0; k < kActions; ++k)
      abs_error[static_cast<std::size_t>(k)].push_back(std::abs(a(k) - s.targets(r, k)));
  }
  json rmse, p95;
  for (int k = 0; k < kActions; ++k) {
    auto& e = abs_error[static_cast<std::size_t>(k)];
    double sum = 0.0;
    for (double v : e) sum += v * v;
    std::sort(e.begin(), e.end());
    const std::string& name = names[static_cast<std::size_t>(k)];
    rmse[name] = e.empty() ? 0.0 : std::sqrt(sum / double(e.size()));
    p95[name] = e.empty() ? 0.0 : run::nearest_rank_sorted(e, 0.95);
  }
  return {{"test_rmse", rmse}, {"test_p95_abs_error", p95}};
}

// Training scenarios split once more, by scenario, for early stopping.
std::vector<char> validation_scenarios(const Context& c) {
  std::vector<int> well_posed;
  for (int r : c.split.train) {
    const auto row = static_cast<std::size_t>(r);
    const bool pooled = c.validation_pool.empty() || c.validation_pool[row] != 0;
    if (pooled && c.data.scenarios.label[row] == kWellPosed) well_posed.push_back(r);
  }
  if (well_posed.size() < 2)
    throw InputError("--data", "needs at least two well-posed training plans");
  const Split inner = split_scenarios(static_cast<int>(well_posed.size()),
                                      c.options.network.validation_share, c.seeds.validation);
  std::vector<int> rows;
  for (int i : inner.test) rows.push_back(well_posed[static_cast<std::size_t>(i)]);
  return mask_of(rows, c.data.scenarios.rows());
}

// A warm start keeps the standardizers its network was trained under: the
// same weights mean something else under new ones.
std::pair<Standardizer, Standardizer> network_standardizers(const Context& c,
                                                            const Eigen::MatrixXd& fit_in,
                                                            const Eigen::MatrixXd& fit_out) {
  if (c.warm_start.empty()) return {Standardizer::fit(fit_in), Standardizer::fit(fit_out)};
  // The warm start's network.dlib is its newest network, the last member.
  const PolicyWeights w =
      policy_members_from_json(
          lanechange::detail::read_json_file((fs::path(c.warm_start) / "policy.json").string()))
          .back();
  if (w.inputs != c.data.action_inputs || w.outputs != c.data.action_targets) {
    throw InputError(c.warm_start, "its network has other inputs or outputs than the data's");
  }
  return {Standardizer{w.input_mean, w.input_scale}, Standardizer{w.output_mean, w.output_scale}};
}

// Checked before any training: a retrain reads the count from its base's model.json.
void require_network_count(int networks, const std::string& where) {
  if (networks < 1 || networks > kMaxNetworks) {
    throw InputError(where, "networks must be 1.." + std::to_string(kMaxNetworks) + ", not " +
                                std::to_string(networks));
  }
}

// An ensemble's networks, on the same rows, on up to `jobs` threads; one
// network is the paper's.
std::vector<TrainedNetwork> train_members(const Context& c, const Eigen::MatrixXd& x,
                                          const Eigen::MatrixXd& y, const std::vector<int>& fit,
                                          const std::vector<int>& validation,
                                          const std::string& warm_file) {
  const int n = c.options.network.networks;
  std::vector<TrainedNetwork> nets(static_cast<std::size_t>(n));
  parallel_for(n, c.options.jobs, [&](int k) {
    NetworkSettings settings = c.options.network;
    settings.seed = member_seed(c.seeds.network, k);
    // Several threads' epoch lines would interleave: the first network's alone.
    nets[static_cast<std::size_t>(k)] = train_network(
        x, y, fit, validation, settings, k == 0 ? c.options.progress : nullptr, warm_file);
  });
  return nets;
}

// network.dlib is the first new network, network-K.dlib the others; a
// retrain's copy of its base may hold more of them than it makes.
void save_networks(const Context& c, const std::vector<TrainedNetwork>& nets) {
  for (const auto& entry : fs::directory_iterator(c.dir)) {
    const std::string name = entry.path().filename().string();
    if (name.starts_with("network-") && name.ends_with(".dlib")) fs::remove(entry.path());
  }
  for (std::size_t k = 0; k < nets.size(); ++k) {
    const std::string name = k == 0 ? "network.dlib" : "network-" + std::to_string(k) + ".dlib";
    nets[k].save((c.dir / name).string());
  }
}

json member_metrics(const TrainedNetwork& net) {
  return {{"epochs", net.curve.size()},
          {"best_epoch", net.best_epoch},
          {"best_validation_mse",
           net.curve[static_cast<std::size_t>(net.best_epoch - 1)].validation_mse},
          {"train_s", net.train_s},
          {"s_per_epoch", net.seconds_per_epoch()}};
}

void train_action_network(Context& c) {
  const SampleTable& s = c.data.samples;
  const int n = c.data.scenarios.rows();
  const std::vector<char> validation_mask = validation_scenarios(c);
  std::vector<char> fit_mask = mask_of(c.split.train, n);
  for (int i = 0; i < n; ++i)
    if (validation_mask[static_cast<std::size_t>(i)] != 0)
      fit_mask[static_cast<std::size_t>(i)] = 0;
  const std::vector<int> fit = sample_rows_of(s, fit_mask);
  const std::vector<int> validation = sample_rows_of(s, validation_mask);
  const std::vector<int> test = sample_rows_of(s, mask_of(c.split.test, n));

  Eigen::MatrixXd fit_in(static_cast<Eigen::Index>(fit.size()), s.inputs.cols());
  Eigen::MatrixXd fit_out(static_cast<Eigen::Index>(fit.size()), s.targets.cols());
  for (std::size_t i = 0; i < fit.size(); ++i) {
    fit_in.row(static_cast<Eigen::Index>(i)) = s.inputs.row(fit[i]);
    fit_out.row(static_cast<Eigen::Index>(i)) = s.targets.row(fit[i]);
  }
  const auto [in_norm, out_norm] = network_standardizers(c, fit_in, fit_out);
  const int networks = c.options.network.networks;
  c.say("action network" + (networks > 1 ? "s: " + std::to_string(networks) + " x " : ": ") +
        std::to_string(fit.size()) + " training rows, " + std::to_string(validation.size()) +
        " validation rows" +
        (c.warm_start.empty() ? std::string() : ", from the network of " + c.warm_start));
  const std::string warm_file =
      c.warm_start.empty() ? "" : (fs::path(c.warm_start) / "network.dlib").string();
  const auto start = Clock::now();
  const std::vector<TrainedNetwork> nets = train_members(
      c, in_norm.apply(s.inputs), out_norm.apply(s.targets), fit, validation, warm_file);
  const double train_s = seconds_since(start);
  std::vector<PolicyWeights> members;
  if (!c.average_with.empty()) {
    members = policy_members_from_json(
        lanechange::detail::read_json_file((fs::path(c.average_with) / "policy.json").string()));
  }
  for (const TrainedNetwork& net : nets) {
    PolicyWeights w{c.data.action_inputs, c.data.action_targets, in_norm.mean, in_norm.scale,
                    out_norm.mean,        out_norm.scale,        {},           {}};
    net.export_layers(w.weights, w.biases);
    members.push_back(std::move(w));
  }
  const Policy policy(members);  // InputError for networks of other inputs
  lanechange::detail::write_file_atomically((c.dir / "policy.json").string(),
                                            policy_members_to_json(members).dump());
  save_networks(c, nets);
  const TrainedNetwork& first = nets.front();
  detail::write_loss_csv(first.curve, (c.dir / "loss.csv").string());
  if (c.options.plots)
    detail::plot_loss(first.curve, first.best_epoch, (c.dir / "loss.png").string());

  // The errors are the policy's: the members' mean where it averages. The
  // curve's figures are the first network's.
  json m = policy_errors(policy, s, test, c.data.action_targets);
  m.update(member_metrics(first));
  m["members"] = members.size();
  m["train_s"] = train_s;
  if (networks > 1) {
    m["ensemble"] = json::array();
    for (const TrainedNetwork& net : nets) m["ensemble"].push_back(member_metrics(net));
  }
  m["train_rows"] = fit.size();
  m["validation_rows"] = validation.size();
  m["test_rows"] = test.size();
  c.metrics["network"] = m;
  c.model["network"] = {{"policy", "policy.json"}, {"dlib", "network.dlib"}};
  c.say("action network" + std::string(networks > 1 ? "s" : "") + ": " +
        std::to_string(first.curve.size()) + " epochs" + (networks > 1 ? " (the first)" : "") +
        ", test RMSE a " + m["test_rmse"].begin()->dump() + ", omega " +
        (++m["test_rmse"].begin())->dump());
}

// The strategy model, and the share of test plans whose strategy (from
// their start) is its first guess and among its first five: how often the
// exact integer part is recovered, a lower bound on how often a feasible
// one is (docs/strategy.md measures that).
void train_strategy(Context& c) {
  const auto start = Clock::now();
  const StrategyModel model = StrategyModel::fit(
      strategy_rows(c.data, c.split.train, c.options.strategy.node_stride), c.options.strategy);
  const StrategyRows test = strategy_rows(c.data, c.split.test, 0);
  long long top1 = 0, top5 = 0;
  for (std::size_t i = 0; i < test.labels.size(); ++i) {
    const std::vector<Strategy> guess = model.predict(test.features[i], 5);
    top1 += !guess.empty() && guess.front() == test.labels[i] ? 1 : 0;
    top5 += std::find(guess.begin(), guess.end(), test.labels[i]) != guess.end() ? 1 : 0;
  }
  const double n = double(std::max<std::size_t>(test.labels.size(), 1));
  lanechange::detail::write_file_atomically((c.dir / std::string(kStrategyFile)).string(),
                                            model.to_json().dump());
  c.model["strategy"] = {{"file", kStrategyFile}};
  c.metrics["strategy"] = {
      {"train_rows", model.rows()},          {"distinct_strategies", model.strategies()},
      {"test_plans", test.labels.size()},    {"test_exact_top1", double(top1) / n},
      {"test_exact_top5", double(top5) / n}, {"train_s", seconds_since(start)}};
  std::string line = "strategy model: ";
  line += std::to_string(model.rows());
  line += " rows, ";
  line += std::to_string(model.strategies());
  line += " strategies; a test plan's own strategy first in ";
  line += std::to_string(double(top1) / n);
  line += ", in the top 5 in ";
  line += std::to_string(double(top5) / n);
  c.say(line);
}

json describe_data(const Context& c) {
  const int n = c.data.scenarios.rows();
  json split = json::array();
  for (std::size_t d = 0; d < c.data.datasets.size(); ++d) {
    std::vector<long long> test;
    for (int r : c.split.test) {
      if (c.data.scenarios.dataset[static_cast<std::size_t>(r)] == static_cast<int>(d)) {
        test.push_back(c.data.scenarios.index[static_cast<std::size_t>(r)]);
      }
    }
    const DatasetIdentity& id = c.data.datasets[d];
    split.push_back({{"dir", id.dir},
                     {"manifest_crc32", id.manifest_crc32},
                     {"scenarios", id.scenarios},
                     {"seed", id.seed},
                     {"test_indices", test}});
  }
  return {{"datasets", split}, {"scenarios", n}};
}

// Everything model.json says beyond the files and their checksums.
void describe_model(Context& c) {
  c.model["format"] = kModelFormat;
  c.model["config"] = c.options.config();
  c.model["seeds"] = c.seeds.to_json();
  c.model["expert_config"] = c.data.config;
  c.model["dataset_format"] = c.data.dataset_format;
  c.model["data"] = describe_data(c);
  c.model["labels"] = kLabelNames;
  c.model["features"]["action_inputs"] = c.data.action_inputs;
  c.model["features"]["action_targets"] = c.data.action_targets;
  c.model["features"]["classifier"] = c.data.classifier_features;
}

void write_model_files(Context& c) {
  lanechange::detail::write_file_atomically((c.dir / "metrics.json").string(), c.metrics.dump(2));
  lanechange::detail::write_file_atomically((c.dir / "report.md").string(),
                                            detail::report_markdown(c.metrics));
  // Every file but model.json itself, with its checksum.
  json files = json::object();
  for (const auto& entry : fs::recursive_directory_iterator(c.dir)) {
    // A retrained model starts as a copy of its base, model.json included.
    if (!entry.is_regular_file() || entry.path().filename() == kModelFile) continue;
    files[fs::relative(entry.path(), c.dir).generic_string()] =
        run::file_crc32(entry.path().string());
  }
  c.model["files"] = files;
  lanechange::detail::write_file_atomically((c.dir / kModelFile).string(), c.model.dump(2));
}

// Fills the staging directory, completes it and publishes it; a failure
// removes it and leaves any old model where it stood.
template <class Fill>
TrainReport build_and_publish(Context& c, const fs::path& out, Clock::time_point start,
                              Fill&& fill) {
  try {
    fill();
    write_model_files(c);
    publish(c.dir, out);
  } catch (...) {
    std::error_code ignored;
    fs::remove_all(c.dir, ignored);
    throw;
  }
  c.say("wrote " + out.string());
  return {c.metrics, seconds_since(start)};
}

}  // namespace

json TrainOptions::config() const {
  json out = {
      {"seed", seed},
      {"test_share", test_share},
      {"cv_folds", search.folds},
      {"knn_k", search.knn_k},
      {"ensemble_trees", search.ensemble_trees},
      {"naive_bayes_kernel", search.naive_bayes_kernel},
      {"quick_search", search.quick},
      {"network",
       {{"hidden_layers", kHiddenLayers},
        {"hidden_width", network.hidden_width},
        {"activation", "tanh"},
        {"optimizer", "adam"},
        {"max_epochs", network.max_epochs},
        {"patience", network.patience},
        {"batch_size", network.batch_size},
        {"learning_rate", network.learning_rate},
        {"validation_share", network.validation_share}}},
      {"strategy", {{"neighbors", strategy.neighbors}, {"node_stride", strategy.node_stride}}}};
  // Only an ensemble says so: models and DAgger runs from before ensembles
  // describe (and resume) as before.
  if (network.networks != 1) out["network"]["networks"] = network.networks;
  if (network.inputs != NetworkInputs::Paper) out["network"]["inputs"] = to_string(network.inputs);
  return out;
}

TrainReport train_models(const TrainOptions& options) {
  const auto start = Clock::now();
  require_network_count(options.network.networks, "--networks");
  check_out_dir(options.out_dir);
  const LearningData data =
      load_learning_data(options.data_dirs, manifest_key(options.network.inputs));
  const Split split = split_scenarios(data.scenarios.rows(), options.test_share, options.seed);
  const auto [out, staging] = staging_for(options.out_dir);
  fs::create_directories(staging);
  Context c{options, data, split, Seeds(options.seed), staging, json::object(), json::object(),
            {},      {},   {}};
  return build_and_publish(c, out, start, [&] {
    c.say("read " + std::to_string(data.scenarios.rows()) + " scenarios and " +
          std::to_string(data.samples.rows()) + " well-posed samples from " +
          std::to_string(data.datasets.size()) + " data set(s)");
    c.metrics["seed"] = options.seed;
    c.metrics["data"] = {
        {"scenarios", data.scenarios.rows()},
        {"train_scenarios", split.train.size()},
        {"test_scenarios", split.test.size()},
        {"train_samples",
         sample_rows_of(data.samples, mask_of(split.train, data.scenarios.rows())).size()},
        {"test_samples",
         sample_rows_of(data.samples, mask_of(split.test, data.scenarios.rows())).size()}};
    c.metrics["majority_class"] = majority_class(c);
    train_classifier_set(c, FeatureSet::Plain);
    train_classifier_set(c, FeatureSet::WithBehavior);
    train_gap_classifiers(c);
    train_action_network(c);
    train_strategy(c);
    c.metrics["wall_s"] = seconds_since(start);
    describe_model(c);
  });
}

namespace {

// The base model's split for the data sets it was trained on (found by
// their manifests' checksums); every row of another data set trains.
struct BaseSplit {
  Split split;
  std::vector<char> base_rows;  // rows of the data sets the base was trained on
};

BaseSplit base_split(const LearningData& data, const json& base) {
  std::map<std::string, std::set<long long>> test_of;
  for (const json& d : base.at("data").at("datasets")) {
    const auto indices = d.at("test_indices").get<std::vector<long long>>();
    test_of[d.at("manifest_crc32").get<std::string>()] = {indices.begin(), indices.end()};
  }
  BaseSplit out;
  out.base_rows.assign(static_cast<std::size_t>(data.scenarios.rows()), 0);
  for (int r = 0; r < data.scenarios.rows(); ++r) {
    const auto row = static_cast<std::size_t>(r);
    const auto& id = data.datasets[static_cast<std::size_t>(data.scenarios.dataset[row])];
    const auto it = test_of.find(id.manifest_crc32);
    out.base_rows[row] = it != test_of.end() ? 1 : 0;
    const bool test = it != test_of.end() && it->second.count(data.scenarios.index[row]) > 0;
    (test ? out.split.test : out.split.train).push_back(r);
  }
  return out;
}

}  // namespace

TrainReport retrain_network(const RetrainOptions& options) {
  const auto start = Clock::now();
  check_out_dir(options.out_dir);
  const json base = Model::load(options.base_model).description();
  // A retrain reads what its base's network reads.
  const NetworkInputs inputs =
      base.at("config").at("network").value("inputs", "paper") == std::string("gap")
          ? NetworkInputs::Gap
          : NetworkInputs::Paper;
  const LearningData data = load_learning_data(options.data_dirs, manifest_key(inputs));
  if (expert_data_config(data.config) != expert_data_config(base.at("expert_config"))) {
    throw InputError("--data", "the data sets' expert config is not the base model's");
  }
  const BaseSplit split = base_split(data, base);
  TrainOptions train;
  train.seed = base.at("config").at("seed").get<std::uint64_t>();
  train.network = options.network;
  // A retrain keeps the base's shape (and a fine-tune needs it).
  const json& base_network = base.at("config").at("network");
  train.network.hidden_width = base_network.value("hidden_width", kHiddenWidth);
  // An ensemble's rounds are ensembles of its size.
  train.network.networks = base_network.value("networks", 1);
  train.network.inputs = inputs;
  require_network_count(train.network.networks, options.base_model);
  if (train.network.networks > 1 && !options.warm_start.empty()) {
    throw InputError(options.warm_start,
                     "a fine-tune starts from one network, and the base model "
                     "averages " +
                         std::to_string(train.network.networks));
  }
  train.plots = options.plots;
  train.progress = options.progress;
  // Named, not a structured binding: the lambda below captures it.
  const auto [out, staging_dir] = staging_for(options.out_dir);
  const fs::path staging = staging_dir;
  const json metrics =
      lanechange::detail::read_json_file((fs::path(options.base_model) / "metrics.json").string());
  // The base's own validation rows, in the same order, give the same inner
  // split as the base's: early stopping is then like for like.
  std::vector<char> pool = options.validate_on_added ? std::vector<char>{} : split.base_rows;
  Seeds seeds(train.seed);
  seeds.network += options.network_seed_offset;
  Context c{train,
            data,
            split.split,
            seeds,
            staging,
            base,
            metrics,
            std::move(pool),
            options.warm_start,
            options.average_with};
  return build_and_publish(c, out, start, [&] {
    fs::copy(options.base_model, staging, fs::copy_options::recursive);
    train_action_network(c);
    c.model["data"] = describe_data(c);
    c.model["retrained_network"] = {{"base_model", options.base_model},
                                    {"warm_start", options.warm_start},
                                    {"average_with", options.average_with},
                                    {"network_seed", seeds.network},
                                    {"note", options.note}};
    c.metrics["data"]["samples_network"] = data.samples.rows();
    c.metrics["network"]["validation"] = options.validate_on_added ? "all data sets" : "base's";
    c.metrics["wall_s_retrain"] = seconds_since(start);
  });
}

}  // namespace lanechange::learn
