#include "experiments_command.hpp"

#include <unistd.h>

#include <iostream>

#include "lanechange/experiments/experiments.hpp"
#include "planner_list.hpp"
#include "team.hpp"

namespace lanechange::app {

void add_experiments(CLI::App& app, const ConfigSource& config_source) {
  auto* cmd = app.add_subcommand(
      "experiments",
      "Run the paper's experiments end to end and write report.md and report.html (resumable)");
  static experiments::ExperimentOptions o;
  static std::string scale = "small";
  static std::string planners;
  static bool no_figures = false;
  cmd->add_option("--out", o.out_dir, "Output directory; rerun the command to resume")->required();
  cmd->add_option("--scale", scale, "tiny, small (15 min on 2 cores) or paper");
  cmd->add_option("--eval-count", o.eval_count,
                  "Closed-loop scenarios per behavior (default: the scale's; paper: 500)")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--planners", planners,
                  "Planners of Tables II and III, comma-separated (default: all)");
  cmd->add_option("--jobs", o.jobs, "Worker threads (default: all cores)")
      ->check(CLI::NonNegativeNumber);
  cmd->add_flag("--no-figures", no_figures, "Skip the PNGs (no gnuplot needed)");
  cmd->callback([config_source] {
    o.config = config_source();
    o.scale = experiments::scale_from_string(scale, "--scale");
    o.planners = planner_list(planners);
    o.figures = !no_figures;
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
  });
}

}  // namespace lanechange::app
