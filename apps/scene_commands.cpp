// Scenes and single plans: validate, sample, config, plan, plot.
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <nlohmann/json.hpp>

#include "commands.hpp"
#include "lanechange/error.hpp"
#include "lanechange/expert/planner.hpp"
#include "lanechange/plot.hpp"
#include "lanechange/sampler.hpp"

namespace lanechange::app {

namespace {

struct SampleArgs {
  long long count = 0;
  std::uint64_t seed = 0;
  std::string out_dir;
  std::string behavior;
  std::string target_lane_cars;
};

struct PlanArgs {
  std::string scenario_path;
  std::string planner = "miqp";
  std::string solver = "fast";
  double time_limit = 60.0;
  std::string out_path = "-";
};

struct PlotArgs {
  std::string trajectory_path;
  std::string out_path;
  int snapshots = 5;
  bool animate = false;
  double speedup = 1.0;
};

void write_samples(const SampleArgs& a, const Config& config) {
  const std::optional<Behavior> fixed = behavior_option(a.behavior);
  const ScenarioSampler sampler(config, a.seed);
  std::filesystem::create_directories(a.out_dir);
  for (long long i = 0; i < a.count; ++i) {
    char name[64];
    std::snprintf(name, sizeof name, "scenario_%06lld.json", i);
    save_scenario(sampler.sample(static_cast<std::uint64_t>(i), fixed),
                  (std::filesystem::path(a.out_dir) / name).string());
  }
  std::cerr << "wrote " << a.count << " scenarios to " << a.out_dir << "\n";
}

void plan_once(const PlanArgs& a, const Config& config) {
  if (a.planner != "miqp") {
    throw InputError("--planner", "plan makes the expert's open-loop plan (miqp); \"" + a.planner +
                                      "\" acts in closed loop: use simulate --planner " +
                                      a.planner);
  }
  const Scenario scenario = load_scenario(a.scenario_path, config);
  const expert::ExpertPlanner expert(
      config, expert::make_lane_change_solver(a.solver, config.expert.big_m));
  const auto result = expert.plan(scenario, {a.time_limit});
  const Trajectory trajectory = expert.to_trajectory(result, scenario);
  save_trajectory(trajectory, a.out_path);
  std::cerr << "label " << to_string(trajectory.label) << ", " << expert::to_string(result.status)
            << " after " << result.iterations() << " rounds, objective " << result.objective << ", "
            << result.total_ms << " ms"
            << (trajectory.reason.empty() ? "" : " (" + trajectory.reason + ")") << "\n";
}

void draw(const PlotArgs& a, const Config& config) {
  const Trajectory trajectory = load_trajectory(a.trajectory_path);
  if (a.animate) {
    AnimationOptions options;
    options.vehicle = config.vehicle;
    options.speedup = a.speedup;
    animate_trajectory(trajectory, a.out_path, options);
  } else {
    PlotOptions options;
    options.vehicle = config.vehicle;  // the trajectory file does not store it
    options.snapshots = a.snapshots;
    plot_trajectory(trajectory, a.out_path, options);
  }
  std::cerr << "wrote " << a.out_path << "\n";
}

}  // namespace

void add_validate(CLI::App& app, const ConfigSource& config) {
  auto* cmd =
      app.add_subcommand("validate", "Check a scenario file and print it with all defaults");
  auto path = make_args<std::string>();
  cmd->add_option("--scenario", *path, "Scenario JSON file")->required();
  cmd->callback([path, config] {
    std::cout << scenario_to_json(load_scenario(*path, config())).dump(2) << "\n";
  });
}

void add_sample(CLI::App& app, const ConfigSource& config) {
  auto* cmd = app.add_subcommand("sample", "Write N random scenario files (seeded)");
  auto a = make_args<SampleArgs>();
  cmd->add_option("--count", a->count, "How many scenarios")
      ->required()
      ->check(CLI::Range(1LL, 100'000'000LL));
  cmd->add_option("--seed", a->seed, "Sampler seed")->required();
  cmd->add_option("--out", a->out_dir, "Output directory (created if missing)")->required();
  add_behavior_option(*cmd, a->behavior);
  add_traffic_option(*cmd, a->target_lane_cars);
  cmd->callback(
      [a, config] { write_samples(*a, with_target_lane_cars(config(), a->target_lane_cars)); });
}

void add_config(CLI::App& app, const ConfigSource& config) {
  auto* cmd = app.add_subcommand("config", "Print the effective config as JSON (or save it)");
  auto out_path = make_args<std::string>();
  cmd->add_option("--out", *out_path, "Write to this file instead of standard output");
  cmd->callback([out_path, config] {
    if (out_path->empty()) {
      const nlohmann::json j = config();
      std::cout << j.dump(2) << "\n";
    } else {
      save_config(config(), *out_path);
    }
  });
}

void add_plan(CLI::App& app, const ConfigSource& config) {
  auto* cmd = app.add_subcommand("plan", "Plan once from the scenario's initial state");
  auto a = make_args<PlanArgs>();
  cmd->add_option("--scenario", a->scenario_path, "Scenario JSON file")->required();
  cmd->add_option("--planner", a->planner,
                  "Planner: miqp, the expert's open-loop plan (the closed-loop planners run with "
                  "simulate and evaluate)");
  cmd->add_option("--solver", a->solver, "MIQP back-end: fast (ours) or reference (Bonmin B-BB)");
  cmd->add_option("--time-limit", a->time_limit, "Seconds for the whole plan")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--out", a->out_path, "Trajectory JSON file, or - for standard output");
  cmd->callback([a, config] { plan_once(*a, config()); });
}

void add_plot(CLI::App& app, const ConfigSource& config) {
  auto* cmd = app.add_subcommand(
      "plot", "Draw a trajectory file as a PNG (needs gnuplot), or --animate it as an SVG");
  auto a = make_args<PlotArgs>();
  cmd->add_option("--trajectory", a->trajectory_path, "Trajectory JSON file (plan or rollout)")
      ->required();
  cmd->add_option("--out", a->out_path, "PNG file to write (SVG with --animate)")->required();
  cmd->add_flag("--animate", a->animate,
                "Write an animated SVG (plays in a web browser; no gnuplot needed)");
  cmd->add_option("--speedup", a->speedup, "Playback speed of --animate against real time")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--snapshots", a->snapshots, "How many instants to draw the cars at")
      ->check(CLI::Range(1, 50));
  cmd->callback([a, config] { draw(*a, config()); });
}

}  // namespace lanechange::app
