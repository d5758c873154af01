#pragma once
#include <CLI/CLI.hpp>

#include "data_commands.hpp"

namespace lanechange::app {

/// `train` (with `--dagger R`: docs/strategy.md) and `model-info` (docs/learning.md).
void add_train(CLI::App& app, const ConfigSource& config);
void add_model_info(CLI::App& app);

}  // namespace lanechange::app
