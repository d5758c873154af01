#include "lanechange/scenario.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>

#include "common/config_fields.hpp"
#include "lanechange/geometry.hpp"
#include "scenario/recorded_fields.hpp"

namespace lanechange {

using detail::json;

std::string_view to_string(Behavior behavior) {
  switch (behavior) {
    case Behavior::ConstantSpeed: return "constant_speed";
    case Behavior::ConstantAccel: return "constant_accel";
    case Behavior::Idm: return "idm";
    case Behavior::Replay: return "replay";
  }
  return "?";
}

Behavior behavior_from_string(std::string_view name, const std::string& field) {
  for (Behavior b :
       {Behavior::ConstantSpeed, Behavior::ConstantAccel, Behavior::Idm, Behavior::Replay}) {
    if (to_string(b) == name) return b;
  }
  throw InputError(field, "unknown behavior \"" + std::string(name) +
                              "\" (expected constant_speed, constant_accel, idm or replay)");
}

std::string_view to_string(Lane lane) { return lane == Lane::Ego ? "ego" : "target"; }

std::string_view to_string(Side side) { return side == Side::Left ? "left" : "right"; }

std::string_view to_string(Role role) {
  switch (role) {
    case Role::Leader: return "leader";
    case Role::Follower: return "follower";
    case Role::Target: return "target";
  }
  return "?";
}

CarState RecordedTrack::at(double t) const {
  const double steps = std::max(t, 0.0) / dt;
  const auto last = x.size() - 1;
  if (steps >= static_cast<double>(last)) {
    return {x[last] + v[last] * (steps - static_cast<double>(last)) * dt, v[last], 0.0};
  }
  const auto k = static_cast<std::size_t>(steps);
  const double f = steps - static_cast<double>(k);
  return {x[k] + f * (x[k + 1] - x[k]), v[k] + f * (v[k + 1] - v[k]), (v[k + 1] - v[k]) / dt};
}

void Scenario::set_behavior(Behavior b) {
  behavior = b;
  for (OtherCar& car : cars) car.behavior = b;
}

CarIndex Scenario::index_of(Role role) const {
  const auto& slot = roles[index(role)];
  if (!slot) throw std::logic_error("the scene has no " + std::string(to_string(role)));
  return *slot;
}

VehicleSize Scenario::size_of(CarIndex which) const {
  return cars.at(which).size.value_or(vehicle);
}

double Scenario::bumper_gap(CarIndex which, double dx) const {
  return std::abs(dx) - 0.5 * (vehicle.length + size_of(which).length);
}

SafeDistance Scenario::centre_safe_distance(CarIndex which, SafeDistance base) const {
  base.standstill += 0.5 * (size_of(which).length - vehicle.length);
  return base;
}

SafetyMargins Scenario::centre_safe_distances() const {
  auto of = [this](Role role, SafeDistance base) {
    return has(role) ? centre_safe_distance(index_of(role), base) : base;
  };
  return {of(Role::Leader, safe_distance.leader), of(Role::Follower, safe_distance.follower),
          of(Role::Target, safe_distance.target)};
}

double Scenario::lane_center(Lane lane) const { return lane == Lane::Ego ? 0.0 : lane_width; }

std::optional<CarIndex> Scenario::find(std::string_view id) const {
  for (CarIndex i = 0; i < cars.size(); ++i) {
    if (cars[i].id == id) return i;
  }
  return std::nullopt;
}

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

Scenario three_car_scenario(const Config& defaults) {
  Scenario s = default_scenario(defaults);
  for (const Role role : kRoles) {
    OtherCar car;
    car.id = std::string(to_string(role));
    car.lane = role == Role::Leader ? Lane::Ego : Lane::Target;
    s.roles[static_cast<std::size_t>(role)] = s.cars.size();
    s.cars.push_back(std::move(car));
  }
  return s;
}

std::optional<CarIndex> nearest_in_lane(const Scenario& s, std::span<const CarState> now, Lane lane,
                                        double x, bool ahead) {
  std::optional<CarIndex> best;
  for (CarIndex i = 0; i < now.size(); ++i) {
    const double at = now[i].x;
    if (s.cars[i].lane != lane || (at > x) != ahead) continue;
    if (!best || (ahead ? at < now[*best].x : at > now[*best].x)) best = i;
  }
  return best;
}

std::optional<CarIndex> nearest_in_role(const Scenario& s, Role role) {
  std::vector<CarState> start;
  start.reserve(s.car_count());
  for (const OtherCar& car : s.cars) start.push_back(car.state);
  return nearest_in_lane(s, start, role == Role::Leader ? Lane::Ego : Lane::Target, s.ego.x,
                         role != Role::Follower);
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

CarState read_car_state(const json& j, const std::string& path, bool accel_required) {
  CarState c;
  c.x = read_number(j, path, "x", true, 0.0);
  c.v = read_number(j, path, "v", true, 0.0);
  c.a = read_number(j, path, "a", accel_required, 0.0);
  return c;
}

// Optional and together: a body is a length and a width. The other one
// defaults to `vehicle`'s, known only once the whole scene is read.
std::optional<VehicleSize> read_car_size(const json& j, const std::string& path,
                                         const VehicleSize& vehicle) {
  const bool has_length = j.contains("length");
  const bool has_width = j.contains("width");
  if (!has_length && !has_width) return std::nullopt;
  VehicleSize size = vehicle;
  if (has_length) size.length = read_number(j, path, "length", true, 0.0);
  if (has_width) size.width = read_number(j, path, "width", true, 0.0);
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

OrientedBox box_of(const Scenario& s, CarIndex car) {
  const VehicleSize size = s.size_of(car);
  return {s.car(car).x, s.lane_center(car), 0.0, size.length, size.width};
}

void require(bool ok, const std::string& field, const std::string& problem) {
  if (!ok) throw InputError(field, problem);
}

}  // namespace

namespace {

// A format-2 car's place in the file. Appending, not operator+, which GCC 12
// wrongly warns about here (-Wrestrict).
std::string car_path(std::size_t i) {
  std::string path = "cars[";
  path += std::to_string(i);
  path += ']';
  return path;
}

// The shape format 1 holds: the paper's three cars, in Role order, of the
// scene's behavior.
bool has_three_car_shape(const Scenario& s) {
  if (s.cars.size() != 3 || s.target_side != Side::Left || s.origin ||
      s.behavior == Behavior::Replay) {
    return false;
  }
  for (const Role role : kRoles) {
    const auto i = static_cast<std::size_t>(role);
    const OtherCar& car = s.cars[i];
    if (s.roles[i] != i || car.id != to_string(role) || car.behavior != s.behavior ||
        car.lane != (role == Role::Leader ? Lane::Ego : Lane::Target)) {
      return false;
    }
  }
  return true;
}

// How an error names a car: by its format-1 key, or by its place in format
// 2's "cars".
struct CarNames {
  bool by_role = false;
  [[nodiscard]] std::string operator()(const Scenario& s, CarIndex i) const {
    return by_role ? s.cars[i].id : car_path(i);
  }
};

void validate_car(const Scenario& s, CarIndex i, const CarNames& car_field) {
  const std::string name = car_field(s, i);
  const OtherCar& car = s.cars[i];
  require(!car.id.empty(), name + ".id", "must not be empty");
  require(s.find(car.id) == i, name + ".id", "\"" + car.id + "\" names two cars");
  require(car.state.v >= 0, name + ".v", "speed must not be negative");
  const VehicleSize size = s.size_of(i);
  require(size.length > 0, name + ".length", "must be positive");
  require(size.width > 0 && size.width < s.lane_width, name + ".width",
          "must be positive and narrower than the lane");
}

void validate_roles(const Scenario& s, const CarNames& car_field) {
  for (const Role role : kRoles) {
    if (!s.has(role)) continue;
    const CarIndex i = s.index_of(role);
    require(i < s.cars.size(), std::string(to_string(role)), "names no car of the scene");
    const Lane lane = role == Role::Leader ? Lane::Ego : Lane::Target;
    require(s.cars[i].lane == lane, car_field(s, i) + ".lane",
            "the " + std::string(to_string(role)) + " drives in the " +
                std::string(to_string(lane)) + " lane");
  }
  if (s.has(Role::Leader)) {
    require(s.leader().x > s.ego.x, car_field(s, s.index_of(Role::Leader)) + ".x",
            "the leader must be ahead of the ego");
  }
  if (s.has(Role::Follower) && s.has(Role::Target)) {
    require(s.target().x > s.follower().x, car_field(s, s.index_of(Role::Target)) + ".x",
            "the target must be ahead of the follower");
  }
}

void validate_no_overlap(const Scenario& s, const CarNames& car_field) {
  const OrientedBox ego{s.ego.x, s.ego.y, s.ego.theta, s.vehicle.length, s.vehicle.width};
  for (CarIndex i = 0; i < s.cars.size(); ++i) {
    const OrientedBox box = box_of(s, i);
    require(!boxes_collide(ego, box), car_field(s, i) + ".x", "overlaps the ego at t = 0");
    for (CarIndex j = 0; j < i; ++j) {
      require(s.cars[i].lane != s.cars[j].lane || !boxes_collide(box_of(s, j), box),
              car_field(s, i) + ".x", "overlaps the " + car_field(s, j) + " at t = 0");
    }
  }
}

void validate_named(const Scenario& s, const CarNames& car_field) {
  require(std::isfinite(s.lane_width) && s.lane_width > 0,
          car_field.by_role ? "lane_width" : "road.lane_width", "must be positive");
  require(s.ego.v >= 0, "ego.v", "speed must not be negative");
  for (CarIndex i = 0; i < s.cars.size(); ++i) validate_car(s, i, car_field);
  require(s.horizon > 0, "horizon", "must be positive");
  require(s.steps >= 2 && s.steps <= 10000, "steps", "must be in [2, 10000]");
  require(s.vehicle.length > 0, "vehicle.length", "must be positive");
  require(s.vehicle.width > 0 && s.vehicle.width < s.lane_width, "vehicle.width",
          "must be positive and narrower than the lane");
  require(std::abs(s.ego.theta) < std::numbers::pi / 2, "ego.theta",
          "must point forward (|theta| < pi/2)");
  require(s.ego.y >= -0.5 * s.lane_width && s.ego.y <= 1.5 * s.lane_width, "ego.y",
          s.target_side == Side::Left ? "must lie on the two-lane road [-w/2, 3w/2]"
                                      : "must lie on the two-lane road [-3w/2, w/2]");
  validate_roles(s, car_field);
  validate_no_overlap(s, car_field);
}

}  // namespace

void validate_scenario(const Scenario& s) { validate_named(s, {has_three_car_shape(s)}); }

namespace {

constexpr std::size_t kMaxCars = 1000;

const std::initializer_list<const char*> kOptionalKeys = {"horizon", "steps",         "vehicle",
                                                          "idm",     "safe_distance", "limits"};

Behavior read_behavior(const json& object, const std::string& path, const char* key) {
  const json& behavior = required(object, path, key);
  const std::string field = detail::join_path(path, key);
  require(behavior.is_string(), field, "must be a string");
  return behavior_from_string(behavior.get<std::string>(), field);
}

void read_format_1_cars(const json& root, Scenario& s) {
  if (s.behavior == Behavior::Replay) {
    throw InputError("behavior", "replay needs format 2, whose cars carry their records");
  }
  const bool accel_required = s.behavior == Behavior::ConstantAccel;
  for (const Role role : kRoles) {
    const std::string name(to_string(role));
    const json& j = require_object(root, name.c_str());
    reject_unknown_keys(j, name, {"x", "v", "a", "length", "width"});
    OtherCar& car = s.cars[static_cast<std::size_t>(role)];
    car.state = read_car_state(j, name, accel_required);
    car.behavior = s.behavior;
  }
}

Lane read_lane(const json& j, const std::string& path) {
  const std::string field = detail::join_path(path, "lane");
  const json& lane = required(j, path, "lane");
  require(lane.is_string() && (lane == "ego" || lane == "target"), field,
          "must be \"ego\" or \"target\"");
  return lane == "ego" ? Lane::Ego : Lane::Target;
}

std::optional<Role> read_role(const json& j, const std::string& path) {
  auto it = j.find("role");
  if (it == j.end()) return std::nullopt;
  for (const Role role : kRoles) {
    if (it->is_string() && it->get<std::string>() == to_string(role)) return role;
  }
  throw InputError(detail::join_path(path, "role"),
                   "must be \"leader\", \"follower\" or \"target\"");
}

OtherCar read_other_car(const json& j, const std::string& path, Behavior scene_behavior) {
  require(j.is_object(), path, "must be an object");
  reject_unknown_keys(
      j, path, {"id", "lane", "x", "v", "a", "length", "width", "behavior", "role", "record"});
  OtherCar car;
  const json& id = required(j, path, "id");
  require(id.is_string(), detail::join_path(path, "id"), "must be a string");
  car.id = id.get<std::string>();
  require(car.id.find_first_of(",\"\n\r") == std::string::npos, detail::join_path(path, "id"),
          "must not hold a comma, quote or line break (results name cars in CSV files)");
  car.lane = read_lane(j, path);
  car.behavior = j.contains("behavior") ? read_behavior(j, path, "behavior") : scene_behavior;
  car.state = read_car_state(j, path, car.behavior == Behavior::ConstantAccel);
  const auto record = j.find("record");
  if (car.behavior == Behavior::Replay) {
    if (record == j.end()) throw InputError(path + ".record", "missing: a replayed car needs one");
    car.record = detail::read_recorded_track(*record, path + ".record", car.state);
  } else if (record != j.end()) {
    throw InputError(path + ".record", "only a car of behavior replay has a record");
  }
  return car;
}

void read_road(const json& root, Scenario& s) {
  const json& road = require_object(root, "road");
  reject_unknown_keys(road, "road", {"lane_width", "target_lane"});
  s.lane_width = read_number(road, "road", "lane_width", true, 0.0);
  if (auto it = road.find("target_lane"); it != road.end()) {
    require(it->is_string() && (*it == "left" || *it == "right"), "road.target_lane",
            "must be \"left\" or \"right\"");
    s.target_side = *it == "right" ? Side::Right : Side::Left;
  }
}

// The ego as every stage sees it: a right-hand change is planned as its
// mirror image. Its own inverse.
void mirror_ego(Scenario& s) {
  s.ego.y *= mirror_sign(s.target_side);
  s.ego.theta *= mirror_sign(s.target_side);
}

// Each car's role as the file names it; where no car names one, every role
// goes to the nearest car, so a file names all of its roles or none.
void read_format_2_cars(const json& root, Scenario& s) {
  const json& list = required(root, "", "cars");
  require(list.is_array(), "cars", "must be an array");
  require(list.size() <= kMaxCars, "cars", "holds more than " + std::to_string(kMaxCars) + " cars");
  std::vector<std::optional<Role>> named;
  for (std::size_t i = 0; i < list.size(); ++i) {
    const std::string path = car_path(i);
    s.cars.push_back(read_other_car(list[i], path, s.behavior));
    named.push_back(read_role(list[i], path));
  }
  bool any_named = false;
  for (CarIndex i = 0; i < named.size(); ++i) {
    if (!named[i]) continue;
    auto& slot = s.roles[static_cast<std::size_t>(*named[i])];
    if (slot) throw InputError(car_path(i) + ".role", "another car has this role");
    slot = i;
    any_named = true;
  }
  if (!any_named) {
    for (const Role role : kRoles)
      s.roles[static_cast<std::size_t>(role)] = nearest_in_role(s, role);
  }
}

void read_car_sizes(const json& root, Scenario& s, bool format_1) {
  for (CarIndex i = 0; i < s.cars.size(); ++i) {
    const std::string path = format_1 ? s.cars[i].id : car_path(i);
    const json& j = format_1 ? root.at(s.cars[i].id) : root.at("cars").at(i);
    s.cars[i].size = read_car_size(j, path, s.vehicle);
  }
}

}  // namespace

Scenario scenario_from_json(const json& root, const Config& defaults) {
  if (!root.is_object()) throw InputError("", "a scenario must be a JSON object");
  bool format_1 = true;
  if (auto it = root.find("format"); it != root.end()) {
    format_1 = it->is_string() && it->get<std::string>() == kScenarioFormat;
    require(format_1 || (it->is_string() && it->get<std::string>() == kScenarioFormatCars),
            "format",
            "must be \"" + std::string(kScenarioFormat) + "\" or \"" +
                std::string(kScenarioFormatCars) + "\"");
  }
  std::vector<const char*> known = {"format", "behavior", "ego"};
  if (format_1) {
    known.insert(known.end(), {"lane_width", "leader", "follower", "target"});
  } else {
    known.insert(known.end(), {"road", "cars", "origin"});
  }
  known.insert(known.end(), kOptionalKeys.begin(), kOptionalKeys.end());
  for (const auto& item : root.items()) {
    if (std::find_if(known.begin(), known.end(), [&](const char* k) { return item.key() == k; }) ==
        known.end()) {
      throw InputError(item.key(), "unknown field");
    }
  }
  Scenario s = format_1 ? three_car_scenario(defaults) : default_scenario(defaults);
  if (format_1) {
    s.lane_width = read_number(root, "", "lane_width", true, 0.0);
  } else {
    read_road(root, s);
  }
  s.behavior = read_behavior(root, "", "behavior");
  s.ego = read_ego(root);
  mirror_ego(s);
  if (format_1) {
    read_format_1_cars(root, s);
  } else {
    read_format_2_cars(root, s);
    if (auto it = root.find("origin"); it != root.end()) s.origin = detail::read_scene_origin(*it);
  }
  read_optional_fields(root, s);
  read_car_sizes(root, s, format_1);
  validate_named(s, {format_1});
  effective_config(defaults, s).validate();
  return s;
}

Scenario scenario_from_text(const std::string& text, const Config& defaults) {
  return scenario_from_json(detail::parse_json_text(text, "the scenario"), defaults);
}

Scenario load_scenario(const std::string& path, const Config& defaults) {
  return scenario_from_json(detail::read_json_file(path), defaults);
}

namespace {

json car_to_json(const Scenario& s, CarIndex i, bool format_1) {
  const OtherCar& car = s.cars[i];
  json out;
  if (!format_1) {
    out["id"] = car.id;
    out["lane"] = to_string(car.lane);
    out["behavior"] = to_string(car.behavior);
    for (const Role role : kRoles) {
      if (s.roles[static_cast<std::size_t>(role)] == i) out["role"] = to_string(role);
    }
  }
  out["x"] = car.state.x;
  out["v"] = car.state.v;
  out["a"] = car.state.a;
  if (car.size) {
    out["length"] = car.size->length;
    out["width"] = car.size->width;
  }
  if (car.record) out["record"] = detail::write_recorded_track(*car.record);
  return out;
}

}  // namespace

json scenario_to_json(const Scenario& s) {
  const bool format_1 = has_three_car_shape(s);
  json out;
  out["format"] = format_1 ? kScenarioFormat : kScenarioFormatCars;
  if (format_1) {
    out["lane_width"] = s.lane_width;
  } else {
    out["road"] = {{"lane_width", s.lane_width}, {"target_lane", to_string(s.target_side)}};
  }
  out["behavior"] = to_string(s.behavior);
  const double sign = mirror_sign(s.target_side);
  out["ego"] = {{"x", s.ego.x},
                {"y", sign * s.ego.y},
                {"v", s.ego.v},
                {"theta", sign * s.ego.theta},
                {"a", s.ego.a}};
  if (format_1) {
    for (CarIndex i = 0; i < 3; ++i) out[s.cars[i].id] = car_to_json(s, i, true);
  } else {
    out["cars"] = json::array();
    for (CarIndex i = 0; i < s.cars.size(); ++i) out["cars"].push_back(car_to_json(s, i, false));
  }
  out["horizon"] = s.horizon;
  out["steps"] = s.steps;
  out["vehicle"] = detail::write_value(s.vehicle);
  out["idm"] = detail::write_value(s.idm);
  out["safe_distance"] = {{"leader", write_safe_distance(s.safe_distance.leader)},
                          {"follower", write_safe_distance(s.safe_distance.follower)},
                          {"target", write_safe_distance(s.safe_distance.target)}};
  out["limits"] = detail::write_value(s.limits);
  if (s.origin) out["origin"] = detail::write_scene_origin(*s.origin);
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
