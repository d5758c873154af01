#pragma once
// libsumo, behind the few calls the co-simulation makes. libsumo's state is
// global: one simulation per process.
#include <set>
#include <string>
#include <vector>

#include "lanechange/config.hpp"
#include "lanechange/scenario.hpp"
#include "sumo/road_frame.hpp"

namespace lanechange::sumo::detail {

/// A SUMO car on one of the two lanes of a lane change, in our frame.
struct SumoCar {
  std::string id;
  Lane lane = Lane::Ego;
  CarState state;  ///< x of its centre along the road
  VehicleSize size;
};

/// The car as a scene's car of `behavior`.
[[nodiscard]] inline OtherCar as_other_car(const SumoCar& car, Behavior behavior) {
  OtherCar other;
  other.id = car.id;
  other.lane = car.lane;
  other.state = car.state;
  other.behavior = behavior;
  other.size = car.size;
  return other;
}

/// A contact SUMO reported.
struct SumoContact {
  std::string other;
  bool ego_collider = false;  ///< SUMO names the ego the collider (it ran into the other)
};

/// How hard the cars behind the ego brake, m/s^2 (0: none).
struct FollowerBraking {
  /// What each car's own car-following model demands with the ego as its
  /// leader: the braking the ego's place forces on it.
  double forced = 0.0;
  /// What the cars did, their yielding to the ego's signalled change and
  /// their driver imperfection included.
  double actual = 0.0;
};

/// The ego's id in SUMO.
inline constexpr const char* kEgoId = "ego";

/// The road of an ego that starts at a point of SUMO's network.
struct EgoRoad {
  std::vector<WorldPoint> centre;  ///< its lane's centre line, on through the lanes it leads to
  std::vector<std::string> edges;  ///< the route along it
  int lane_index = 0;              ///< its lane's, 0 the rightmost
  int lanes = 1;                   ///< of its edge
  double lane_width = 0.0;
  double speed_limit = 0.0;
};

/// Loads a simulation on construction and closes it on destruction.
class SumoConnection {
 public:
  /// `args` as SUMO's command line, without the program's name.
  explicit SumoConnection(const std::vector<std::string>& args);
  ~SumoConnection();
  SumoConnection(const SumoConnection&) = delete;
  SumoConnection& operator=(const SumoConnection&) = delete;

  void step();

  /// The lane of SUMO's network nearest the point, and the lanes it leads to
  /// (straight on where it forks). std::runtime_error where no lane is near.
  [[nodiscard]] EgoRoad road_at(double x, double y) const;

  /// Puts the ego in place of the SUMO car on `lane_id` whose front is
  /// nearest `front` (m along the lane), with that car's speed; returns the
  /// ego's state in our frame, its speed clipped to `limits`.
  [[nodiscard]] EgoState replace_car_with_ego(const RoadFrame& frame, const std::string& lane_id,
                                              double front, const VehicleSize& ego,
                                              const Limits& limits);
  /// Adds the ego at `ego` (our frame) on a route of `edges`.
  void add_ego(const RoadFrame& frame, const std::vector<std::string>& edges, const EgoState& ego,
               const VehicleSize& size);
  /// Moves the ego to `ego` (our frame) before the next step.
  void move_ego(const RoadFrame& frame, const EgoState& ego, double ego_length);
  /// Asks SUMO's lane-change model of the ego for a change of `lane_offset`
  /// lanes (+1 left) for `seconds`: SUMO's cars around it answer the wish
  /// (cooperative slowing), while moveToXY keeps placing the ego.
  void signal_ego_change(int lane_offset, double seconds);
  /// The distance (m) between SUMO's ego front bumper and ours.
  [[nodiscard]] double ego_pose_error(const RoadFrame& frame, const EgoState& ego,
                                      double ego_length) const;

  /// The cars of the ego and target lanes whose centres are within `reach`
  /// of x, in SUMO's order.
  void cars_near(const RoadFrame& frame, double x, double reach, std::vector<SumoCar>& out) const;
  /// The target-lane cars among `cars` whose leader in SUMO is the ego (the
  /// ego cut in ahead of them): their ids are added to `followers`; returns
  /// their hardest braking, forced and actual, over the next step of `dt` s.
  [[nodiscard]] FollowerBraking cars_behind_ego(const std::vector<SumoCar>& cars, double dt,
                                                std::set<std::string>& followers) const;
  /// The contacts with the ego SUMO reported in the last step.
  [[nodiscard]] std::vector<SumoContact> ego_contacts() const;
};

}  // namespace lanechange::sumo::detail
