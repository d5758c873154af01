// `train` (docs/learning.md).
#include "learn_commands.hpp"

#include <iostream>

#include "lanechange/dagger/dagger.hpp"
#include "lanechange/error.hpp"
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
  int network_width = learn::kHiddenWidth;
  int networks = 1;
  bool plain_naive_bayes = false;
  bool quick = false;
  bool no_plots = false;
  // DAgger (docs/strategy.md); off unless --dagger is given.
  dagger::DaggerOptions dagger;
  std::string dagger_rollout = "network";
  CLI::Option* dagger_rounds = nullptr;
  std::vector<CLI::Option*> dagger_only;
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

learn::TrainOptions train_options(const TrainArgs& a) {
  learn::TrainOptions o;
  o.data_dirs = a.data;
  o.out_dir = a.out;
  o.seed = a.seed;
  o.test_share = a.test_share;
  o.jobs = a.jobs;
  o.network.max_epochs = a.max_epochs;
  o.network.hidden_width = a.network_width;
  o.network.networks = a.networks;
  o.search.naive_bayes_kernel = !a.plain_naive_bayes;
  o.search.quick = a.quick;
  o.plots = !a.no_plots;
  o.progress = &std::cerr;
  return o;
}

void run_dagger(const TrainArgs& a, const Config& config) {
  dagger::DaggerOptions o = a.dagger;
  o.rollout = dagger::parse_rollout(a.dagger_rollout, "--dagger-rollout");
  o.train = train_options(a);
  o.config = config;
  o.jobs = a.jobs;
  if (o.work_dir.empty()) o.work_dir = a.out + "-dagger";
  const dagger::DaggerReport report = dagger::run(o, &std::cerr);
  std::cout << dagger::markdown_table(report);
  std::cerr << "dagger: tables in " << o.work_dir << "/dagger.csv and dagger.md; the last round's "
            << "model is at " << a.out << "\n";
}

void run_train(const TrainArgs& a, const ConfigSource& config) {
  if (a.dagger_rounds->count() > 0) return run_dagger(a, config());
  for (const CLI::Option* option : a.dagger_only) {
    if (option->count() > 0) throw InputError(option->get_name(), "only goes with --dagger R");
  }
  const learn::TrainReport report = learn::train_models(train_options(a));
  std::cerr << "trained in " << report.wall_s << " s\n";
}

void add_dagger_options(CLI::App& cmd, TrainArgs& a) {
  dagger::DaggerOptions& d = a.dagger;
  a.dagger_rounds =
      cmd.add_option("--dagger", d.rounds, "DAgger rounds after training (docs/strategy.md)");
  a.dagger_only = {
      cmd.add_option("--dagger-dir", d.work_dir,
                     "DAgger's rounds, labels and tables (default: OUT-dagger; rerun to resume)"),
      cmd.add_option("--dagger-scenes", d.scenes, "Training scenes rolled out per round"),
      cmd.add_option("--dagger-seed", d.scene_seed, "Sampler seed of those scenes"),
      cmd.add_option("--dagger-stride", d.stride, "The expert labels every k-th step"),
      cmd.add_option("--dagger-label-nodes", d.label_nodes,
                     "Nodes kept of each expert plan, from the visited state (0: all)"),
      cmd.add_option("--dagger-eval-count", d.eval_count, "Held-out scenes per evaluation"),
      cmd.add_option("--dagger-eval-seed", d.eval_seed, "Sampler seed of the held-out scenes"),
      cmd.add_flag("--dagger-every-scene", d.every_scene,
                   "Roll out also on scenes the classifier refuses (the first version)"),
      cmd.add_option("--dagger-rollout", a.dagger_rollout,
                     "Who drives the labelled rollouts: network (DAgger) or gated (mlp-miqp, "
                     "labels up to the take-over: HG-DAgger)"),
      cmd.add_option("--dagger-past-takeover", d.past_takeover_s,
                     "Gated: seconds of the expert's recovery after the take-over, labelled"),
      cmd.add_flag("--dagger-label-lookahead", d.label_lookahead,
                   "Gated: label the states of the look-ahead that failed the check"),
      cmd.add_flag("--dagger-fixed-strategy", d.fixed_strategy,
                   "Label with the lane modes of the expert's plan from the scene's start fixed"),
      cmd.add_option("--dagger-learning-rate", d.retrain_learning_rate,
                     "Adam's learning rate in the retrains (0: round 0's)"),
      cmd.add_option("--dagger-beta", d.beta,
                     "Network rollouts: round r lets the expert act at each step with "
                     "probability beta^r (Ross et al.'s mixing; 0: the network alone)"),
      cmd.add_flag("--dagger-fine-tune", d.fine_tune,
                   "Each retrain starts from the last round's network and its standardizers"),
      cmd.add_flag("--dagger-average", d.average,
                   "Round r's policy is the mean action of the networks of rounds 0..r"),
      cmd.add_flag("--dagger-validate-all", d.validate_on_dagger,
                   "Early stopping of a retrain also on DAgger rows (the first version)"),
      cmd.add_option("--dagger-candidates", d.candidates,
                     "Retrains per round (network seeds 0..K-1); the fewest take-overs on the "
                     "selection scenes wins (1: no selection)"),
      cmd.add_option("--dagger-select-count", d.select_count,
                     "Selection scenes, drawn like the training scenes"),
      cmd.add_option("--dagger-select-seed", d.select_seed,
                     "Sampler seed of the selection scenes (not the held-out ones)")};
  for (CLI::Option* option : a.dagger_only) option->capture_default_str();
}

}  // namespace

void add_train(CLI::App& app, const ConfigSource& config) {
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
  cmd->add_option("--network-width", args.network_width,
                  "Neurons in each of the network's 10 hidden layers (the paper's: 10)")
      ->check(CLI::Range(1, learn::kMaxHiddenWidth));
  cmd->add_option("--networks", args.networks,
                  "Action networks trained from their own seeds; the policy acts as their mean "
                  "(an ensemble; DAgger's rounds keep the number)")
      ->check(CLI::Range(1, learn::kMaxNetworks));
  cmd->add_flag("--plain-naive-bayes", args.plain_naive_bayes,
                "One normal per feature and class instead of kernel densities");
  cmd->add_flag("--quick", args.quick, "Smaller hyperparameter grids (tests, smoke runs)");
  cmd->add_flag("--no-plots", args.no_plots, "Skip the PNGs (no gnuplot needed)");
  add_dagger_options(*cmd, args);
  cmd->callback([config] { run_train(args, config); });
}

void add_model_info(CLI::App& app) {
  auto* cmd = app.add_subcommand("model-info", "Load a trained model (checks it) and summarise it");
  static std::string dir;
  cmd->add_option("dir", dir, "Model directory")->required();
  cmd->callback([] { print_model(learn::Model::load(dir), dir); });
}

}  // namespace lanechange::app
