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

double front_x(const EgoState& e, double length) { return e.x + 0.5 * length * std::cos(e.theta); }
double front_y(const RoadFrame& f, const EgoState& e, double length) {
  return f.ego_lane_y() + e.y + 0.5 * length * std::sin(e.theta);
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

double SumoConnection::time() const { return libsumo::Simulation::getTime(); }

EgoState SumoConnection::insert_ego(const RoadFrame& frame, double x, const VehicleSize& ego,
                                    const Limits& limits) {
  using libsumo::Vehicle;
  const auto ids = libsumo::Lane::getLastStepVehicleIDs(
      frame.lane_ids.at(static_cast<std::size_t>(frame.ego_lane)));
  if (ids.empty())
    throw std::runtime_error("SUMO: no car on the ego lane to hand its place to the ego");
  std::string nearest = ids.front();
  for (const std::string& id : ids) {
    if (std::abs(Vehicle::getLanePosition(id) - x) <
        std::abs(Vehicle::getLanePosition(nearest) - x)) {
      nearest = id;
    }
  }
  const double front = Vehicle::getLanePosition(nearest);
  const std::string route = Vehicle::getRouteID(nearest);
  EgoState e;
  e.v = std::clamp(Vehicle::getSpeed(nearest), limits.v.lo, limits.v.hi);
  e.x = front - 0.5 * ego.length;
  Vehicle::remove(nearest);
  libsumo::VehicleType::copy("DEFAULT_VEHTYPE", kEgoId);
  libsumo::VehicleType::setLength(kEgoId, ego.length);
  libsumo::VehicleType::setWidth(kEgoId, ego.width);
  Vehicle::add(kEgoId, route, kEgoId, "now", std::to_string(frame.ego_lane), std::to_string(front),
               std::to_string(e.v));
  Vehicle::setSpeedMode(kEgoId, kSpeedModeNone);
  Vehicle::setLaneChangeMode(kEgoId, 0);
  move_ego(frame, e, ego.length);
  return e;
}

void SumoConnection::move_ego(const RoadFrame& frame, const EgoState& e, double ego_length) {
  const double angle = 90.0 - e.theta * 180.0 / std::numbers::pi;  // SUMO: clockwise from north
  libsumo::Vehicle::moveToXY(kEgoId, frame.edge, -1, front_x(e, ego_length),
                             front_y(frame, e, ego_length), angle, kKeepRouteExact);
  libsumo::Vehicle::setSpeed(kEgoId, e.v);
}

double SumoConnection::ego_pose_error(const RoadFrame& frame, const EgoState& e,
                                      double ego_length) const {
  const libsumo::TraCIPosition p = libsumo::Vehicle::getPosition(kEgoId);
  return std::hypot(p.x - front_x(e, ego_length), p.y - front_y(frame, e, ego_length));
}

void SumoConnection::cars_near(const RoadFrame& frame, double x, double reach,
                               std::vector<SumoCar>& out) const {
  using libsumo::Vehicle;
  out.clear();
  for (const Lane lane : {Lane::Ego, Lane::Target}) {
    const int index = frame.ego_lane + (lane == Lane::Target ? 1 : 0);
    for (const std::string& id :
         libsumo::Lane::getLastStepVehicleIDs(frame.lane_ids.at(static_cast<std::size_t>(index)))) {
      if (id == kEgoId) continue;
      const double length = Vehicle::getLength(id);
      const double centre = Vehicle::getLanePosition(id) - 0.5 * length;
      if (std::abs(centre - x) > reach) continue;
      out.push_back({id,
                     lane,
                     {centre, Vehicle::getSpeed(id), Vehicle::getAcceleration(id)},
                     {length, Vehicle::getWidth(id)}});
    }
  }
}

double SumoConnection::cars_behind_ego(const std::vector<SumoCar>& cars,
                                       std::set<std::string>& followers) const {
  double hardest = 0.0;
  for (const SumoCar& car : cars) {
    if (libsumo::Vehicle::getLeader(car.id).first != kEgoId) continue;
    followers.insert(car.id);
    hardest = std::max(hardest, -car.state.a);
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
