#include <algorithm>
#include <cmath>
#include <limits>

#include "lanechange/planner/planner.hpp"
#include "lanechange/traffic.hpp"

namespace lanechange::planner {

std::string_view to_string(ActStatus status) {
  switch (status) {
    case ActStatus::Planned: return "planned";
    case ActStatus::TookOver: return "took_over";
    case ActStatus::Fallback: return "fallback";
    case ActStatus::Failed: return "failed";
  }
  return "?";
}

EgoControl LaneKeeper::control(const EgoState& ego, double lane_center,
                               const CarState* ahead) const {
  const ClosedLoopSettings& c = config_.closed_loop;
  // The traffic's own IDM, so the ego follows as the other cars do; its
  // desired speed is the ego's speed limit at most.
  IdmParameters idm = config_.idm;
  idm.desired_speed = std::min(idm.desired_speed, config_.limits.v.hi);
  const double speed = std::max(0.0, ego.v * std::cos(ego.theta));
  double gap = std::numeric_limits<double>::infinity();
  double ahead_speed = speed;
  if (ahead != nullptr && ahead->x > ego.x) {
    gap = std::max(0.01, ahead->x - ego.x - config_.vehicle.length);
    ahead_speed = ahead->v;
  }
  EgoControl out;
  out.a = idm_acceleration(idm, speed, gap, ahead_speed);
  // Steer along a heading that closes the offset: a second-order lateral
  // response, damped for the speeds of the scenarios (docs/closed_loop.md).
  constexpr double kMaxHeading = 0.15;  // rad: a calm return, never a swerve
  const double wanted =
      std::clamp(-c.keeper_lateral_gain * (ego.y - lane_center), -kMaxHeading, kMaxHeading);
  out.omega = c.keeper_heading_gain * (wanted - ego.theta);
  return out;
}

const CarState* car_ahead(const Observation& o, bool target_lane) {
  if (!target_lane) return &o.car(Car::Leader);
  // In the target lane the follower may be ahead once the ego fell behind it.
  const CarState* best = nullptr;
  for (const Car car : {Car::Follower, Car::Target}) {
    const CarState& c = o.car(car);
    if (c.x > o.ego.x && (best == nullptr || c.x < best->x)) best = &c;
  }
  return best;
}

EgoControl fallback_control(const LaneKeeper& keeper, const Observation& o) {
  const double w = o.scene->lane_width;
  const bool target_lane = o.ego.y > w / 2.0;
  return keeper.control(o.ego, target_lane ? w : 0.0, car_ahead(o, target_lane));
}

bool body_on_road(double y, const Scenario& scene) {
  const double half_body = scene.vehicle.width / 2.0;
  return y - half_body >= -scene.lane_width / 2.0 && y + half_body <= 1.5 * scene.lane_width;
}

bool clip_to_limits(EgoControl& control, const EgoState& ego, const Limits& limits, double dt) {
  const EgoControl wanted = control;
  // A non-finite control is no control: hold speed and heading rate.
  if (!std::isfinite(control.a)) control.a = 0.0;
  if (!std::isfinite(control.omega)) control.omega = 0.0;
  // The speed must stay in its bounds over the step; a speed already
  // outside them may only move back towards them.
  const double a_lo = std::max(limits.a.lo, std::min(0.0, (limits.v.lo - ego.v) / dt));
  const double a_hi = std::min(limits.a.hi, std::max(0.0, (limits.v.hi - ego.v) / dt));
  control.a = std::clamp(control.a, a_lo, std::max(a_lo, a_hi));
  control.omega = std::clamp(control.omega, limits.omega.lo, limits.omega.hi);
  constexpr double kTolerance = 1e-9;
  // NaN compares unequal, so a non-finite wish counts as clipped.
  return !(std::abs(control.a - wanted.a) <= kTolerance &&
           std::abs(control.omega - wanted.omega) <= kTolerance);
}

}  // namespace lanechange::planner
