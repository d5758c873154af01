#pragma once
#include <CLI/CLI.hpp>

namespace lanechange::app {

/// `train` (docs/learning.md).
void add_train(CLI::App& app);

}  // namespace lanechange::app
