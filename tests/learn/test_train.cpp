// End to end on a small generated data set: train, reload, refuse damage.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>

#include "../data/data_helpers.hpp"
#include "lanechange/error.hpp"
#include "lanechange/learn/learn_data.hpp"
#include "lanechange/learn/model.hpp"
#include "lanechange/learn/train.hpp"
#include "lanechange/planner/planner.hpp"
#include "lanechange/sampler.hpp"

namespace lanechange::learn {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

constexpr int kMaxEpochs = 6;

// Path -> content of every file under dir.
std::map<std::string, std::string> snapshot(const fs::path& dir) {
  std::map<std::string, std::string> out;
  for (const auto& e : fs::recursive_directory_iterator(dir)) {
    if (e.is_regular_file()) out[e.path().string()] = testing::read_text(e.path().string());
  }
  return out;
}

// Every test of this suite reads one data set and one model, made once per
// CTest run (tests/CMakeLists.txt, SHARED_SUITES): each test runs in its own
// process, and making them took 40 s a test under the sanitizers.
class Trained : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    root_ = fs::path(LANECHANGE_TEST_SHARED_DIR) / "trained";
    testing::made_once(root_, [] {
      const auto gen = testing::run_cli(testing::small_run(data_dir(), 120, 5, "--jobs 2"));
      ASSERT_EQ(gen.exit_code, 0) << gen.output;
      const TrainReport report = train_models(options(model_dir()));
      testing::write_text(report_metrics_file(), report.metrics.dump());
    });
    report_metrics_ = json::parse(testing::read_text(report_metrics_file()));
  }

  static TrainOptions options(const std::string& out) {
    TrainOptions o;
    o.data_dirs = {data_dir()};
    o.out_dir = out;
    o.seed = 4;
    o.jobs = 2;
    o.search.quick = true;
    o.network.max_epochs = kMaxEpochs;
    o.plots = false;
    return o;
  }
  // A short retrain of `base`'s network on the suite's data set.
  static RetrainOptions quick_retrain(const std::string& base, const std::string& out) {
    RetrainOptions o;
    o.base_model = base;
    o.data_dirs = {data_dir()};
    o.out_dir = out;
    o.network.max_epochs = 2;
    o.plots = false;
    return o;
  }
  static std::string data_dir() { return (root_ / "data").string(); }
  static std::string model_dir() { return (root_ / "model").string(); }
  // The metrics train_models returned, beside the metrics.json it wrote.
  static std::string report_metrics_file() { return (root_ / "returned_metrics.json").string(); }
  static std::string train_args(const std::string& out) {
    return "train --data " + data_dir() + " --out " + out +
           " --seed 4 --jobs 2 --quick --max-epochs " + std::to_string(kMaxEpochs);
  }

  static inline fs::path root_;
  static inline json report_metrics_;
};

TEST_F(Trained, MetricsHoldEveryClassifierAndTheNetwork) {
  const json m = json::parse(testing::read_text(model_dir() + "/metrics.json"));
  EXPECT_EQ(m, report_metrics_);
  for (const char* set : {"classifiers", "classifiers_with_behavior"}) {
    for (ClassifierKind kind : kClassifierKinds) {
      const json& c = m.at(set).at(std::string(classifier_name(kind)));
      EXPECT_GE(c.at("test_accuracy").get<double>(), 0.0);
      EXPECT_LE(c.at("test_accuracy").get<double>(), 1.0);
      EXPECT_EQ(c.at("cv_fold_accuracy").size(), 5u);
      EXPECT_EQ(c.at("confusion_row_normalised").size(), 3u);
    }
  }
  EXPECT_EQ(m.at("data").at("test_scenarios").get<int>(), 24);  // 0.2 of 120
  for (const char* out : {"a", "omega"}) {
    EXPECT_TRUE(std::isfinite(m.at("network").at("test_rmse").at(out).get<double>()));
    EXPECT_GE(m.at("network").at("test_p95_abs_error").at(out).get<double>(), 0.0);
  }
  EXPECT_LE(m.at("network").at("epochs").get<int>(), kMaxEpochs);
  EXPECT_NE(testing::read_text(model_dir() + "/report.md").find("| svm |"), std::string::npos);
}

TEST_F(Trained, ReloadedModelGivesTheSamePredictions) {
  const Model model = Model::load(model_dir());
  const LearningData data = load_learning_data({data_dir()});
  const json& d = model.description();
  const auto test_indices =
      d.at("data").at("datasets").at(0).at("test_indices").get<std::vector<long long>>();
  std::vector<int> rows;
  for (int r = 0; r < data.scenarios.rows(); ++r) {
    if (std::find(test_indices.begin(), test_indices.end(),
                  data.scenarios.index[static_cast<std::size_t>(r)]) != test_indices.end()) {
      rows.push_back(r);
    }
  }
  const json m = report_metrics_;
  for (FeatureSet set : {FeatureSet::Plain, FeatureSet::WithBehavior}) {
    const Eigen::MatrixXd raw =
        classifier_inputs(data.scenarios, rows, set == FeatureSet::WithBehavior);
    for (ClassifierKind kind : kClassifierKinds) {
      const std::vector<int> predicted = model.classify(kind, set, raw);
      Eigen::MatrixXd counts = Eigen::MatrixXd::Zero(kClasses, kClasses);
      for (std::size_t i = 0; i < rows.size(); ++i) {
        counts(data.scenarios.label[static_cast<std::size_t>(rows[i])], predicted[i]) += 1.0;
      }
      const json& want =
          m.at(set == FeatureSet::Plain ? "classifiers" : "classifiers_with_behavior")
              .at(std::string(classifier_name(kind)))
              .at("confusion_counts");
      for (int r = 0; r < kClasses; ++r) {
        for (int c = 0; c < kClasses; ++c)
          EXPECT_EQ(counts(r, c), want[r][c].get<double>()) << classifier_name(kind);
      }
    }
  }
  // The reloaded policy reproduces the stored test error.
  const std::vector<int> samples =
      sample_rows_of(data.samples, mask_of(rows, data.scenarios.rows()));
  double sum = 0.0;
  for (int r : samples) {
    const double e =
        model.policy().act(data.samples.inputs.row(r).transpose())(0) - data.samples.targets(r, 0);
    sum += e * e;
  }
  EXPECT_NEAR(std::sqrt(sum / static_cast<double>(samples.size())),
              m.at("network").at("test_rmse").at("a").get<double>(), 1e-9);
}

// The gap classifiers learn, from the gap features, the slot of the gap the
// expert completes (or none), and reload to the scores they were trained to.
TEST_F(Trained, GapClassifiersNameTheExpertsGapAndReloadToTheirScores) {
  const LearningData data = load_learning_data({data_dir()});
  const ScenarioTable& t = data.scenarios;
  ASSERT_EQ(t.gap_features.rows(), t.rows());
  ASSERT_EQ(t.gap_features.cols(), static_cast<Eigen::Index>(data.gap_classifier_features.size()));
  int named = 0;
  for (int r = 0; r < t.rows(); ++r) {
    const auto row = static_cast<std::size_t>(r);
    const int slot = t.gap_class[row];
    EXPECT_EQ(slot != kNoGap, t.label[row] == kWellPosed) << "row " << r;
    // Without gap labels the one gap known to be completable is the plan's.
    EXPECT_EQ(t.completable_slots[row], slot == kNoGap ? 0U : 1U << slot) << "row " << r;
    named += slot != kNoGap ? 1 : 0;
  }
  EXPECT_GT(named, 0);
  const Model model = Model::load(model_dir());
  ASSERT_TRUE(model.has(FeatureSet::Gaps));
  const auto test_indices = model.description()
                                .at("data")
                                .at("datasets")
                                .at(0)
                                .at("test_indices")
                                .get<std::vector<long long>>();
  Eigen::MatrixXd raw(static_cast<Eigen::Index>(test_indices.size()), t.gap_features.cols());
  std::vector<int> truth;
  for (int r = 0; r < t.rows(); ++r) {
    const auto row = static_cast<std::size_t>(r);
    if (std::find(test_indices.begin(), test_indices.end(), t.index[row]) == test_indices.end()) {
      continue;
    }
    raw.row(static_cast<Eigen::Index>(truth.size())) = t.gap_features.row(r);
    truth.push_back(t.gap_class[row]);
  }
  ASSERT_EQ(truth.size(), test_indices.size());
  for (ClassifierKind kind : kClassifierKinds) {
    const std::vector<int> predicted = model.classify(kind, FeatureSet::Gaps, raw);
    long long right = 0;
    for (std::size_t i = 0; i < truth.size(); ++i) right += predicted[i] == truth[i] ? 1 : 0;
    const json& m = report_metrics_.at("gap_classifiers").at(std::string(classifier_name(kind)));
    EXPECT_DOUBLE_EQ(double(right) / double(truth.size()), m.at("test_accuracy").get<double>());
    EXPECT_DOUBLE_EQ(m.at("completable_share").get<double>(), m.at("test_accuracy").get<double>());
  }
}

TEST_F(Trained, StrategyModelIsSavedWithAChecksumAndLoadsBack) {
  const json m = json::parse(testing::read_text(model_dir() + "/metrics.json"));
  const json& s = m.at("strategy");
  EXPECT_GT(s.at("train_rows").get<int>(), 0);
  EXPECT_GT(s.at("distinct_strategies").get<int>(), 0);
  EXPECT_GE(s.at("test_exact_top5").get<double>(), s.at("test_exact_top1").get<double>());
  const json d = json::parse(testing::read_text(model_dir() + "/model.json"));
  EXPECT_TRUE(d.at("files").contains(std::string(kStrategyFile)));
  const Model model = Model::load(model_dir());
  const auto strategy = model.strategy();
  const StrategyModel again = StrategyModel::from_json(
      json::parse(testing::read_text(model_dir() + "/" + std::string(kStrategyFile))));
  const Scenario scene = ScenarioSampler(Config{}, 3).sample(0);
  EXPECT_EQ(strategy->predict(scene, 5), again.predict(scene, 5));
  EXPECT_FALSE(strategy->predict(scene, 5).empty());
  EXPECT_NO_THROW((void)planner::make_planner("strategy-qp", Config{}, model_dir()));

  const fs::path copy = root_ / "strategy_damaged";
  fs::remove_all(copy);
  fs::copy(model_dir(), copy, fs::copy_options::recursive);
  testing::write_text((copy / std::string(kStrategyFile)).string(), again.to_json().dump(1));
  EXPECT_THROW((void)Model::load(copy.string()), InputError);
}

// A model trained before strategy-qp still serves mlp-miqp; only strategy-qp
// is refused, and says why.
TEST_F(Trained, AModelWithoutAStrategyServesMlpMiqpOnly) {
  const fs::path copy = root_ / "no_strategy";
  fs::remove_all(copy);
  fs::copy(model_dir(), copy, fs::copy_options::recursive);
  fs::remove(copy / std::string(kStrategyFile));
  json d = json::parse(testing::read_text((copy / "model.json").string()));
  d.erase("strategy");
  d["files"].erase(std::string(kStrategyFile));
  testing::write_text((copy / "model.json").string(), d.dump());
  EXPECT_NO_THROW((void)Model::load(copy.string()));
  EXPECT_NO_THROW((void)planner::make_planner("mlp-miqp", Config{}, copy.string()));
  try {
    (void)planner::make_planner("strategy-qp", Config{}, copy.string());
    ADD_FAILURE() << "strategy-qp was built without a strategy model";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("lane-strategy model"), std::string::npos) << e.what();
  }
  EXPECT_THROW((void)planner::make_planner("strategy-qp", Config{}, ""), InputError);
}

TEST_F(Trained, DamagedOrForeignModelsAreRefused) {
  const fs::path copy = root_ / "damaged";
  fs::remove_all(copy);
  fs::copy(model_dir(), copy, fs::copy_options::recursive);
  const fs::path svm = copy / "classifiers" / "plain" / "svm.libsvm";
  fs::resize_file(svm, fs::file_size(svm) / 2);
  EXPECT_THROW((void)Model::load(copy.string()), InputError);
  const auto info = testing::run_cli("model-info --model " + copy.string());
  EXPECT_EQ(info.exit_code, 2) << info.output;
  EXPECT_NE(info.output.find("checksum"), std::string::npos) << info.output;
  const auto good = testing::run_cli("model-info --model " + model_dir());
  EXPECT_EQ(good.exit_code, 0) << good.output;

  fs::remove_all(copy);
  fs::copy(model_dir(), copy, fs::copy_options::recursive);
  json d = json::parse(testing::read_text((copy / "model.json").string()));
  d["format"] = "lanechange.model/0";
  testing::write_text((copy / "model.json").string(), d.dump());
  EXPECT_THROW((void)Model::load(copy.string()), InputError);

  ModelRequirements wrong_features;
  wrong_features.classifier_features = {"ego_x0", "ego_v0"};
  EXPECT_THROW((void)Model::load(model_dir(), wrong_features), InputError);
  ModelRequirements other_config;
  other_config.expert_config = json{{"expert", {{"steps", 99}}}};
  EXPECT_THROW((void)Model::load(model_dir(), other_config), InputError);
  ModelRequirements fitting;
  fitting.classifier_features = load_learning_data({data_dir()}).classifier_features;
  EXPECT_NO_THROW((void)Model::load(model_dir(), fitting));
}

TEST_F(Trained, CliTrainsRepeatablyWithPicturesAndBadInputLeavesTheModelAlone) {
  const std::string out = (root_ / "cli_model").string();
  const auto run = testing::run_cli(train_args(out + "/"));  // a trailing slash is the same dir
  ASSERT_EQ(run.exit_code, 0) << run.output;
  EXPECT_NE(run.output.find("svm (plain)"), std::string::npos) << run.output;
  const json m = json::parse(testing::read_text(out + "/metrics.json"));
  for (ClassifierKind kind : kClassifierKinds) {
    const std::string name(classifier_name(kind));
    EXPECT_EQ(m["classifiers"][name]["test_accuracy"],
              report_metrics_["classifiers"][name]["test_accuracy"])
        << name;
  }
  EXPECT_EQ(m["network"]["test_rmse"], report_metrics_["network"]["test_rmse"]);
  for (const char* png :
       {"loss.png", "confusion_plain_svm.png", "confusion_with_behavior_knn.png"}) {
    EXPECT_TRUE(fs::exists(fs::path(out) / png)) << png;
  }
  const auto before = snapshot(out);
  const auto bad =
      testing::run_cli("train --data " + (root_ / "nothing").string() + " --out " + out);
  EXPECT_EQ(bad.exit_code, 2) << bad.output;
  EXPECT_EQ(snapshot(out), before);

  const fs::path foreign = root_ / "foreign";
  fs::create_directories(foreign);
  testing::write_text((foreign / "keep.txt").string(), "mine");
  const auto refused = testing::run_cli(train_args(foreign.string()));
  EXPECT_EQ(refused.exit_code, 2) << refused.output;
  EXPECT_EQ(testing::read_text((foreign / "keep.txt").string()), "mine");
}

// A network wider than the paper's: trained from the command line, loaded
// at its width, kept by a retrain; an impossible width is an input error.
TEST_F(Trained, AWiderNetworkIsTrainedLoadedAndKeptByARetrain) {
  const std::string out = (root_ / "wide_model").string();
  const auto run = testing::run_cli(train_args(out) + " --network-width 16");
  ASSERT_EQ(run.exit_code, 0) << run.output;
  EXPECT_EQ(Model::load(out).policy().width(), 16);
  const json config = json::parse(testing::read_text(out + "/model.json"))["config"];
  EXPECT_EQ(config["network"]["hidden_width"], 16);

  RetrainOptions o = quick_retrain(out, (root_ / "wide_retrained").string());
  (void)retrain_network(o);
  EXPECT_EQ(Model::load(o.out_dir).policy().width(), 16);

  const auto before = snapshot(out);
  const auto bad = testing::run_cli(train_args(out) + " --network-width 65");
  EXPECT_EQ(bad.exit_code, 2) << bad.output;
  EXPECT_NE(bad.output.find("--network-width"), std::string::npos) << bad.output;
  EXPECT_EQ(snapshot(out), before);
}

// A network that drives to a chosen gap: trained on the data sets' gap
// inputs, kept by a retrain, loaded by mlp-miqp for a scene of any number of
// cars; data without those columns is refused by name, the model left alone.
TEST_F(Trained, AGapNetworkReadsTheGapAndDataWithoutItIsRefused) {
  const std::string out = (root_ / "gap_model").string();
  const auto run = testing::run_cli(train_args(out) + " --network-inputs gap");
  ASSERT_EQ(run.exit_code, 0) << run.output;
  const json model = json::parse(testing::read_text(out + "/model.json"));
  const auto inputs = model["features"]["action_inputs"].get<std::vector<std::string>>();
  const json manifest = json::parse(testing::read_text(data_dir() + "/manifest.json"));
  EXPECT_EQ(inputs, manifest["columns"]["gap_action_inputs"].get<std::vector<std::string>>());
  EXPECT_EQ(model["config"]["network"]["inputs"], "gap");
  EXPECT_EQ(Model::load(out).policy().inputs(), static_cast<int>(inputs.size()));

  RetrainOptions o = quick_retrain(out, (root_ / "gap_retrained").string());
  (void)retrain_network(o);
  const json retrained = json::parse(testing::read_text(o.out_dir + "/model.json"));
  EXPECT_EQ(retrained["features"]["action_inputs"], model["features"]["action_inputs"]);

  const Scenario twelve = testing::dense_scenario(10);
  const auto planner = planner::make_planner("mlp-miqp", Config{}, out);
  EXPECT_NE(planner->start(twelve), nullptr);

  const fs::path old_data = root_ / "data_without_gap_inputs";
  fs::remove_all(old_data);
  fs::copy(data_dir(), old_data, fs::copy_options::recursive);
  json old_manifest = manifest;
  old_manifest["columns"].erase("gap_action_inputs");
  testing::write_text((old_data / "manifest.json").string(), old_manifest.dump());
  const auto before = snapshot(out);
  const auto refused = testing::run_cli("train --quick --network-inputs gap --data " +
                                        old_data.string() + " --out " + out);
  EXPECT_EQ(refused.exit_code, 2) << refused.output;
  EXPECT_NE(refused.output.find("gap_action_inputs"), std::string::npos) << refused.output;
  EXPECT_EQ(snapshot(out), before);
}

// An ensemble: its first network is the one-network model's (the same seed,
// though trained beside another on two threads), the others differ, the
// policy acts as their mean, and DAgger's retrain keeps the ensemble's size.
TEST_F(Trained, AnEnsembleAveragesItsNetworksAndARetrainKeepsItsSize) {
  const std::string out = (root_ / "ensemble_model").string();
  const auto run = testing::run_cli(train_args(out) + " --networks 3");
  ASSERT_EQ(run.exit_code, 0) << run.output;
  const Model model = Model::load(out);
  ASSERT_EQ(model.policy().members(), 3);
  const json members = json::parse(testing::read_text(out + "/policy.json"))["average_of"];
  ASSERT_EQ(members.size(), 3U);
  EXPECT_EQ(members[0], json::parse(testing::read_text(model_dir() + "/policy.json")));
  EXPECT_NE(members[1]["layers"], members[0]["layers"]);
  EXPECT_NE(members[2]["layers"], members[1]["layers"]);
  for (const char* file : {"network.dlib", "network-1.dlib", "network-2.dlib"}) {
    EXPECT_TRUE(fs::exists(fs::path(out) / file)) << file;
  }
  EXPECT_EQ(json::parse(testing::read_text(out + "/metrics.json"))["network"]["ensemble"].size(),
            3U);

  const LearningData data = load_learning_data({data_dir()});
  for (int r = 0; r < 5; ++r) {
    const Observation obs = data.samples.inputs.row(r).transpose();
    Eigen::Vector2d mean = Eigen::Vector2d::Zero();
    for (const json& m : members) mean += Policy(PolicyWeights::from_json(m)).act(obs) / 3.0;
    EXPECT_LT((model.policy().act(obs) - mean).norm(), 1e-9) << r;
  }

  RetrainOptions o = quick_retrain(out, (root_ / "ensemble_retrained").string());
  (void)retrain_network(o);
  EXPECT_EQ(Model::load(o.out_dir).policy().members(), 3);
  o.out_dir = (root_ / "ensemble_fine_tuned").string();
  o.warm_start = out;
  EXPECT_THROW((void)retrain_network(o), InputError);
  EXPECT_FALSE(fs::exists(o.out_dir));

  // A base whose model.json names an impossible ensemble is refused, not trained.
  const fs::path edited = root_ / "ensemble_edited";
  fs::copy(out, edited, fs::copy_options::recursive);
  json description = json::parse(testing::read_text((edited / "model.json").string()));
  description["config"]["network"]["networks"] = 0;
  testing::write_text((edited / "model.json").string(), description.dump());
  RetrainOptions from_edited = quick_retrain(edited.string(), (root_ / "edited_out").string());
  EXPECT_THROW((void)retrain_network(from_edited), InputError);
  EXPECT_FALSE(fs::exists(from_edited.out_dir));

  const auto before = snapshot(out);
  const auto bad = testing::run_cli(train_args(out) + " --networks 0");
  EXPECT_EQ(bad.exit_code, 2) << bad.output;
  EXPECT_NE(bad.output.find("--networks"), std::string::npos) << bad.output;
  EXPECT_EQ(snapshot(out), before);
}

}  // namespace
}  // namespace lanechange::learn
