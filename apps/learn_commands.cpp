// `train`, `dagger` and `model-info` (docs/learning.md, docs/strategy.md).
#include <iostream>

#include "commands.hpp"
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
  std::string network_inputs = "paper";
  bool plain_naive_bayes = false;
  bool quick = false;
  bool no_plots = false;
};

struct DaggerArgs {
  TrainArgs train;
  dagger::DaggerOptions dagger;
  std::string rollout = "network";
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
  o.network.inputs =
      a.network_inputs == "gap" ? learn::NetworkInputs::Gap : learn::NetworkInputs::Paper;
  o.search.naive_bayes_kernel = !a.plain_naive_bayes;
  o.search.quick = a.quick;
  o.plots = !a.no_plots;
  o.progress = &std::cerr;
  return o;
}

void run_dagger(const DaggerArgs& a, const Config& config) {
  dagger::DaggerOptions o = a.dagger;
  o.rollout = dagger::parse_rollout(a.rollout, "--rollout");
  o.train = train_options(a.train);
  o.config = config;
  o.jobs = a.train.jobs;
  if (o.work_dir.empty()) o.work_dir = a.train.out + "-dagger";
  const dagger::DaggerReport report = dagger::run(o, &std::cerr);
  std::cout << dagger::markdown_table(report);
  std::cerr << "dagger: tables in " << o.work_dir << "/dagger.csv and dagger.md; the last round's "
            << "model is at " << a.train.out << "\n";
}

// The options of a training run, shared by train and dagger (its round 0
// and retrains).
void add_training_options(CLI::App& cmd, TrainArgs& a) {
  cmd.add_option("--data", a.data, "Data set directory (repeat for several)")->required();
  cmd.add_option("--out", a.out, "Model directory (replaced atomically)")->required();
  cmd.add_option("--seed", a.seed, "Seed of the split, folds and network");
  cmd.add_option("--test-share", a.test_share, "Share of scenarios held out for testing")
      ->check(CLI::Range(0.0, 1.0));
  cmd.add_option("--jobs", a.jobs, "Threads for cross-validation (default: all cores)")
      ->check(CLI::Range(0, 1024));
  cmd.add_option("--max-epochs", a.max_epochs, "Upper bound on the network's epochs")
      ->check(CLI::Range(1, 100000));
  cmd.add_option("--network-width", a.network_width,
                 "Neurons in each of the network's 10 hidden layers (the paper's: 10)")
      ->check(CLI::Range(1, learn::kMaxHiddenWidth));
  cmd.add_option("--networks", a.networks,
                 "Action networks trained from their own seeds; the policy acts as their mean "
                 "(an ensemble; DAgger's rounds keep the number)")
      ->check(CLI::Range(1, learn::kMaxNetworks));
  cmd.add_option("--network-inputs", a.network_inputs,
                 "What the network reads: paper (the scene's three cars by role) or gap (the "
                 "ego and the gap it drives to, any number of cars; data of format 4)")
      ->check(CLI::IsMember({"paper", "gap"}));
  cmd.add_flag("--plain-naive-bayes", a.plain_naive_bayes,
               "One normal per feature and class instead of kernel densities");
  cmd.add_flag("--quick", a.quick, "Smaller hyperparameter grids (tests, smoke runs)");
  cmd.add_flag("--no-plots", a.no_plots, "Skip the PNGs (no gnuplot needed)");
}

void add_dagger_options(CLI::App& cmd, DaggerArgs& a) {
  dagger::DaggerOptions& d = a.dagger;
  cmd.add_option("--rounds", d.rounds, "DAgger rounds after round 0's training")->required();
  cmd.add_option("--dir", d.work_dir,
                 "The rounds, labels and tables (default: OUT-dagger; rerun to resume)");
  cmd.add_option("--scenes", d.scenes, "Training scenes rolled out per round");
  cmd.add_option("--scene-seed", d.scene_seed, "Sampler seed of those scenes");
  cmd.add_option("--stride", d.stride, "The expert labels every k-th step");
  cmd.add_option("--label-nodes", d.label_nodes,
                 "Nodes kept of each expert plan, from the visited state (0: all)");
  cmd.add_option("--eval-count", d.eval_count, "Held-out scenes per evaluation");
  cmd.add_option("--eval-seed", d.eval_seed, "Sampler seed of the held-out scenes");
  cmd.add_option("--rollout", a.rollout,
                 "Who drives the labelled rollouts: network (DAgger) or gated (mlp-miqp, "
                 "labels up to the take-over: HG-DAgger)");
  cmd.add_option("--past-takeover", d.past_takeover_s,
                 "Gated: seconds of the expert's recovery after the take-over, labelled");
  cmd.add_flag("--label-lookahead", d.label_lookahead,
               "Gated: label the states of the look-ahead that failed the check");
  cmd.add_flag("--fixed-strategy", d.fixed_strategy,
               "Label with the lane modes of the expert's plan from the scene's start fixed");
  cmd.add_option("--learning-rate", d.retrain_learning_rate,
                 "Adam's learning rate in the retrains (0: round 0's)");
  cmd.add_option("--beta", d.beta,
                 "Network rollouts: round r lets the expert act at each step with "
                 "probability beta^r (Ross et al.'s mixing; 0: the network alone)");
  cmd.add_flag("--fine-tune", d.fine_tune,
               "Each retrain starts from the last round's network and its standardizers");
  cmd.add_flag("--average", d.average,
               "Round r's policy is the mean action of the networks of rounds 0..r");
  cmd.add_option("--candidates", d.candidates,
                 "Retrains per round (network seeds 0..K-1); the fewest take-overs on the "
                 "selection scenes wins (1: no selection)");
  cmd.add_option("--select-count", d.select_count,
                 "Selection scenes, drawn like the training scenes");
  cmd.add_option("--select-seed", d.select_seed,
                 "Sampler seed of the selection scenes (not the held-out ones)");
  for (CLI::Option* option : cmd.get_options()) option->capture_default_str();
}

}  // namespace

void add_train(CLI::App& app) {
  auto* cmd = app.add_subcommand(
      "train", "Train the five classifiers and the action network on expert data sets");
  auto a = make_args<TrainArgs>();
  add_training_options(*cmd, *a);
  // The config travels in the data sets: train takes none.
  cmd->callback([a] {
    const learn::TrainReport report = learn::train_models(train_options(*a));
    std::cerr << "trained in " << report.wall_s << " s\n";
  });
}

void add_dagger(CLI::App& app, const ConfigSource& config) {
  auto* cmd = app.add_subcommand(
      "dagger",
      "Train, then DAgger rounds: roll the learner out, label with the expert, retrain "
      "(resumable; docs/dagger.md)");
  auto a = make_args<DaggerArgs>();
  add_training_options(*cmd, a->train);
  add_dagger_options(*cmd, *a);
  cmd->callback([a, config] { run_dagger(*a, config()); });
}

void add_model_info(CLI::App& app) {
  auto* cmd = app.add_subcommand("model-info", "Load a trained model (checks it) and summarise it");
  auto dir = make_args<std::string>();
  cmd->add_option("--model", *dir, "Model directory")->required();
  cmd->callback([dir] { print_model(learn::Model::load(*dir), *dir); });
}

}  // namespace lanechange::app
