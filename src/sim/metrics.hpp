#pragma once
// The measures of a finished rollout (judge.cpp), used by the simulator.
#include "lanechange/sim/simulator.hpp"

namespace lanechange::sim::detail {

[[nodiscard]] RolloutMetrics measure(const Rollout& rollout, const Scenario& scene,
                                     const Config& config);

}  // namespace lanechange::sim::detail
