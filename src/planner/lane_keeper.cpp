#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>

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
                               const std::optional<LaneCar>& ahead,
                               const std::optional<LaneCar>& behind) const {
  // The traffic's own IDM, so the ego follows as the other cars do; its
  // desired speed is the ego's speed limit at most.
  IdmParameters idm = config_.idm;
  idm.desired_speed = std::min(idm.desired_speed, config_.limits.v.hi);
  const double speed = std::max(0.0, ego.v * std::cos(ego.theta));
  double gap = std::numeric_limits<double>::infinity();
  double ahead_speed = speed;
  if (ahead && ahead->state.x > ego.x) {
    const double centres = 0.5 * (config_.vehicle.length + ahead->length);
    gap = std::max(0.01, ahead->state.x - ego.x - centres);
    ahead_speed = ahead->state.v;
  }
  EgoControl out;
  out.a = idm_acceleration(idm, speed, gap, ahead_speed);
  if (behind) out.a = std::max(out.a, keep_up(ego.x, speed, gap, ahead_speed, *behind));
  out.omega = steer(ego, lane_center, kCalmHeading);
  return out;
}

// Steer along a heading that closes the offset: a second-order lateral
// response, damped for the speeds of the scenarios (docs/closed_loop.md).
double LaneKeeper::steer(const EgoState& ego, double lane_center, double max_heading) const {
  const ClosedLoopSettings& c = config_.closed_loop;
  const double wanted =
      std::clamp(-c.keeper_lateral_gain * (ego.y - lane_center), -max_heading, max_heading);
  return c.keeper_heading_gain * (wanted - ego.theta);
}

double LaneKeeper::back_out(const EgoState& ego, double lane_center) const {
  return steer(ego, lane_center, config_.closed_loop.keeper_backout_heading);
}

// The other cars ignore the ego: a faster one behind drives into it unless
// the ego gets out of its way. Against one that would close to the gap IDM
// would keep behind the ego (s0 + v T) within keeper_rear_horizon: the
// constant acceleration that matches its speed before the gap closes to s0
// (recomputed each step, so it corrects itself), up to the ego's bound. The
// car ahead caps it through IDM's interaction term (with no free-road
// limit), so the ego is never pushed into that car.
double LaneKeeper::keep_up(double ego_x, double speed, double gap_ahead, double ahead_speed,
                           const LaneCar& behind) const {
  constexpr double kNone = -std::numeric_limits<double>::infinity();
  const double horizon = config_.closed_loop.keeper_rear_horizon;
  const double closing = behind.state.v - speed;
  if (horizon <= 0.0 || closing <= 0.0 || behind.state.x >= ego_x) return kNone;
  const IdmParameters& idm = config_.idm;
  const double gap = ego_x - behind.state.x - 0.5 * (config_.vehicle.length + behind.length);
  if (gap - closing * horizon >= idm.min_gap + behind.state.v * idm.time_headway) return kNone;
  // The speeds are to match with a metre more than s0 left. Within half a
  // metre of that, the constant acceleration would ask for the ego's full
  // bound over the last cm, so the rest of the speed is matched in a second,
  // or with half a metre left where the car is already that close (a cut-in).
  constexpr double kAimBeyondMinGap = 1.0;  // m
  constexpr double kLeastRoom = 0.5;        // m
  constexpr double kMatchTime = 1.0;        // s
  constexpr double kContact = 0.1;          // m
  const double room = gap - idm.min_gap - kAimBeyondMinGap;
  const double strongest = std::max(idm.max_accel, config_.limits.a.hi);
  const double needed =
      std::min(room > kLeastRoom
                   ? closing * closing / (2.0 * room)
                   : std::max(closing / kMatchTime,
                              closing * closing / (2.0 * std::max(gap - kLeastRoom, kContact))),
               strongest);
  IdmParameters ahead_allows = idm;
  ahead_allows.desired_speed = std::numeric_limits<double>::infinity();
  ahead_allows.max_accel = std::max(needed, idm.max_accel);
  return std::min(needed, idm_acceleration(ahead_allows, speed, gap_ahead, ahead_speed));
}

namespace {

LaneCar lane_car(const Observation& o, CarIndex car) {
  return LaneCar{car, o.car(car), o.scene->size_of(car).length};
}

// The car of the lane nearest the ego ahead of it (ahead) or behind it.
std::optional<LaneCar> nearest_in_lane(const Observation& o, bool target_lane, bool ahead) {
  const auto car = lanechange::nearest_in_lane(
      *o.scene, o.cars, target_lane ? Lane::Target : Lane::Ego, o.ego.x, ahead);
  if (!car) return std::nullopt;
  return lane_car(o, *car);
}

}  // namespace

std::optional<LaneCar> car_ahead(const Observation& o, bool target_lane) {
  return nearest_in_lane(o, target_lane, true);
}

std::optional<LaneCar> car_behind(const Observation& o, bool target_lane) {
  return nearest_in_lane(o, target_lane, false);
}

namespace {

// How far (m) the ego is from breaking the expert's safe distances (Eq. 1)
// to the cars of a lane: negative when it already does. A car behind is
// measured by the follower's rule, one ahead by the target's (or, in the ego
// lane, the leader's).
double lane_margin(const Observation& o, bool target_lane) {
  const Scenario& s = *o.scene;
  const Lane lane = target_lane ? Lane::Target : Lane::Ego;
  const EgoState& ego = o.ego;
  double margin = std::numeric_limits<double>::infinity();
  for (CarIndex i = 0; i < o.cars.size(); ++i) {
    if (s.cars[i].lane != lane) continue;
    const CarState& c = o.car(i);
    if (c.x <= ego.x) {
      const SafeDistance d = s.centre_safe_distance(i, s.safe_distance.follower);
      margin = std::min(margin, ego.x - (c.x + d.standstill + d.time_headway * c.v));
    } else {
      const SafeDistance d =
          s.centre_safe_distance(i, target_lane ? s.safe_distance.target : s.safe_distance.leader);
      margin = std::min(margin, c.x - d.standstill - (ego.x + d.time_headway * ego.v));
    }
  }
  return margin;
}

// The nearest car of a lane with its body wholly ahead of the ego's: one
// already beside the ego is passing or being passed, and braking for it only
// stops the ego in the way of the cars behind.
std::optional<LaneCar> car_ahead_of_body(const Observation& o, bool target_lane) {
  const Lane lane = target_lane ? Lane::Target : Lane::Ego;
  double from = o.ego.x;
  while (const auto car = lanechange::nearest_in_lane(*o.scene, o.cars, lane, from, true)) {
    const double dx = o.car(*car).x - o.ego.x;
    if (o.scene->bumper_gap(*car, dx) > 0.0) return lane_car(o, *car);
    from = o.car(*car).x;
  }
  return std::nullopt;
}

}  // namespace

bool fallback_in_target_lane(const Observation& o) {
  if (o.ego.y <= o.scene->lane_width / 2.0) return false;
  // Over the line, turning back is the riskier move, unless the target lane
  // is closing in around the ego while its own lane is clear.
  const double target = lane_margin(o, true);
  return target >= 0.0 || target >= lane_margin(o, false);
}

EgoControl fallback_control(const LaneKeeper& keeper, const Observation& o) {
  const double w = o.scene->lane_width;
  const bool target_lane = fallback_in_target_lane(o);
  const double center = target_lane ? w : 0.0;
  EgoControl u =
      keeper.control(o.ego, center, car_ahead(o, target_lane), car_behind(o, target_lane));
  // Until its body has left the other lane, the ego also follows the car
  // ahead there: turning away from a car does not stop it closing in.
  const double half_body = o.scene->vehicle.width / 2.0;
  const bool in_other_lane =
      target_lane ? o.ego.y - half_body < w / 2.0 : o.ego.y + half_body > w / 2.0;
  if (in_other_lane) {
    u.a = std::min(u.a, keeper.control(o.ego, center, car_ahead_of_body(o, !target_lane)).a);
    // Backing out, the ego is in the way of the target lane's cars until its
    // body has left, 4 s and more at the keeper's calm heading; a sharper
    // one is the user's choice (docs/closed_loop.md, "Backing out").
    if (!target_lane) u.omega = keeper.back_out(o.ego, center);
  }
  return u;
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
