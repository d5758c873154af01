// `experiments` (docs/experiments.md).
#include <unistd.h>

#include <iostream>

#include "commands.hpp"
#include "lanechange/experiments/experiments.hpp"
#include "team.hpp"

namespace lanechange::app {

namespace {

struct ExperimentsArgs {
  experiments::ExperimentOptions options;
  std::string scale = "small";
  std::string planners;
  bool no_figures = false;
};

void run_all(ExperimentsArgs& a, const Config& config) {
  experiments::ExperimentOptions& o = a.options;
  o.config = config;
  o.scale = experiments::scale_from_string(a.scale, "--scale");
  o.planners = planner_list(a.planners);
  o.figures = !a.no_figures;
  const auto team = make_team();
  o.team = team.get();
  o.progress = &std::cerr;
  o.progress_on_terminal = ::isatty(STDERR_FILENO) != 0;
  run_on_team(*team, [&] {
    const auto report = experiments::run_experiments(o);
    if (team->rank() != 0) return;
    std::cerr << "experiments done in " << report.wall_s << " s\n";
    std::cout << "report: " << report.report_md << "\n        " << report.report_html << "\n";
  });
}

}  // namespace

void add_experiments(CLI::App& app, const ConfigSource& config) {
  auto* cmd = app.add_subcommand(
      "experiments",
      "Run the paper's experiments end to end and write report.md and report.html (resumable)");
  auto a = make_args<ExperimentsArgs>();
  experiments::ExperimentOptions& o = a->options;
  cmd->add_option("--out", o.out_dir, "Output directory; rerun the command to resume")->required();
  cmd->add_option("--scale", a->scale, "tiny, small (15 min on 2 cores) or paper");
  cmd->add_option("--eval-count", o.eval_count,
                  "Closed-loop scenarios per behavior (default: the scale's; paper: 500)")
      ->check(CLI::NonNegativeNumber);
  add_planner_option(*cmd, a->planners,
                     "Planners of Tables II and III, comma-separated (default: all)");
  cmd->add_option("--jobs", o.jobs, "Worker threads (default: all cores)")
      ->check(CLI::NonNegativeNumber);
  cmd->add_flag("--no-figures", a->no_figures, "Skip the PNGs (no gnuplot needed)");
  cmd->add_option("--commonroad", o.commonroad_dir,
                  "CommonRoad interactive scenario folders to run in SUMO beside the highway");
  cmd->callback([a, config] { run_all(*a, config()); });
}

}  // namespace lanechange::app
