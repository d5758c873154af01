#pragma once
#include <CLI/CLI.hpp>

#include "data_commands.hpp"

namespace lanechange::app {

void add_experiments(CLI::App& app, const ConfigSource& config);

}  // namespace lanechange::app
