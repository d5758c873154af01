#pragma once
#include <CLI/CLI.hpp>
#include <functional>

#include "lanechange/config.hpp"

namespace lanechange::app {

/// The config the global options (--preset, --config) select.
using ConfigSource = std::function<Config()>;

void add_generate(CLI::App& app, const ConfigSource& config);
void add_dataset_info(CLI::App& app);

}  // namespace lanechange::app
