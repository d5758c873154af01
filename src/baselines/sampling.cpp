#include "baselines/sampling.hpp"

#include <algorithm>
#include <array>
#include <cmath>

#include "lanechange/geometry.hpp"
#include "planner/miqp_planner.hpp"

namespace lanechange::baselines {

bool lane_change_on(const planner::Observation& o) {
  const Scenario& s = *o.scene;
  return o.t <= s.horizon + 1e-9 ||
         body_in_lane(o.ego.y, s.vehicle.width, s.lane_width, s.lane_width);
}

TrafficPrediction predict_from(const planner::Observation& o, const Config& config, int steps) {
  const Scenario now = planner::scene_now(o, config);
  return predict_traffic(now, config, steps, o.scene->horizon / o.scene->steps);
}

double min_separation(std::span<const EgoState> path, const TrafficPrediction& cars,
                      const Scenario& scene, double cap) {
  const double length = scene.vehicle.length;
  const double width = scene.vehicle.width;
  // Two boxes whose centres are further apart than their circumscribed
  // circles plus the cap cannot come closer than the cap.
  const double ego_reach = 0.5 * std::hypot(length, width) + cap;
  const int nodes = std::min(static_cast<int>(path.size()), cars.nodes());
  double closest = cap;
  for (int k = 0; k < nodes; ++k) {
    const EgoState& e = path[static_cast<std::size_t>(k)];
    const OrientedBox ego{e.x, e.y, e.theta, length, width};
    for (CarIndex c = 0; c < cars.car_count(); ++c) {
      const double x = cars.car(c).x[static_cast<std::size_t>(k)];
      const double y = scene.lane_center(c);
      const VehicleSize size = scene.size_of(c);
      if (std::hypot(x - e.x, y - e.y) > ego_reach + 0.5 * std::hypot(size.length, size.width)) {
        continue;
      }
      closest = std::min(closest, -overlap_depth(ego, {x, y, 0.0, size.length, size.width}));
    }
  }
  return closest;
}

bool keeps_target_lane_distances(std::span<const EgoState> path, const TrafficPrediction& cars,
                                 const Scenario& scene) {
  const int nodes = std::min(static_cast<int>(path.size()), cars.nodes());
  for (int k = 1; k < nodes; ++k) {
    const EgoState& e = path[static_cast<std::size_t>(k)];
    if (!body_in_lane(e.y, scene.vehicle.width, scene.lane_width, scene.lane_width)) continue;
    for (CarIndex c = 0; c < cars.car_count(); ++c) {
      if (scene.cars[c].lane != Lane::Target) continue;
      const auto i = static_cast<std::size_t>(k);
      const double ahead_by = cars.car(c).x[i] - e.x;
      const SafeDistance d = scene.centre_safe_distance(
          c, ahead_by >= 0 ? scene.safe_distance.target : scene.safe_distance.follower);
      const double needed =
          d.standstill + d.time_headway * (ahead_by >= 0 ? e.v : cars.car(c).v[i]);
      if (std::abs(ahead_by) < needed) return false;
    }
  }
  return true;
}

}  // namespace lanechange::baselines
