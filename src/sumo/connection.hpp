#pragma once
// libsumo, behind the few calls the co-simulation makes. libsumo's state is
// global: one simulation per process.
#include <set>
#include <string>
#include <vector>

#include "lanechange/config.hpp"
#include "lanechange/scenario.hpp"

namespace lanechange::sumo::detail {

/// A SUMO car on one of the two lanes of a lane change, in our frame.
struct SumoCar {
  std::string id;
  Lane lane = Lane::Ego;
  CarState state;  ///< x of its centre along the road
  VehicleSize size;
};

/// A straight road along +x: SUMO's lane i is centred at y = (i + 1/2) w.
struct RoadFrame {
  std::string edge;
  std::vector<std::string> lane_ids;  ///< by SUMO lane index
  int ego_lane = 0;                   ///< SUMO index; the target lane is ego_lane + 1
  double lane_width = 3.75;
  [[nodiscard]] double ego_lane_y() const { return (ego_lane + 0.5) * lane_width; }
};

/// A contact SUMO reported.
struct SumoContact {
  std::string other;
  bool ego_collider = false;  ///< SUMO names the ego the collider (it ran into the other)
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
  [[nodiscard]] double time() const;

  /// Puts the ego in place of the SUMO car of `frame.ego_lane` nearest `x`
  /// (front bumper, m along the road), with that car's speed; returns the
  /// ego's state in our frame (x its centre), its speed clipped to `limits`.
  [[nodiscard]] EgoState insert_ego(const RoadFrame& frame, double x, const VehicleSize& ego,
                                    const Limits& limits);
  /// Moves the ego to `ego` (our frame) before the next step.
  void move_ego(const RoadFrame& frame, const EgoState& ego, double ego_length);
  /// The distance (m) between SUMO's ego front bumper and ours.
  [[nodiscard]] double ego_pose_error(const RoadFrame& frame, const EgoState& ego,
                                      double ego_length) const;

  /// The cars of the ego and target lanes whose centres are within `reach`
  /// of x, in SUMO's order.
  void cars_near(const RoadFrame& frame, double x, double reach, std::vector<SumoCar>& out) const;
  /// The cars among `cars` whose leader in SUMO is the ego: their ids are
  /// added to `followers`; returns their hardest braking (m/s^2, 0: none).
  double cars_behind_ego(const std::vector<SumoCar>& cars, std::set<std::string>& followers) const;
  /// The contacts with the ego SUMO reported in the last step.
  [[nodiscard]] std::vector<SumoContact> ego_contacts() const;
};

/// The ego's id in SUMO.
inline constexpr const char* kEgoId = "ego";

}  // namespace lanechange::sumo::detail
