#pragma once
// The fields of format 2 that scenes cut from recordings carry
// (docs/scenarios.md): "origin", where the scene comes from and the recorded
// driver's own lane change, and a replayed car's "record".
#include <nlohmann/json.hpp>

#include "lanechange/scenario.hpp"

namespace lanechange::detail {

/// Throws InputError naming the field (under "origin") for a missing or
/// unknown key, a negative time, or a human change given for a planning problem.
[[nodiscard]] SceneOrigin read_scene_origin(const nlohmann::json& j);
[[nodiscard]] nlohmann::json write_scene_origin(const SceneOrigin& origin);

/// Throws InputError naming the field under `path` for a non-positive dt,
/// x and v of unequal or zero length, a negative speed, or a first sample
/// other than the car's own x and v (`start`).
[[nodiscard]] RecordedTrack read_recorded_track(const nlohmann::json& j, const std::string& path,
                                                const CarState& start);
[[nodiscard]] nlohmann::json write_recorded_track(const RecordedTrack& track);

}  // namespace lanechange::detail
