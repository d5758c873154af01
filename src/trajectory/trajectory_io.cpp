#include <iostream>

#include "common/json_fields.hpp"
#include "lanechange/trajectory.hpp"

namespace lanechange {

using detail::json;

std::vector<double> Trajectory::ys() const {
  std::vector<double> out;
  out.reserve(ego.size());
  for (const auto& s : ego) out.push_back(s.y);
  return out;
}

std::vector<TrackedCar> tracked_cars(const Scenario& s) {
  std::vector<TrackedCar> out;
  out.reserve(s.car_count());
  for (CarIndex i = 0; i < s.car_count(); ++i) {
    out.push_back({s.cars[i].id, s.cars[i].lane, s.size_of(i)});
  }
  return out;
}

Trajectory failed_trajectory(std::string planner, const Scenario& scenario, std::string reason) {
  Trajectory t;
  t.planner = std::move(planner);
  t.label = Label::Failure;
  t.reason = std::move(reason);
  t.dt = scenario.horizon / scenario.steps;
  t.lane_width = scenario.lane_width;
  t.target_side = scenario.target_side;
  t.t = {0.0};
  t.ego = {scenario.ego};
  t.controls = {EgoControl{}};
  t.others.dt = t.dt;
  for (CarIndex c = 0; c < scenario.car_count(); ++c) {
    const CarState& car = scenario.car(c);
    t.others.cars.push_back({{car.x}, {car.v}, {car.a}, {}});
  }
  t.cars = tracked_cars(scenario);
  return t;
}

namespace {

template <class F>
std::vector<double> column(const std::vector<EgoState>& states, F field) {
  std::vector<double> out;
  out.reserve(states.size());
  for (const auto& s : states) out.push_back(field(s));
  return out;
}

std::vector<double> read_array(const json& parent, const std::string& path, const char* key,
                               std::size_t expected) {
  auto it = parent.find(key);
  const std::string field = detail::join_path(path, key);
  if (it == parent.end()) throw InputError(field, "missing required field");
  if (!it->is_array()) throw InputError(field, "must be an array");
  if (it->size() != expected) {
    throw InputError(field, "has " + std::to_string(it->size()) + " entries, expected " +
                                std::to_string(expected));
  }
  std::vector<double> out(expected);
  for (std::size_t i = 0; i < expected; ++i) {
    detail::read_value((*it)[i], field + "[" + std::to_string(i) + "]", out[i]);
  }
  return out;
}

const json& object_at(const json& parent, const std::string& path, const char* key) {
  auto it = parent.find(key);
  const std::string field = detail::join_path(path, key);
  if (it == parent.end()) throw InputError(field, "missing required field");
  if (!it->is_object()) throw InputError(field, "must be an object");
  return *it;
}

}  // namespace

json trajectory_to_json(const Trajectory& tr) {
  json out = tr.details.is_object() ? tr.details : json::object();
  out["format"] = kTrajectoryFormat;
  out["planner"] = tr.planner;
  out["label"] = to_string(tr.label);
  if (!tr.reason.empty()) out["reason"] = tr.reason;
  out["dt"] = tr.dt;
  out["lane_width"] = tr.lane_width;
  out["target_lane"] = to_string(tr.target_side);
  out["t"] = tr.t;
  const double sign = mirror_sign(tr.target_side);
  std::vector<double> a, omega;
  for (const auto& u : tr.controls) {
    a.push_back(u.a);
    omega.push_back(sign * u.omega);
  }
  out["ego"] = {{"x", column(tr.ego, [](const EgoState& s) { return s.x; })},
                {"y", column(tr.ego, [&](const EgoState& s) { return sign * s.y; })},
                {"v", column(tr.ego, [](const EgoState& s) { return s.v; })},
                {"theta", column(tr.ego, [&](const EgoState& s) { return sign * s.theta; })},
                {"a", a},
                {"omega", omega}};
  json others = json::array();
  for (CarIndex c = 0; c < tr.others.car_count(); ++c) {
    const TrackedCar& who = c < tr.cars.size() ? tr.cars[c] : TrackedCar{};
    const CarTrack& track = tr.others.car(c);
    others.push_back({{"id", who.id},
                      {"lane", to_string(who.lane)},
                      {"length", who.size.length},
                      {"width", who.size.width},
                      {"x", track.x},
                      {"v", track.v}});
    if (!track.present.empty()) {
      json& present = others.back()["present"] = json::array();
      for (const char p : track.present) present.push_back(p != 0);
    }
  }
  out["others"] = others;
  out["collision"] = tr.collision;
  out["compute_ms"] = {{"total", tr.compute_total_ms}, {"max_step", tr.compute_max_step_ms}};
  return out;
}

namespace {

CarTrack read_track(const json& car, const std::string& path, std::size_t nodes) {
  CarTrack track;
  track.x = read_array(car, path, "x", nodes);
  track.v = read_array(car, path, "v", nodes);
  track.a.assign(nodes, 0.0);
  const auto present = car.find("present");
  if (present == car.end()) return track;
  const std::string field = detail::join_path(path, "present");
  if (!present->is_array() || present->size() != nodes) {
    throw InputError(field, "must be an array of one true or false per node");
  }
  for (const json& p : *present) {
    if (!p.is_boolean()) throw InputError(field, "must hold only true or false");
    track.present.push_back(p.get<bool>() ? 1 : 0);
  }
  return track;
}

TrackedCar read_tracked_car(const json& car, const std::string& path) {
  TrackedCar who;
  detail::read_value(car.value("id", json()), detail::join_path(path, "id"), who.id);
  std::string lane;
  detail::read_value(car.value("lane", json()), detail::join_path(path, "lane"), lane);
  if (lane != "ego" && lane != "target") {
    throw InputError(detail::join_path(path, "lane"), "must be \"ego\" or \"target\"");
  }
  who.lane = lane == "ego" ? Lane::Ego : Lane::Target;
  detail::read_value(car.value("length", json()), detail::join_path(path, "length"),
                     who.size.length);
  detail::read_value(car.value("width", json()), detail::join_path(path, "width"), who.size.width);
  if (!(who.size.length > 0.0) || !(who.size.width > 0.0)) {
    throw InputError(detail::join_path(path, "length"), "a car's body must be positive");
  }
  return who;
}

// Format 1 keys the paper's three cars by role and gives no bodies: each has
// the default one.
void read_others(const json& in, bool three_cars, std::size_t nodes, Trajectory& tr) {
  tr.others.dt = tr.dt;
  if (three_cars) {
    const json& others = object_at(in, "", "others");
    for (const Role role : kRoles) {
      const std::string name(to_string(role));
      tr.others.cars.push_back(
          read_track(object_at(others, "others", name.c_str()), "others." + name, nodes));
      tr.cars.push_back({name, role == Role::Leader ? Lane::Ego : Lane::Target, VehicleSize{}});
    }
    return;
  }
  auto it = in.find("others");
  if (it == in.end() || !it->is_array()) throw InputError("others", "must be an array");
  for (std::size_t i = 0; i < it->size(); ++i) {
    std::string path = "others[";
    path += std::to_string(i);
    path += ']';
    const json& car = (*it)[i];
    if (!car.is_object()) throw InputError(path, "must be an object");
    tr.cars.push_back(read_tracked_car(car, path));
    tr.others.cars.push_back(read_track(car, path, nodes));
  }
}

}  // namespace

Trajectory trajectory_from_json(const json& in) {
  if (!in.is_object()) throw InputError("", "a trajectory must be a JSON object");
  Trajectory tr;
  auto format = in.find("format");
  const bool three_cars =
      format != in.end() && format->is_string() && *format == kTrajectoryFormatThreeCars;
  if (!three_cars && (format == in.end() || !format->is_string() || *format != kTrajectoryFormat)) {
    throw InputError("format", "must be \"" + std::string(kTrajectoryFormat) + "\" or \"" +
                                   std::string(kTrajectoryFormatThreeCars) + "\"");
  }
  tr.details = in;
  for (const char* k : {"format", "planner", "label", "reason", "dt", "lane_width", "target_lane",
                        "t", "ego", "others", "collision", "compute_ms"}) {
    tr.details.erase(k);
  }
  detail::read_value(in.value("planner", json("")), "planner", tr.planner);
  std::string label;
  detail::read_value(in.value("label", json()), "label", label);
  tr.label = label_from_string(label);
  if (in.contains("reason")) detail::read_value(in["reason"], "reason", tr.reason);
  detail::read_value(in.value("dt", json()), "dt", tr.dt);
  tr.lane_width = 3.75;
  if (in.contains("lane_width")) detail::read_value(in["lane_width"], "lane_width", tr.lane_width);
  if (in.contains("target_lane")) {
    const json& side = in["target_lane"];
    if (!side.is_string() || (side != "left" && side != "right")) {
      throw InputError("target_lane", "must be \"left\" or \"right\"");
    }
    tr.target_side = side == "right" ? Side::Right : Side::Left;
  }
  const double sign = mirror_sign(tr.target_side);
  if (!in.contains("t") || !in["t"].is_array()) throw InputError("t", "must be an array");
  const std::size_t n = in["t"].size();
  tr.t = read_array(in, "", "t", n);
  const json& ego = object_at(in, "", "ego");
  const auto x = read_array(ego, "ego", "x", n), y = read_array(ego, "ego", "y", n),
             v = read_array(ego, "ego", "v", n), th = read_array(ego, "ego", "theta", n),
             a = read_array(ego, "ego", "a", n), w = read_array(ego, "ego", "omega", n);
  for (std::size_t k = 0; k < n; ++k) {
    tr.ego.push_back({x[k], sign * y[k], v[k], sign * th[k], a[k]});
    tr.controls.push_back({a[k], sign * w[k]});
  }
  read_others(in, three_cars, n, tr);
  if (in.contains("collision")) detail::read_value(in["collision"], "collision", tr.collision);
  if (in.contains("compute_ms") && in["compute_ms"].is_object()) {
    const json& ms = in["compute_ms"];
    if (ms.contains("total"))
      detail::read_value(ms["total"], "compute_ms.total", tr.compute_total_ms);
    if (ms.contains("max_step")) {
      detail::read_value(ms["max_step"], "compute_ms.max_step", tr.compute_max_step_ms);
    }
  }
  return tr;
}

Trajectory load_trajectory(const std::string& path) {
  return trajectory_from_json(detail::read_json_file(path));
}

void save_trajectory(const Trajectory& trajectory, const std::string& path) {
  const std::string text = trajectory_to_json(trajectory).dump() + "\n";
  if (path.empty() || path == "-") {
    std::cout << text;
    return;
  }
  detail::write_file_atomically(path, text);
}

}  // namespace lanechange
