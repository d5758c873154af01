#pragma once
#include <CLI/CLI.hpp>

namespace lanechange::app {

/// `train` and `model-info` (docs/learning.md).
void add_train(CLI::App& app);
void add_model_info(CLI::App& app);

}  // namespace lanechange::app
