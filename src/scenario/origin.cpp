#include "scenario/origin.hpp"

#include <algorithm>
#include <initializer_list>
#include <string>
#include <string_view>

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
