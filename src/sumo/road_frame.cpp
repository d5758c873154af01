#include "sumo/road_frame.hpp"

#include <cmath>
#include <numbers>

namespace lanechange::sumo::detail {

namespace {

double wrap(double angle) { return std::remainder(angle, 2.0 * std::numbers::pi); }

}  // namespace

RoadFrame::RoadFrame(const std::vector<WorldPoint>& centre, double lane_width, Side side)
    : centre_(centre), lane_width_(lane_width), side_(side) {}

RoadPose RoadFrame::to_road(const WorldPose& p) const {
  const commonroad::detail::Projection on = centre_.project({p.x, p.y});
  const double sign = mirror_sign(side_);
  return {on.s, sign * on.d, sign * wrap(p.heading - on.heading)};
}

WorldPose RoadFrame::to_world(const RoadPose& r) const {
  const double sign = mirror_sign(side_);
  WorldPoint point;
  const commonroad::detail::Projection on = centre_.place(r.x, sign * r.y, point);
  return {point.x, point.y, on.heading + sign * r.theta};
}

std::optional<Lane> RoadFrame::lane_at(double y) const {
  if (std::abs(y) <= lane_width_ / 2.0) return Lane::Ego;
  if (std::abs(y - lane_width_) <= lane_width_ / 2.0) return Lane::Target;
  return std::nullopt;
}

}  // namespace lanechange::sumo::detail
