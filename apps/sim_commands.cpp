#include <unistd.h>

#include <fstream>
#include <iostream>
#include <sstream>

#include "commands.hpp"
#include "lanechange/baselines/baselines.hpp"
#include "lanechange/error.hpp"
#include "lanechange/scenario.hpp"
#include "lanechange/sim/evaluate.hpp"
#include "lanechange/sim/simulator.hpp"
#include "lanechange/sumo/evaluate.hpp"
#include "lanechange/trajectory.hpp"
#include "team.hpp"

namespace lanechange::app {

namespace {

struct SimulateArgs {
  std::string scenario_path;
  std::string planner = "miqp";
  double duration = 0.0;
  std::string model_dir;
  std::string out_path = "-";
};

struct EvaluateArgs {
  sim::EvaluateOptions options;
  std::string sumo_highway;     ///< densities, comma-separated: SUMO episodes instead of scenes
  std::string sumo_commonroad;  ///< a directory of interactive scenario folders
  std::string prediction = "constant_speed";  ///< SUMO episodes: how planners predict SUMO's cars
  bool signal_change = true;                  ///< SUMO episodes: the ego asks SUMO for the change
  bool shard_size_given = false;
  std::string behavior;
  std::string target_lane_cars;
  std::string planners = "miqp";
  int jobs = 0;
};

void simulate_once(const SimulateArgs& a, const Config& config) {
  const Scenario scenario = load_scenario(a.scenario_path, config);
  const auto planner = baselines::make_planner(a.planner, config, a.model_dir);
  const sim::Rollout rollout = sim::simulate(scenario, *planner, config, {a.duration});
  sim::save_rollout(rollout, a.out_path);
  const auto& m = rollout.metrics;
  std::cerr << "outcome " << sim::to_string(rollout.outcome)
            << (rollout.trajectory.collision ? " (collision)" : "") << ", " << rollout.steps.size()
            << " steps, median step " << m.median_step_ms << " ms, max " << m.max_step_ms
            << " ms, fallback steps " << m.fallbacks
            << (rollout.reason.empty() ? "" : "; " + rollout.reason) << "\n";
}

// Runs an evaluation on this process's team (MPI ranks, or alone), with
// progress on rank 0's standard error.
void run_evaluation(int jobs, const std::string& out_dir,
                    const std::function<sim::EvaluateReport(const sim::EvaluateRun&)>& evaluate) {
  const auto team = make_team();
  sim::EvaluateRun run;
  run.jobs = jobs;
  run.team = team.get();
  if (team->rank() == 0) {
    run.progress = &std::cerr;
    run.progress_on_terminal = ::isatty(STDERR_FILENO) != 0;
  }
  run_on_team(*team, [&] {
    const sim::EvaluateReport r = evaluate(run);
    if (team->rank() != 0) return;
    std::cerr << "evaluate: " << r.rollouts << " rollouts on rank 0 in " << r.wall_s << " s ("
              << r.shards_skipped << " of " << r.shards_total
              << " shards were done already or belong to other ranks); see " << out_dir
              << "/summary.csv\n";
  });
}

void evaluate_all(EvaluateArgs& a, const Config& config) {
  sim::EvaluateOptions& o = a.options;
  o.config = config;
  o.make_planner = baselines::make_planner;
  o.behavior = behavior_option(a.behavior);
  o.planners = planner_list(a.planners);
  run_evaluation(a.jobs, o.out_dir,
                 [&o](const sim::EvaluateRun& run) { return sim::evaluate(o, run); });
}

std::vector<double> densities_of(const std::string& list) {
  std::vector<double> out;
  std::stringstream in(list);
  std::string item;
  while (std::getline(in, item, ',')) {
    if (item.empty()) continue;
    std::size_t used = 0;
    double d = 0.0;
    try {
      d = std::stod(item, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used != item.size()) {
      throw InputError("--sumo-highway",
                       "\"" + item + "\" is not a number of cars per lane and km");
    }
    out.push_back(d);
  }
  return out;
}

// SUMO episodes on the built-in highway: the scene options' count and seed,
// one group of episodes per density.
void evaluate_sumo(const EvaluateArgs& a, const Config& config) {
  const sim::EvaluateOptions& o = a.options;
  sumo::EvaluateOptions s;
  s.densities = densities_of(a.sumo_highway);
  s.commonroad_dir = a.sumo_commonroad;
  s.count = o.count;
  s.seed = static_cast<int>(o.seed);
  s.planners = planner_list(a.planners);
  s.model_dir = o.model_dir;
  s.out_dir = o.out_dir;
  if (a.shard_size_given) s.shard_size = o.shard_size;
  s.loop.duration = o.duration;
  s.loop.prediction = behavior_from_string(a.prediction, "--prediction");
  s.loop.signal_change = a.signal_change;
  s.config = config;
  s.make_planner = baselines::make_planner;
  run_evaluation(a.jobs, s.out_dir,
                 [&s](const sim::EvaluateRun& run) { return sumo::evaluate(s, run); });
}

}  // namespace

void add_simulate(CLI::App& app, const ConfigSource& config) {
  auto* cmd = app.add_subcommand("simulate", "Run one closed-loop rollout of a planner");
  auto a = make_args<SimulateArgs>();
  cmd->add_option("--scenario", a->scenario_path, "Scenario JSON file")->required();
  add_planner_option(*cmd, a->planner, "Planner");
  cmd->add_option("--model", a->model_dir,
                  "Model directory (lanechange train), for mlp-miqp and strategy-qp");
  cmd->add_option("--duration", a->duration,
                  "Seconds to simulate (default: the horizon plus closed_loop.settle_time)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--out", a->out_path, "Rollout JSON file, or - for standard output");
  cmd->callback([a, config] { simulate_once(*a, config()); });
}

void add_evaluate(CLI::App& app, const ConfigSource& config) {
  auto* cmd = app.add_subcommand(
      "evaluate", "Closed-loop rollouts of sampled scenarios for one or more planners (resumable)");
  auto a = make_args<EvaluateArgs>();
  sim::EvaluateOptions& o = a->options;
  auto* count = cmd->add_option("--count", o.count, "How many sampled scenarios");
  auto* seed = cmd->add_option("--seed", o.seed, "Sampler seed");
  auto* scenes = cmd->add_option("--scenarios", o.scenarios_dir,
                                 "Roll out every scene file (*.json) of this folder instead of "
                                 "sampled scenes (scenes.csv names each index's file)");
  scenes->excludes(count)->excludes(seed);
  add_behavior_option(*cmd, a->behavior);
  add_traffic_option(*cmd, a->target_lane_cars);
  add_planner_option(*cmd, a->planners, "Planners, comma-separated");
  cmd->add_option("--model", o.model_dir,
                  "Model directory (lanechange train), for mlp-miqp and strategy-qp");
  cmd->add_option("--out", o.out_dir, "Output directory; rerun the command to resume")->required();
  cmd->add_option("--jobs", a->jobs, "Worker threads (default: all cores)")
      ->check(CLI::NonNegativeNumber);
  auto* shard_size =
      cmd->add_option("--shard-size", o.shard_size, "Scenarios per shard file (SUMO episodes: 5)");
  cmd->add_option("--duration", o.duration, "Seconds per rollout (default: horizon + settle)");
  auto* sumo_highway = cmd->add_option(
      "--sumo-highway", a->sumo_highway,
      "SUMO episodes on the built-in highway instead of scenes (docs/sumo.md): densities in "
      "cars per lane and km, comma-separated; --count episodes per density, seeds from --seed");
  sumo_highway->excludes(scenes);
  auto* sumo_commonroad = cmd->add_option(
      "--sumo-commonroad", a->sumo_commonroad,
      "SUMO episodes of every CommonRoad interactive scenario folder of this directory");
  sumo_commonroad->excludes(scenes)->excludes(sumo_highway)->excludes(count)->excludes(seed);
  auto* prediction = cmd->add_option("--prediction", a->prediction,
                                     "SUMO episodes: how planners predict SUMO's cars (idm, "
                                     "constant_speed or constant_accel; docs/sumo.md)")
                         ->capture_default_str();
  auto* no_signal = cmd->add_flag("!--no-signal", a->signal_change,
                                  "SUMO episodes: the ego does not ask SUMO for the change, so "
                                  "SUMO's cars do not cooperate with it (docs/sumo.md)");
  cmd->callback([a, config, count, seed, scenes, sumo_highway, sumo_commonroad, shard_size,
                 prediction, no_signal] {
    a->shard_size_given = shard_size->count() > 0;
    const bool sumo_episodes = sumo_highway->count() > 0 || sumo_commonroad->count() > 0;
    for (const CLI::Option* sumo_only : {prediction, no_signal}) {
      if (sumo_only->count() > 0 && !sumo_episodes) {
        throw InputError(sumo_only->get_name(),
                         "applies to SUMO episodes only (--sumo-highway or "
                         "--sumo-commonroad)");
      }
    }
    if (sumo_commonroad->count() > 0) {
      evaluate_sumo(*a, config());
      return;
    }
    if (sumo_highway->count() > 0) {
      if (count->count() == 0 || seed->count() == 0) {
        throw InputError("--count", "SUMO episodes need --count N and --seed S");
      }
      evaluate_sumo(*a, config());
      return;
    }
    if (scenes->count() == 0 && (count->count() == 0 || seed->count() == 0)) {
      throw InputError("--count", "evaluate needs --count N and --seed S, or --scenarios DIR");
    }
    evaluate_all(*a, with_target_lane_cars(config(), a->target_lane_cars));
  });
}

}  // namespace lanechange::app
