// `train` (docs/learning.md).
#include "learn_commands.hpp"

#include <iostream>

#include "lanechange/learn/model.hpp"
#include "lanechange/learn/train.hpp"

namespace lanechange::app {

namespace {

struct TrainArgs {
  std::vector<std::string> data;
  std::string out;
  std::uint64_t seed = 1;
  double test_share = 0.2;
  int jobs = 0;
  int max_epochs = learn::NetworkSettings{}.max_epochs;
  bool plain_naive_bayes = false;
  bool quick = false;
  bool no_plots = false;
};

// The test accuracies of a loaded model, one line per classifier.
void print_model(const learn::Model& model, const std::string& dir) {
  const nlohmann::json& d = model.description();
  std::cout << dir << ": " << d.at("format").get<std::string>() << ", "
            << d.at("data").at("scenarios") << " scenarios from "
            << d.at("data").at("datasets").size() << " data set(s), policy with "
            << model.policy().inputs() << " inputs; every file's checksum verified\n";
  for (const auto& [name, m] : model.metrics().at("classifiers").items()) {
    std::cout << "  " << name << ": test accuracy " << m.at("test_accuracy").get<double>() << "\n";
  }
}

void run_train(const TrainArgs& a) {
  learn::TrainOptions o;
  o.data_dirs = a.data;
  o.out_dir = a.out;
  o.seed = a.seed;
  o.test_share = a.test_share;
  o.jobs = a.jobs;
  o.network.max_epochs = a.max_epochs;
  o.search.naive_bayes_kernel = !a.plain_naive_bayes;
  o.search.quick = a.quick;
  o.plots = !a.no_plots;
  o.progress = &std::cerr;
  const learn::TrainReport report = learn::train_models(o);
  std::cerr << "trained in " << report.wall_s << " s\n";
}

}  // namespace

void add_train(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "train", "Train the five classifiers and the action network on expert data sets");
  static TrainArgs args;
  cmd->add_option("--data", args.data, "Data set directory (repeat for several)")->required();
  cmd->add_option("--out", args.out, "Model directory (replaced atomically)")->required();
  cmd->add_option("--seed", args.seed, "Seed of the split, folds and network");
  cmd->add_option("--test-share", args.test_share, "Share of scenarios held out for testing")
      ->check(CLI::Range(0.0, 1.0));
  cmd->add_option("--jobs", args.jobs, "Threads for cross-validation (default: all cores)")
      ->check(CLI::Range(0, 1024));
  cmd->add_option("--max-epochs", args.max_epochs, "Upper bound on the network's epochs")
      ->check(CLI::Range(1, 100000));
  cmd->add_flag("--plain-naive-bayes", args.plain_naive_bayes,
                "One normal per feature and class instead of kernel densities");
  cmd->add_flag("--quick", args.quick, "Smaller hyperparameter grids (tests, smoke runs)");
  cmd->add_flag("--no-plots", args.no_plots, "Skip the PNGs (no gnuplot needed)");
  cmd->callback([] { run_train(args); });
}

void add_model_info(CLI::App& app) {
  auto* cmd = app.add_subcommand("model-info", "Load a trained model (checks it) and summarise it");
  static std::string dir;
  cmd->add_option("dir", dir, "Model directory")->required();
  cmd->callback([] { print_model(learn::Model::load(dir), dir); });
}

}  // namespace lanechange::app
