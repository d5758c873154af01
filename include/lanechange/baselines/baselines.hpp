#pragma once
// The baselines of the paper's comparison and of practice (docs/baselines.md):
// the paper's MPC, the dynamic window approach and the Frenet lattice. Each is
// a closed-loop planner like ours, run by the same simulator and judge.
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "lanechange/config.hpp"
#include "lanechange/planner/planner.hpp"

namespace lanechange::baselines {

/// The baselines' names, in the order the docs list them.
[[nodiscard]] std::vector<std::string> baseline_names();

/// Every planner the commands know: planner::make_planner's and the
/// baselines. Throws InputError for an unknown name, listing the known ones.
[[nodiscard]] std::shared_ptr<const planner::ClosedLoopPlanner> make_planner(
    std::string_view name, const Config& config, const std::string& model_dir = "");
[[nodiscard]] std::vector<std::string> planner_names();

}  // namespace lanechange::baselines
