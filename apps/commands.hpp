#pragma once
// The subcommands of the lanechange command line, one registration function
// each. Every subcommand keeps its option values in a struct owned by its
// callback (CLI11 writes them while parsing; the callback reads them after),
// and the same thing has the same option name and default everywhere.
#include <CLI/CLI.hpp>
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "lanechange/config.hpp"
#include "lanechange/scenario.hpp"

namespace lanechange::app {

/// The config the global options (--preset, --config) select.
using ConfigSource = std::function<Config()>;

/// Option values of one subcommand, shared between its options and callback.
template <class Args>
[[nodiscard]] std::shared_ptr<Args> make_args() {
  return std::make_shared<Args>();
}

/// --behavior, with one help text and the default "all" (drawn per scene).
void add_behavior_option(CLI::App& cmd, std::string& behavior);
/// "all" is none; any other name must be a behavior the sampler can draw
/// (InputError naming --behavior; replay needs recorded cars).
[[nodiscard]] std::optional<Behavior> behavior_option(const std::string& behavior);

/// --target-lane-cars N or LO,HI: dense traffic (sampler.target_lane_cars)
/// for the commands that draw scenes; empty keeps the config's.
void add_traffic_option(CLI::App& cmd, std::string& target_lane_cars);
/// `config` with the option's count range; InputError naming
/// --target-lane-cars for anything but one or two whole counts in [0, 100].
[[nodiscard]] Config with_target_lane_cars(Config config, const std::string& option);

/// --planner NAME[,NAME...]: the planners one command runs, by registry name.
void add_planner_option(CLI::App& cmd, std::string& planners, const std::string& what);
/// "a,b,,c" -> {a, b, c}: an empty name (a doubled or trailing comma) is
/// skipped; unknown names are left for the planner registry to name.
[[nodiscard]] std::vector<std::string> planner_list(const std::string& comma_separated);

// Scenes and single plans.
void add_validate(CLI::App& app, const ConfigSource& config);
void add_sample(CLI::App& app, const ConfigSource& config);
void add_config(CLI::App& app, const ConfigSource& config);
void add_plan(CLI::App& app, const ConfigSource& config);
void add_plot(CLI::App& app, const ConfigSource& config);
// Recorded traffic (docs/recorded.md).
void add_import_commonroad(CLI::App& app, const ConfigSource& config);
// Expert data (docs/dataset.md).
void add_generate(CLI::App& app, const ConfigSource& config);
void add_dataset_info(CLI::App& app);
// Learning (docs/learning.md, docs/strategy.md).
void add_train(CLI::App& app);
void add_dagger(CLI::App& app, const ConfigSource& config);
void add_model_info(CLI::App& app);
// Closed loop (docs/closed_loop.md) and the experiments (docs/experiments.md).
void add_simulate(CLI::App& app, const ConfigSource& config);
void add_evaluate(CLI::App& app, const ConfigSource& config);
void add_experiments(CLI::App& app, const ConfigSource& config);
// SUMO co-simulation (docs/sumo.md).
void add_sumo(CLI::App& app, const ConfigSource& config);
// Studies: measurements and comparisons beside the pipeline.
void add_crosscheck(CLI::App& app, const ConfigSource& config);
void add_label_study(CLI::App& app, const ConfigSource& config);
void add_strategy_study(CLI::App& app, const ConfigSource& config);
void add_authors_study(CLI::App& app, const ConfigSource& config);

}  // namespace lanechange::app
