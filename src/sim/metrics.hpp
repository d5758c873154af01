#pragma once
// The measures of a finished rollout (judge.cpp), used by the simulator.
#include <nlohmann/json.hpp>
#include <optional>

#include "lanechange/sim/simulator.hpp"

namespace lanechange::sim::detail {

[[nodiscard]] RolloutMetrics measure(const Rollout& rollout, const Scenario& scene,
                                     const Config& config);

/// The gap a rollout ended in, as a plan's `details.gap`: the ids of the
/// target-lane cars nearest behind and ahead of the ego at its last node
/// (null where none is); none where the ego did not end in the target lane.
[[nodiscard]] std::optional<nlohmann::json> gap_taken(const Trajectory& path,
                                                      const Scenario& scene);

}  // namespace lanechange::sim::detail
