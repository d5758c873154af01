#include "scenario/recorded_fields.hpp"

#include <algorithm>
#include <cmath>
#include <initializer_list>
#include <string>
#include <string_view>
#include <vector>

#include "common/json_fields.hpp"
#include "lanechange/error.hpp"

namespace lanechange::detail {
namespace {

constexpr const char* kRecordedCar = "recorded_car";
constexpr const char* kPlanningProblem = "planning_problem";

void reject_unknown(const json& j, const std::string& path,
                    std::initializer_list<std::string_view> known) {
  for (const auto& item : j.items()) {
    if (std::find(known.begin(), known.end(), item.key()) == known.end())
      throw InputError(join_path(path, item.key()), "unknown field");
  }
}

const json& member(const json& j, const std::string& path, const char* key) {
  const auto it = j.find(key);
  if (it == j.end()) throw InputError(join_path(path, key), "missing");
  return *it;
}

double non_negative(const json& j, const std::string& path, const char* key) {
  double value = 0.0;
  read_value(member(j, path, key), join_path(path, key), value);
  if (value < 0.0) throw InputError(join_path(path, key), "must not be negative");
  return value;
}

std::optional<std::string> car_id_or_none(const json& j, const std::string& path, const char* key) {
  const json& value = member(j, path, key);
  if (value.is_null()) return std::nullopt;
  std::string id;
  read_value(value, join_path(path, key), id);
  return id;
}

HumanLaneChange read_human_change(const json& j, const std::string& path) {
  if (!j.is_object()) throw InputError(path, "must be an object or null");
  reject_unknown(j, path, {"after", "behind", "ahead"});
  return {non_negative(j, path, "after"), car_id_or_none(j, path, "behind"),
          car_id_or_none(j, path, "ahead")};
}

json id_or_null(const std::optional<std::string>& id) { return id ? json(*id) : json(nullptr); }

std::vector<double> samples(const json& j, const std::string& path, const char* key) {
  const json& list = member(j, path, key);
  const std::string where = join_path(path, key);
  if (!list.is_array() || list.empty()) throw InputError(where, "must be a non-empty array");
  std::vector<double> out(list.size());
  for (std::size_t k = 0; k < list.size(); ++k)
    read_value(list[k], where + "[" + std::to_string(k) + "]", out[k]);
  return out;
}

// The record starts where the file puts the car: one place for its start.
void require_start(double recorded, double given, const std::string& where) {
  if (std::abs(recorded - given) > 1e-6 * std::max(1.0, std::abs(given))) {
    throw InputError(where, "must equal the car's own value at t = 0");
  }
}

}  // namespace

SceneOrigin read_scene_origin(const json& j) {
  const std::string path = "origin";
  if (!j.is_object()) throw InputError(path, "must be an object");
  reject_unknown(j, path, {"recording", "time", "ego", "ego_kind", "human_change"});
  SceneOrigin origin;
  read_value(member(j, path, "recording"), "origin.recording", origin.recording);
  origin.time = non_negative(j, path, "time");
  read_value(member(j, path, "ego"), "origin.ego", origin.ego);
  std::string kind;
  read_value(member(j, path, "ego_kind"), "origin.ego_kind", kind);
  if (kind != kRecordedCar && kind != kPlanningProblem) {
    throw InputError("origin.ego_kind", "must be \"recorded_car\" or \"planning_problem\"");
  }
  origin.ego_is_planning_problem = kind == kPlanningProblem;
  // A recorded ego says what its driver did, even if that was to stay.
  const auto change = j.find("human_change");
  if (origin.ego_is_planning_problem) {
    if (change != j.end() && !change->is_null()) {
      throw InputError("origin.human_change", "a planning problem has no recorded lane change");
    }
  } else if (change == j.end()) {
    throw InputError("origin.human_change", "missing (null where the driver stayed)");
  } else if (!change->is_null()) {
    origin.human_change = read_human_change(*change, "origin.human_change");
  }
  return origin;
}

RecordedTrack read_recorded_track(const json& j, const std::string& path, const CarState& start) {
  if (!j.is_object()) throw InputError(path, "must be an object");
  reject_unknown(j, path, {"dt", "x", "v"});
  RecordedTrack track;
  read_value(member(j, path, "dt"), join_path(path, "dt"), track.dt);
  if (track.dt <= 0.0) throw InputError(join_path(path, "dt"), "must be positive");
  track.x = samples(j, path, "x");
  track.v = samples(j, path, "v");
  if (track.v.size() != track.x.size()) {
    throw InputError(join_path(path, "v"), "must have as many samples as x");
  }
  for (std::size_t k = 0; k < track.v.size(); ++k) {
    if (track.v[k] < 0.0)
      throw InputError(path + ".v[" + std::to_string(k) + "]", "speed must not be negative");
  }
  require_start(track.x[0], start.x, path + ".x[0]");
  require_start(track.v[0], start.v, path + ".v[0]");
  return track;
}

json write_recorded_track(const RecordedTrack& track) {
  return {{"dt", track.dt}, {"x", track.x}, {"v", track.v}};
}

json write_scene_origin(const SceneOrigin& origin) {
  json out = {{"recording", origin.recording},
              {"time", origin.time},
              {"ego", origin.ego},
              {"ego_kind", origin.ego_is_planning_problem ? kPlanningProblem : kRecordedCar}};
  if (origin.ego_is_planning_problem) return out;
  out["human_change"] = nullptr;
  if (const auto& h = origin.human_change) {
    out["human_change"] = {
        {"after", h->after}, {"behind", id_or_null(h->behind)}, {"ahead", id_or_null(h->ahead)}};
  }
  return out;
}

}  // namespace lanechange::detail
