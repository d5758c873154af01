// Studies: crosscheck, label-study, strategy-study, authors-study. Each is a
// library function in src/studies; these commands only read options.
#include <cstdio>
#include <fstream>
#include <iostream>
#include <stdexcept>

#include "commands.hpp"
#include "lanechange/error.hpp"
#include "lanechange/studies/authors.hpp"
#include "lanechange/studies/label_study.hpp"
#include "lanechange/studies/solver_crosscheck.hpp"
#include "lanechange/studies/strategy_study.hpp"

namespace lanechange::app {

namespace {

struct CrossCheckArgs {
  studies::CrossCheckOptions options;
  std::string out_path;
};

struct StrategyStudyArgs {
  studies::StrategyStudyOptions options;
  std::string behavior;
  std::string out_path;
};

struct AuthorsStudyArgs {
  studies::AuthorsStudyOptions options;
  int jobs = 1;
  double time_limit = 60.0;
};

void crosscheck(CrossCheckArgs& a, const Config& config) {
  a.options.config = config;
  std::ofstream out;
  if (!a.out_path.empty()) {
    out.open(a.out_path);
    if (!out) throw InputError("--out", a.out_path + " cannot be written");
    a.options.cases = &out;
  }
  a.options.progress = &std::cerr;
  const studies::CrossCheckReport report = studies::run_crosscheck(a.options);
  std::cout << report.agreed << " of " << report.total << " agree\n";
  if (report.agreed != report.total) throw std::runtime_error("the solvers disagree");
}

void strategy_study(StrategyStudyArgs& a, const Config& config) {
  a.options.config = config;
  a.options.behavior = behavior_option(a.behavior);
  a.options.progress = &std::cerr;
  const nlohmann::json study = studies::run_strategy_study(a.options);
  if (!a.out_path.empty()) {
    std::ofstream out(a.out_path);
    out << study.dump(2) << "\n";
    if (!out) throw InputError("--out", a.out_path + " cannot be written");
  }
  std::cout << studies::strategy_study_markdown(study);
}

void authors_study(AuthorsStudyArgs& a, const Config& config) {
  a.options.config = config;
  a.options.settings.threads = a.jobs;
  a.options.settings.limits.time_limit_s = a.time_limit;
  a.options.progress = [](std::size_t done, std::size_t total) {
    if (done % 50 == 0 || done == total) std::fprintf(stderr, "%zu/%zu\n", done, total);
  };
  std::cout << studies::run_authors_study(a.options);
}

}  // namespace

void add_crosscheck(CLI::App& app, const ConfigSource& config) {
  auto* cmd = app.add_subcommand(
      "crosscheck", "Solve the same linearized MIQPs with the fast and the reference solver");
  auto a = make_args<CrossCheckArgs>();
  studies::CrossCheckOptions& o = a->options;
  cmd->add_option("--count", o.count, "How many sampled scenarios")
      ->check(CLI::Range(1LL, 100000LL));
  cmd->add_option("--seed", o.seed, "Sampler seed");
  cmd->add_option("--first", o.first, "Index of the first scenario");
  cmd->add_option("--steps", o.steps, "Override N (fewer steps make the reference faster)");
  cmd->add_option("--tolerance", o.tolerance, "Largest relative objective difference");
  cmd->add_flag("--every-gap", o.every_gap,
                "One MIQP per gap of each scene's target lane (each from the warm start aimed "
                "into it), not Eq. 1's gap alone; with dense scenes (sampler.target_lane_cars)");
  cmd->add_option("--out", a->out_path, "JSON lines file, one case per line");
  cmd->add_option("--replay", o.replay_path,
                  "Re-solve only the fast side of the cases in an earlier --out file and compare "
                  "with its stored reference results (seconds instead of hours); each case "
                  "uses the config stored with it, not --config or --preset")
      ->check(CLI::ExistingFile);
  cmd->callback([a, config] { crosscheck(*a, config()); });
}

void add_label_study(CLI::App& app, const ConfigSource& config) {
  auto* cmd =
      app.add_subcommand("label-study", "Label shares of expert plans under several tolerances");
  auto o = make_args<studies::LabelStudyOptions>();
  cmd->add_option("--count", o->count, "How many sampled scenarios")
      ->check(CLI::Range(1LL, 1000000LL));
  cmd->add_option("--seed", o->seed, "Sampler seed");
  cmd->callback([o, config] {
    o->config = config();
    std::cout << studies::run_label_study(*o);
  });
}

void add_strategy_study(CLI::App& app, const ConfigSource& config) {
  auto* cmd = app.add_subcommand(
      "strategy-study",
      "strategy-qp against the exact expert on sampled scenes, open loop (docs/strategy.md)");
  auto a = make_args<StrategyStudyArgs>();
  studies::StrategyStudyOptions& o = a->options;
  cmd->add_option("--model", o.model_dir, "Model directory (lanechange train)")->required();
  cmd->add_option("--count", o.count, "How many sampled scenes")->check(CLI::PositiveNumber);
  cmd->add_option("--seed", o.seed, "Sampler seed (one the training data did not use)");
  add_behavior_option(*cmd, a->behavior);
  cmd->add_option("--out", a->out_path, "Also write the numbers as JSON to this file");
  cmd->callback([a, config] { strategy_study(*a, config()); });
}

void add_authors_study(CLI::App& app, const ConfigSource& config) {
  auto* cmd = app.add_subcommand(
      "authors-study",
      "Plan every record of the authors' published solutions and compare (use --preset authors; "
      "docs/authors_comparison.md)");
  auto a = make_args<AuthorsStudyArgs>();
  cmd->add_option("--records", a->options.records_path, "The authors' records (JSON lines)")
      ->required()
      ->check(CLI::ExistingFile);
  cmd->add_option("--out", a->options.out_dir,
                  "Output directory: comparisons.jsonl, summary.json, summary.md")
      ->required();
  cmd->add_option("--jobs", a->jobs, "Worker threads")->check(CLI::Range(1, 1024));
  cmd->add_option("--time-limit", a->time_limit, "Seconds per plan")->check(CLI::PositiveNumber);
  cmd->callback([a, config] { authors_study(*a, config()); });
}

}  // namespace lanechange::app
