#include "sim_commands.hpp"

#include <unistd.h>

#include <fstream>
#include <iostream>

#include "lanechange/baselines/baselines.hpp"
#include "lanechange/error.hpp"
#include "lanechange/planner/strategy_study.hpp"
#include "lanechange/scenario.hpp"
#include "lanechange/sim/evaluate.hpp"
#include "lanechange/sim/simulator.hpp"
#include "lanechange/trajectory.hpp"
#include "planner_list.hpp"
#include "team.hpp"

namespace lanechange::app {

namespace {

std::string planner_help() {
  std::string names;
  for (const auto& name : baselines::planner_names()) {
    if (!names.empty()) names += ", ";
    names += name;
  }
  return names;
}

}  // namespace

void add_simulate(CLI::App& app, const ConfigSource& config_source) {
  auto* cmd = app.add_subcommand("simulate", "Run one closed-loop rollout of a planner");
  static std::string scenario_path;
  static std::string planner_name = "miqp";
  static double duration = 0.0;
  static std::string model_dir;
  static std::string out_path = "-";
  cmd->add_option("--scenario", scenario_path, "Scenario JSON file")->required();
  cmd->add_option("--planner", planner_name, "Planner: " + planner_help());
  cmd->add_option("--model", model_dir,
                  "Model directory (lanechange train), for mlp-miqp and strategy-qp");
  cmd->add_option("--duration", duration,
                  "Seconds to simulate (default: the horizon plus closed_loop.settle_time)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--out", out_path, "Rollout JSON file, or - for standard output");
  cmd->callback([config_source] {
    const Config config = config_source();
    const Scenario scenario = load_scenario(scenario_path, config);
    const auto planner = baselines::make_planner(planner_name, config, model_dir);
    const sim::Rollout rollout = sim::simulate(scenario, *planner, config, {duration});
    sim::save_rollout(rollout, out_path);
    const auto& m = rollout.metrics;
    std::cerr << "outcome " << sim::to_string(rollout.outcome)
              << (rollout.trajectory.collision ? " (collision)" : "") << ", "
              << rollout.steps.size() << " steps, median step " << m.median_step_ms << " ms, max "
              << m.max_step_ms << " ms, fallback steps " << m.fallbacks
              << (rollout.reason.empty() ? "" : "; " + rollout.reason) << "\n";
  });
}

void add_evaluate(CLI::App& app, const ConfigSource& config_source) {
  auto* cmd = app.add_subcommand(
      "evaluate", "Closed-loop rollouts of sampled scenarios for one or more planners (resumable)");
  static sim::EvaluateOptions o;
  static std::string behavior = "all";
  static std::string planners = "miqp";
  static int jobs = 0;
  cmd->add_option("--count", o.count, "How many sampled scenarios")->required();
  cmd->add_option("--seed", o.seed, "Sampler seed")->required();
  cmd->add_option("--behavior", behavior, "constant_speed, constant_accel, idm or all");
  cmd->add_option("--planner", planners, "Planner names, comma-separated: " + planner_help());
  cmd->add_option("--model", o.model_dir,
                  "Model directory (lanechange train), for mlp-miqp and strategy-qp");
  cmd->add_option("--out", o.out_dir, "Output directory; rerun the command to resume")->required();
  cmd->add_option("--jobs", jobs, "Worker threads (default: all cores)")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--shard-size", o.shard_size, "Scenarios per shard file");
  cmd->add_option("--duration", o.duration, "Seconds per rollout (default: horizon + settle)");
  cmd->callback([config_source] {
    o.config = config_source();
    o.make_planner = baselines::make_planner;
    o.behavior.reset();
    if (behavior != "all") o.behavior = behavior_from_string(behavior, "--behavior");
    o.planners = planner_list(planners);
    const auto team = make_team();
    sim::EvaluateRun run;
    run.jobs = jobs;
    run.team = team.get();
    if (team->rank() == 0) {
      run.progress = &std::cerr;
      run.progress_on_terminal = ::isatty(STDERR_FILENO) != 0;
    }
    run_on_team(*team, [&] {
      const sim::EvaluateReport r = sim::evaluate(o, run);
      if (team->rank() != 0) return;
      std::cerr << "evaluate: " << r.rollouts << " rollouts on rank 0 in " << r.wall_s << " s ("
                << r.shards_skipped << " of " << r.shards_total
                << " shards were done already or belong to other ranks); see " << o.out_dir
                << "/summary.csv\n";
    });
  });
}

void add_strategy_study(CLI::App& app, const ConfigSource& config_source) {
  auto* cmd = app.add_subcommand(
      "strategy-study",
      "strategy-qp against the exact expert on sampled scenes, open loop (docs/strategy.md)");
  static planner::StrategyStudyOptions o;
  static std::string behavior = "all";
  static std::string out_path;
  cmd->add_option("--model", o.model_dir, "Model directory (lanechange train)")->required();
  cmd->add_option("--count", o.count, "How many sampled scenes")->check(CLI::PositiveNumber);
  cmd->add_option("--seed", o.seed, "Sampler seed (one the training data did not use)");
  cmd->add_option("--behavior", behavior, "constant_speed, constant_accel, idm or all");
  cmd->add_option("--out", out_path, "Also write the numbers as JSON to this file");
  cmd->callback([config_source] {
    o.config = config_source();
    o.behavior.reset();
    if (behavior != "all") o.behavior = behavior_from_string(behavior, "--behavior");
    o.progress = &std::cerr;
    const nlohmann::json study = planner::run_strategy_study(o);
    if (!out_path.empty()) {
      std::ofstream out(out_path);
      out << study.dump(2) << "\n";
      if (!out) throw InputError("--out", out_path + " cannot be written");
    }
    std::cout << planner::strategy_study_markdown(study);
  });
}

}  // namespace lanechange::app
