#include "sumo/connection.hpp"

#include <libsumo/libsumo.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <numbers>
#include <stdexcept>

namespace lanechange::sumo::detail {

namespace {

std::atomic<bool> loaded{false};

constexpr int kSpeedModeNone = 0;   // SUMO checks nothing: our ego model moves the ego
constexpr int kKeepRouteExact = 2;  // moveToXY: exactly there, lateral offset included

// SUMO's angles run clockwise from north in degrees.
double heading_of_angle(double degrees) { return (90.0 - degrees) * std::numbers::pi / 180.0; }
double angle_of_heading(double heading) { return 90.0 - heading * 180.0 / std::numbers::pi; }

WorldPose ego_front(const RoadFrame& f, const EgoState& e, double length) {
  const WorldPose centre = f.to_world({e.x, e.y, e.theta});
  return {centre.x + 0.5 * length * std::cos(centre.heading),
          centre.y + 0.5 * length * std::sin(centre.heading), centre.heading};
}

// A SUMO car's centre and heading: SUMO gives its front bumper.
WorldPose centre_of(const std::string& id, double length) {
  const libsumo::TraCIPosition front = libsumo::Vehicle::getPosition(id);
  const double heading = heading_of_angle(libsumo::Vehicle::getAngle(id));
  return {front.x - 0.5 * length * std::cos(heading), front.y - 0.5 * length * std::sin(heading),
          heading};
}

void set_up_ego_type(const VehicleSize& size) {
  libsumo::VehicleType::copy("DEFAULT_VEHTYPE", kEgoId);
  libsumo::VehicleType::setLength(kEgoId, size.length);
  libsumo::VehicleType::setWidth(kEgoId, size.width);
}

}  // namespace

SumoConnection::SumoConnection(const std::vector<std::string>& args) {
  if (loaded.exchange(true)) {
    throw std::logic_error("libsumo holds one simulation per process, and one is loaded");
  }
  try {
    libsumo::Simulation::load(args);
  } catch (...) {
    loaded = false;
    throw;
  }
}

SumoConnection::~SumoConnection() {
  try {
    libsumo::Simulation::close();
  } catch (...) {  // NOLINT(bugprone-empty-catch): nothing is left to close
  }
  loaded = false;
}

void SumoConnection::step() { libsumo::Simulation::step(); }

EgoRoad SumoConnection::road_at(double x, double y) const {
  const libsumo::TraCIRoadPosition at = libsumo::Simulation::convertRoad(x, y, false, "passenger");
  if (at.edgeID.empty() || at.laneIndex < 0) {
    throw std::runtime_error("SUMO: no lane near (" + std::to_string(x) + ", " + std::to_string(y) +
                             ")");
  }
  EgoRoad road;
  road.lane_index = at.laneIndex;
  road.lanes = libsumo::Edge::getLaneNumber(at.edgeID);
  std::string lane = at.edgeID + "_" + std::to_string(at.laneIndex);
  road.lane_width = libsumo::Lane::getWidth(lane);
  road.speed_limit = libsumo::Lane::getMaxSpeed(lane);
  const auto add_shape = [&road](const std::string& id) {
    for (const libsumo::TraCIPosition& p : libsumo::Lane::getShape(id).value) {
      const bool repeats = !road.centre.empty() && std::hypot(p.x - road.centre.back().x,
                                                              p.y - road.centre.back().y) < 0.01;
      if (!repeats) road.centre.push_back({p.x, p.y});
    }
  };
  // A network without loops ends; the bound only guards against one with.
  for (int hops = 0; hops < 1000 && !lane.empty(); ++hops) {
    road.edges.push_back(libsumo::Lane::getEdgeID(lane));
    add_shape(lane);
    const std::vector<libsumo::TraCIConnection> links = libsumo::Lane::getLinks(lane);
    if (links.empty()) break;
    const auto straight =
        std::find_if(links.begin(), links.end(),
                     [](const libsumo::TraCIConnection& c) { return c.direction == "s"; });
    const libsumo::TraCIConnection& next = straight != links.end() ? *straight : links.front();
    if (!next.approachedInternal.empty()) add_shape(next.approachedInternal);
    lane = next.approachedLane;
  }
  return road;
}

EgoState SumoConnection::replace_car_with_ego(const RoadFrame& frame, const std::string& lane_id,
                                              double front, const VehicleSize& ego,
                                              const Limits& limits) {
  using libsumo::Vehicle;
  const auto ids = libsumo::Lane::getLastStepVehicleIDs(lane_id);
  if (ids.empty())
    throw std::runtime_error("SUMO: no car on " + lane_id + " to hand its place to the ego");
  std::string nearest = ids.front();
  for (const std::string& id : ids) {
    if (std::abs(Vehicle::getLanePosition(id) - front) <
        std::abs(Vehicle::getLanePosition(nearest) - front)) {
      nearest = id;
    }
  }
  const double length = Vehicle::getLength(nearest);
  const RoadPose at = frame.to_road(centre_of(nearest, length));
  EgoState e;
  // Its front where the car's front was.
  e.x = at.x + 0.5 * (length - ego.length);
  e.v = std::clamp(Vehicle::getSpeed(nearest), limits.v.lo, limits.v.hi);
  const std::string route = Vehicle::getRouteID(nearest);
  const int lane = Vehicle::getLaneIndex(nearest);
  const double position = Vehicle::getLanePosition(nearest);
  Vehicle::remove(nearest);
  set_up_ego_type(ego);
  Vehicle::add(kEgoId, route, kEgoId, "now", std::to_string(lane), std::to_string(position),
               std::to_string(e.v));
  Vehicle::setSpeedMode(kEgoId, kSpeedModeNone);
  Vehicle::setLaneChangeMode(kEgoId, 0);
  move_ego(frame, e, ego.length);
  return e;
}

void SumoConnection::add_ego(const RoadFrame& frame, const std::vector<std::string>& edges,
                             const EgoState& ego, const VehicleSize& size) {
  using libsumo::Vehicle;
  libsumo::Route::add("ego_route", edges);
  set_up_ego_type(size);
  Vehicle::add(kEgoId, "ego_route", kEgoId, "now", "best", "base", std::to_string(ego.v));
  Vehicle::setSpeedMode(kEgoId, kSpeedModeNone);
  Vehicle::setLaneChangeMode(kEgoId, 0);
  move_ego(frame, ego, size.length);
}

void SumoConnection::move_ego(const RoadFrame& frame, const EgoState& e, double ego_length) {
  const WorldPose front = ego_front(frame, e, ego_length);
  libsumo::Vehicle::moveToXY(kEgoId, "", -1, front.x, front.y, angle_of_heading(front.heading),
                             kKeepRouteExact);
  libsumo::Vehicle::setSpeed(kEgoId, e.v);
}

void SumoConnection::signal_ego_change(int lane_offset, double seconds) {
  libsumo::Vehicle::changeLaneRelative(kEgoId, lane_offset, seconds);
}

double SumoConnection::ego_pose_error(const RoadFrame& frame, const EgoState& e,
                                      double ego_length) const {
  const libsumo::TraCIPosition p = libsumo::Vehicle::getPosition(kEgoId);
  const WorldPose front = ego_front(frame, e, ego_length);
  return std::hypot(p.x - front.x, p.y - front.y);
}

void SumoConnection::cars_near(const RoadFrame& frame, double x, double reach,
                               std::vector<SumoCar>& out) const {
  using libsumo::Vehicle;
  out.clear();
  for (const std::string& id : Vehicle::getIDList()) {
    if (id == kEgoId) continue;
    const double length = Vehicle::getLength(id);
    const RoadPose at = frame.to_road(centre_of(id, length));
    const auto lane = frame.lane_at(at.y);
    if (!lane || std::abs(at.x - x) > reach) continue;
    out.push_back({id,
                   *lane,
                   {at.x, Vehicle::getSpeed(id), Vehicle::getAcceleration(id)},
                   {length, Vehicle::getWidth(id)}});
  }
}

FollowerBraking SumoConnection::cars_behind_ego(const std::vector<SumoCar>& cars, double dt,
                                                std::set<std::string>& followers) const {
  using libsumo::Vehicle;
  FollowerBraking hardest;
  const double ego_speed = Vehicle::getSpeed(kEgoId);
  const double ego_decel = Vehicle::getDecel(kEgoId);
  for (const SumoCar& car : cars) {
    // A car of the ego lane has followed the ego from the start: its
    // braking is no cut-in's.
    if (car.lane != Lane::Target) continue;
    const auto [leader, gap] = Vehicle::getLeader(car.id);
    if (leader != kEgoId) continue;
    followers.insert(car.id);
    // SUMO's cars also brake to open a gap the ego signals for, at up to
    // their full deceleration, where following the ego needs none: that is
    // SUMO's cooperation, not braking the cut-in forced.
    const double safe_speed =
        Vehicle::getFollowSpeed(car.id, car.state.v, gap, ego_speed, ego_decel, kEgoId);
    hardest.forced = std::max(hardest.forced, (car.state.v - safe_speed) / dt);
    hardest.actual = std::max(hardest.actual, -car.state.a);
  }
  return hardest;
}

std::vector<SumoContact> SumoConnection::ego_contacts() const {
  std::vector<SumoContact> out;
  for (const libsumo::TraCICollision& c : libsumo::Simulation::getCollisions()) {
    if (c.collider == kEgoId) out.push_back({c.victim, true});
    if (c.victim == kEgoId) out.push_back({c.collider, false});
  }
  return out;
}

}  // namespace lanechange::sumo::detail
