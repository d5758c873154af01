#include "lanechange/scenario.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "common/config_fields.hpp"
#include "lanechange/geometry.hpp"

namespace lanechange {

using detail::json;

std::string_view to_string(Behavior behavior) {
  switch (behavior) {
    case Behavior::ConstantSpeed: return "constant_speed";
    case Behavior::ConstantAccel: return "constant_accel";
    case Behavior::Idm: return "idm";
  }
  return "?";
}

Behavior behavior_from_string(std::string_view name, const std::string& field) {
  for (Behavior b : {Behavior::ConstantSpeed, Behavior::ConstantAccel, Behavior::Idm}) {
    if (to_string(b) == name) return b;
  }
  throw InputError(field, "unknown behavior \"" + std::string(name) +
                              "\" (expected constant_speed, constant_accel or idm)");
}

std::string_view to_string(Car car) {
  switch (car) {
    case Car::Leader: return "leader";
    case Car::Follower: return "follower";
    case Car::Target: return "target";
  }
  return "?";
}

const CarState& Scenario::car(Car which) const {
  switch (which) {
    case Car::Leader: return leader;
    case Car::Follower: return follower;
    case Car::Target: return target;
  }
  return leader;
}

VehicleSize Scenario::size_of(Car which) const {
  return car_size[static_cast<std::size_t>(which)].value_or(vehicle);
}

double Scenario::bumper_gap(Car which, double dx) const {
  return std::abs(dx) - 0.5 * (vehicle.length + size_of(which).length);
}

SafetyMargins Scenario::centre_safe_distances() const {
  return {centre_safe_distance(Car::Leader, safe_distance.leader),
          centre_safe_distance(Car::Follower, safe_distance.follower),
          centre_safe_distance(Car::Target, safe_distance.target)};
}

SafeDistance Scenario::centre_safe_distance(Car which, SafeDistance base) const {
  base.standstill += 0.5 * (size_of(which).length - vehicle.length);
  return base;
}

CarState& Scenario::car(Car which) {
  return const_cast<CarState&>(static_cast<const Scenario&>(*this).car(which));
}

double Scenario::lane_center(Car which) const { return which == Car::Leader ? 0.0 : lane_width; }

Interval Scenario::speed_bounds_at(double t) const {
  return {std::min(limits.v.lo, ego.v + limits.a.hi * t),
          std::max(limits.v.hi, ego.v + limits.a.lo * t)};
}

Scenario default_scenario(const Config& defaults) {
  Scenario s;
  s.lane_width = defaults.lane_width;
  s.horizon = defaults.expert.horizon;
  s.steps = defaults.expert.steps;
  s.vehicle = defaults.vehicle;
  s.idm = defaults.idm;
  s.safe_distance = defaults.safety;
  s.limits = defaults.limits;
  return s;
}

namespace {

const json& required(const json& object, const std::string& path, const char* key) {
  auto it = object.find(key);
  if (it == object.end()) throw InputError(detail::join_path(path, key), "missing required field");
  return *it;
}

double read_number(const json& object, const std::string& path, const char* key, bool is_required,
                   double fallback) {
  auto it = object.find(key);
  if (it == object.end()) {
    if (is_required) throw InputError(detail::join_path(path, key), "missing required field");
    return fallback;
  }
  double value = 0.0;
  detail::read_value(*it, detail::join_path(path, key), value);
  return value;
}

void reject_unknown_keys(const json& object, const std::string& path,
                         std::initializer_list<const char*> known) {
  for (const auto& item : object.items()) {
    bool found = false;
    for (const char* k : known) found = found || item.key() == k;
    if (!found) throw InputError(detail::join_path(path, item.key()), "unknown field");
  }
}

const json& require_object(const json& parent, const char* key) {
  const json& object = required(parent, "", key);
  if (!object.is_object()) throw InputError(key, "must be an object");
  return object;
}

EgoState read_ego(const json& root) {
  const json& j = require_object(root, "ego");
  reject_unknown_keys(j, "ego", {"x", "y", "v", "theta", "a"});
  EgoState e;
  e.x = read_number(j, "ego", "x", true, 0.0);
  e.y = read_number(j, "ego", "y", true, 0.0);
  e.v = read_number(j, "ego", "v", true, 0.0);
  e.theta = read_number(j, "ego", "theta", true, 0.0);
  e.a = read_number(j, "ego", "a", false, 0.0);
  return e;
}

CarState read_car(const json& root, const char* name, bool accel_required) {
  const json& j = require_object(root, name);
  reject_unknown_keys(j, name, {"x", "v", "a", "length", "width"});
  CarState c;
  c.x = read_number(j, name, "x", true, 0.0);
  c.v = read_number(j, name, "v", true, 0.0);
  c.a = read_number(j, name, "a", accel_required, 0.0);
  return c;
}

// Optional and together: a body is a length and a width. The other one
// defaults to `vehicle`'s, known only once the whole scene is read.
std::optional<VehicleSize> read_car_size(const json& root, const char* name,
                                         const VehicleSize& vehicle) {
  const json& j = root.at(name);
  const bool has_length = j.contains("length");
  const bool has_width = j.contains("width");
  if (!has_length && !has_width) return std::nullopt;
  VehicleSize size = vehicle;
  if (has_length) size.length = read_number(j, name, "length", true, 0.0);
  if (has_width) size.width = read_number(j, name, "width", true, 0.0);
  return size;
}

// formats.md gives each safe distance as one number of metres; we also take
// {"standstill": .., "time_headway": ..} for a speed-dependent distance.
void read_safe_distance(const json& j, const std::string& path, SafeDistance& out) {
  if (j.is_number()) {
    detail::read_value(j, path, out.standstill);
    out.time_headway = 0.0;
  } else {
    detail::read_value(j, path, out);
  }
}

json write_safe_distance(const SafeDistance& d) {
  if (d.time_headway == 0.0) return d.standstill;
  return detail::write_value(d);
}

void read_optional_fields(const json& root, Scenario& s) {
  if (auto it = root.find("horizon"); it != root.end())
    detail::read_value(*it, "horizon", s.horizon);
  if (auto it = root.find("steps"); it != root.end()) detail::read_value(*it, "steps", s.steps);
  if (auto it = root.find("vehicle"); it != root.end())
    detail::read_value(*it, "vehicle", s.vehicle);
  if (auto it = root.find("idm"); it != root.end()) detail::read_value(*it, "idm", s.idm);
  if (auto it = root.find("limits"); it != root.end()) detail::read_value(*it, "limits", s.limits);
  if (auto it = root.find("safe_distance"); it != root.end()) {
    if (!it->is_object()) throw InputError("safe_distance", "must be an object");
    reject_unknown_keys(*it, "safe_distance", {"leader", "follower", "target"});
    for (auto [key, slot] : {std::pair{"leader", &s.safe_distance.leader},
                             std::pair{"follower", &s.safe_distance.follower},
                             std::pair{"target", &s.safe_distance.target}}) {
      if (auto d = it->find(key); d != it->end()) {
        read_safe_distance(*d, std::string("safe_distance.") + key, *slot);
      }
    }
  }
}

json car_to_json(const Scenario& s, Car car) {
  const CarState& c = s.car(car);
  json out = {{"x", c.x}, {"v", c.v}, {"a", c.a}};
  if (const auto& size = s.car_size[static_cast<std::size_t>(car)]) {
    out["length"] = size->length;
    out["width"] = size->width;
  }
  return out;
}

OrientedBox box_of(const Scenario& s, Car car) {
  const VehicleSize size = s.size_of(car);
  return {s.car(car).x, s.lane_center(car), 0.0, size.length, size.width};
}

void require(bool ok, const std::string& field, const std::string& problem) {
  if (!ok) throw InputError(field, problem);
}

}  // namespace

void validate_scenario(const Scenario& s) {
  require(std::isfinite(s.lane_width) && s.lane_width > 0, "lane_width", "must be positive");
  require(s.ego.v >= 0, "ego.v", "speed must not be negative");
  for (Car car : kAllCars) {
    const std::string name(to_string(car));
    require(s.car(car).v >= 0, name + ".v", "speed must not be negative");
    const VehicleSize size = s.size_of(car);
    require(size.length > 0, name + ".length", "must be positive");
    require(size.width > 0 && size.width < s.lane_width, name + ".width",
            "must be positive and narrower than the lane");
  }
  require(s.horizon > 0, "horizon", "must be positive");
  require(s.steps >= 2 && s.steps <= 10000, "steps", "must be in [2, 10000]");
  require(s.vehicle.length > 0, "vehicle.length", "must be positive");
  require(s.vehicle.width > 0 && s.vehicle.width < s.lane_width, "vehicle.width",
          "must be positive and narrower than the lane");
  require(std::abs(s.ego.theta) < std::numbers::pi / 2, "ego.theta",
          "must point forward (|theta| < pi/2)");
  require(s.ego.y >= -0.5 * s.lane_width && s.ego.y <= 1.5 * s.lane_width, "ego.y",
          "must lie on the two-lane road [-w/2, 3w/2]");
  require(s.leader.x > s.ego.x, "leader.x", "the leader must be ahead of the ego");
  require(s.target.x > s.follower.x, "target.x", "the target must be ahead of the follower");
  const OrientedBox ego{s.ego.x, s.ego.y, s.ego.theta, s.vehicle.length, s.vehicle.width};
  for (Car car : kAllCars) {
    require(!boxes_collide(ego, box_of(s, car)), std::string(to_string(car)) + ".x",
            "overlaps the ego at t = 0");
  }
  require(!boxes_collide(box_of(s, Car::Follower), box_of(s, Car::Target)), "target.x",
          "overlaps the follower at t = 0");
}

Scenario scenario_from_json(const json& root, const Config& defaults) {
  if (!root.is_object()) throw InputError("", "a scenario must be a JSON object");
  reject_unknown_keys(root, "",
                      {"format", "lane_width", "behavior", "ego", "leader", "follower", "target",
                       "horizon", "steps", "vehicle", "idm", "safe_distance", "limits"});
  if (auto it = root.find("format"); it != root.end()) {
    require(it->is_string() && it->get<std::string>() == kScenarioFormat, "format",
            "must be \"" + std::string(kScenarioFormat) + "\"");
  }
  Scenario s = default_scenario(defaults);
  s.lane_width = read_number(root, "", "lane_width", true, 0.0);
  const json& behavior = required(root, "", "behavior");
  require(behavior.is_string(), "behavior", "must be a string");
  s.behavior = behavior_from_string(behavior.get<std::string>());
  const bool accel_required = s.behavior == Behavior::ConstantAccel;
  s.ego = read_ego(root);
  s.leader = read_car(root, "leader", accel_required);
  s.follower = read_car(root, "follower", accel_required);
  s.target = read_car(root, "target", accel_required);
  read_optional_fields(root, s);
  for (Car car : kAllCars) {
    const std::string name(to_string(car));
    s.car_size[static_cast<std::size_t>(car)] = read_car_size(root, name.c_str(), s.vehicle);
  }
  validate_scenario(s);
  effective_config(defaults, s).validate();
  return s;
}

Scenario scenario_from_text(const std::string& text, const Config& defaults) {
  return scenario_from_json(detail::parse_json_text(text, "the scenario"), defaults);
}

Scenario load_scenario(const std::string& path, const Config& defaults) {
  return scenario_from_json(detail::read_json_file(path), defaults);
}

json scenario_to_json(const Scenario& s) {
  json out;
  out["format"] = kScenarioFormat;
  out["lane_width"] = s.lane_width;
  out["behavior"] = to_string(s.behavior);
  out["ego"] = {
      {"x", s.ego.x}, {"y", s.ego.y}, {"v", s.ego.v}, {"theta", s.ego.theta}, {"a", s.ego.a}};
  out["leader"] = car_to_json(s, Car::Leader);
  out["follower"] = car_to_json(s, Car::Follower);
  out["target"] = car_to_json(s, Car::Target);
  out["horizon"] = s.horizon;
  out["steps"] = s.steps;
  out["vehicle"] = detail::write_value(s.vehicle);
  out["idm"] = detail::write_value(s.idm);
  out["safe_distance"] = {{"leader", write_safe_distance(s.safe_distance.leader)},
                          {"follower", write_safe_distance(s.safe_distance.follower)},
                          {"target", write_safe_distance(s.safe_distance.target)}};
  out["limits"] = detail::write_value(s.limits);
  return out;
}

void save_scenario(const Scenario& scenario, const std::string& path) {
  detail::write_file_atomically(path, scenario_to_json(scenario).dump(2) + "\n");
}

Config effective_config(const Config& base, const Scenario& s) {
  Config c = base;
  c.lane_width = s.lane_width;
  c.expert.horizon = s.horizon;
  c.expert.steps = s.steps;
  c.vehicle = s.vehicle;
  c.idm = s.idm;
  c.safety = s.safe_distance;
  c.limits = s.limits;
  return c;
}

}  // namespace lanechange
