#include "sim_commands.hpp"

#include <iostream>

#include "lanechange/planner/planner.hpp"
#include "lanechange/scenario.hpp"
#include "lanechange/sim/simulator.hpp"
#include "lanechange/trajectory.hpp"

namespace lanechange::app {

void add_simulate(CLI::App& app, ConfigSource config_source) {
  auto* cmd = app.add_subcommand("simulate", "Run one closed-loop rollout of a planner");
  static std::string scenario_path;
  static std::string planner_name = "miqp";
  static double duration = 0.0;
  static std::string out_path = "-";
  cmd->add_option("--scenario", scenario_path, "Scenario JSON file")->required();
  cmd->add_option("--planner", planner_name, "Planner: miqp or keep-lane");
  cmd->add_option("--duration", duration,
                  "Seconds to simulate (default: the horizon plus closed_loop.settle_time)")
      ->check(CLI::PositiveNumber);
  cmd->add_option("--out", out_path, "Rollout JSON file, or - for standard output");
  cmd->callback([config_source] {
    const Config config = config_source();
    const Scenario scenario = load_scenario(scenario_path, config);
    const auto planner = planner::make_planner(planner_name, config);
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

}  // namespace lanechange::app
