#pragma once
// The "origin" field of format 2: where a scene cut from a recording comes
// from, and the recorded driver's own lane change (docs/scenarios.md).
#include <nlohmann/json.hpp>

#include "lanechange/scenario.hpp"

namespace lanechange::detail {

/// Throws InputError naming the field (under "origin") for a missing or
/// unknown key, a negative time, or a human change given for a planning problem.
[[nodiscard]] SceneOrigin read_scene_origin(const nlohmann::json& j);
[[nodiscard]] nlohmann::json write_scene_origin(const SceneOrigin& origin);

}  // namespace lanechange::detail
