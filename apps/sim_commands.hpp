#pragma once
#include <CLI/CLI.hpp>

#include "data_commands.hpp"

namespace lanechange::app {

void add_simulate(CLI::App& app, const ConfigSource& config);
void add_evaluate(CLI::App& app, const ConfigSource& config);
void add_strategy_study(CLI::App& app, const ConfigSource& config);

}  // namespace lanechange::app
