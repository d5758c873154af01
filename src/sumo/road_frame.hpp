#pragma once
// Our frame on a SUMO road: x along the centre line of the ego's lane (which
// may bend), y across it towards the target lane, theta against the lane's
// direction. SUMO's world coordinates map to it and back.
#include <optional>
#include <vector>

#include "commonroad/lanes.hpp"
#include "lanechange/scenario.hpp"

namespace lanechange::sumo::detail {

using WorldPoint = commonroad::Point;

/// A pose in SUMO's world: position and heading (rad, counter-clockwise from +x).
struct WorldPose {
  double x = 0.0;
  double y = 0.0;
  double heading = 0.0;
};

/// A pose in our frame.
struct RoadPose {
  double x = 0.0;  ///< along the ego lane's centre line
  double y = 0.0;  ///< across it, positive towards the target lane
  double theta = 0.0;
};

class RoadFrame {
 public:
  /// `centre`: the ego lane's centre line in driving order (two distinct
  /// points at least); the target lane lies to the `side` of it.
  RoadFrame(const std::vector<WorldPoint>& centre, double lane_width, Side side);

  /// Beyond either end the line goes on straight.
  [[nodiscard]] RoadPose to_road(const WorldPose& world) const;
  [[nodiscard]] WorldPose to_world(const RoadPose& road) const;
  /// The lane of a car whose centre is `y` across: the ego lane, the target
  /// lane, or none (a lane further out).
  [[nodiscard]] std::optional<Lane> lane_at(double y) const;

  [[nodiscard]] double lane_width() const { return lane_width_; }
  [[nodiscard]] Side side() const { return side_; }

 private:
  commonroad::detail::Polyline centre_;
  double lane_width_;
  Side side_;
};

}  // namespace lanechange::sumo::detail
