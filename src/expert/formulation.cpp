#include "lanechange/expert/formulation.hpp"

#include <algorithm>
#include <cmath>
#include <initializer_list>
#include <numbers>
#include <optional>
#include <string>

#include "lanechange/traffic.hpp"

namespace lanechange::expert {

std::string_view to_string(LaneOccupancy occupancy) {
  switch (occupancy) {
    case LaneOccupancy::EgoLane: return "ego_lane";
    case LaneOccupancy::BothLanes: return "both_lanes";
    case LaneOccupancy::TargetLane: return "target_lane";
  }
  return "?";
}

namespace {

// Linearization of (v cos theta, v sin theta) at (v_bar, theta_bar): each is
// dv * v + dtheta * theta + constant.
struct VelocityLinearization {
  double x_dv, x_dtheta, x_const;
  double y_dv, y_dtheta, y_const;
};

VelocityLinearization linearize_velocity(double v_bar, double theta_bar) {
  const double c = std::cos(theta_bar);
  const double s = std::sin(theta_bar);
  return {c, -v_bar * s, v_bar * theta_bar * s, s, v_bar * c, -v_bar * theta_bar * c};
}

// v and theta take the exact step of a held control; x and y the trapezoid
// of the two linearized velocities, with v_{k+1} and theta_{k+1} substituted
// so that the step is explicit in (z_k, u_k).
StageDynamics trapezoid_step(const State& at_k, const State& at_next, double dt) {
  const auto l0 = linearize_velocity(at_k[kV], at_k[kTheta]);
  const auto l1 = linearize_velocity(at_next[kV], at_next[kTheta]);
  StageDynamics d;
  d.A.setIdentity();
  d.B.setZero();
  d.c.setZero();
  const double h = 0.5 * dt;
  d.A(kX, kV) = h * (l0.x_dv + l1.x_dv);
  d.A(kX, kTheta) = h * (l0.x_dtheta + l1.x_dtheta);
  d.B(kX, kA) = h * dt * l1.x_dv;
  d.B(kX, kOmega) = h * dt * l1.x_dtheta;
  d.c(kX) = h * (l0.x_const + l1.x_const);
  d.A(kY, kV) = h * (l0.y_dv + l1.y_dv);
  d.A(kY, kTheta) = h * (l0.y_dtheta + l1.y_dtheta);
  d.B(kY, kA) = h * dt * l1.y_dv;
  d.B(kY, kOmega) = h * dt * l1.y_dtheta;
  d.c(kY) = h * (l0.y_const + l1.y_const);
  d.B(kV, kA) = dt;
  d.B(kTheta, kOmega) = dt;
  return d;
}

HalfSpace row(double gx, double gy, double gv, double upper, double gtheta = 0.0) {
  HalfSpace h;
  h.g << gx, gy, gv, gtheta;
  h.upper = upper;
  return h;
}

// The rows of Eq. 1 at one node, against the cars' positions there: in the
// ego lane, behind every car ahead of the ego at t = 0 and ahead of every car
// behind it (the lane keeps its order); in the target lane, those of the gap.
struct CarRows {
  std::vector<HalfSpace>& ego_lane;
  std::vector<HalfSpace>& target_lane;
};

// x_ego + h v_ego <= x_car - d: behind the car, by its distance at the ego's speed.
HalfSpace behind(const SafeDistance& d, double car_x) {
  return row(1.0, 0.0, d.time_headway, car_x - d.standstill);
}

// x_car + d + h v_car <= x_ego: ahead of the car, by its distance at its own speed.
HalfSpace ahead_of(const SafeDistance& d, double car_x, double car_v) {
  return row(-1.0, 0.0, 0.0, -(car_x + d.standstill + d.time_headway * car_v));
}

// x_car + gap(v_ego) + half lengths <= x_ego, the gap at which the car that
// the ego cuts in ahead of brakes no harder than expert.cut_in_decel (MOBIL's
// safety criterion), linear in the ego's speed about the point's; none where
// the car does not react to the ego or the config sets no limit.
std::optional<HalfSpace> cut_in_row(const Scenario& s, const Config& config, CarIndex c,
                                    double car_x, double car_v, double ego_speed, double dt) {
  const auto& decel = config.expert.cut_in_decel;
  if (!decel) return std::nullopt;
  const std::optional<SafeGapLine> line =
      gap_braking_at_most(*decel, s.cars[c].behavior, car_v, ego_speed, dt, s.idm, config.traffic);
  if (!line) return std::nullopt;
  const double centres = 0.5 * (s.size_of(c).length + s.vehicle.length);
  return row(-1.0, 0.0, line->slope, -(car_x + centres + line->gap - line->slope * ego_speed));
}

// What one node's rows need beyond the scene: where in the prediction it
// looks, the linearization point's ego speed there, and how much of a
// shortfall at the start (a row the initial state breaks) it still allows.
struct NodeContext {
  int index = 0;  ///< of the prediction, for node k
  double ego_speed = 0.0;
  double dt = 0.0;
  double shortfall_left = 0.0;  ///< 1 at the start, 0 once the distance must be whole
  bool in_ego_lane = true;      ///< the ego's body at the start, by lane
  bool in_target_lane = false;
};

// A row behind a car at node k, loosened by the share of its shortfall at
// the start that the node may still have: an ego that starts closer than
// Eq. 1 allows to a car ahead (recorded traffic) restores the distance over
// expert.restore_distance_within instead of failing at node 1. Rows of a
// lane the ego's body is not in at the start are not loosened (a cut-in
// keeps the whole distance), nor are those ahead of the cars behind: a car
// that closes in from behind is for the ego to leave, not to pull away from
// while it changes lanes in front of it.
template <class MakeRow>
HalfSpace restoring(const Scenario& s, const NodeContext& node, bool ego_in_lane, MakeRow make) {
  HalfSpace h = make(static_cast<std::size_t>(node.index));
  if (node.shortfall_left <= 0.0 || !ego_in_lane) return h;
  const HalfSpace start = make(std::size_t{0});
  const Eigen::Vector4d z0(s.ego.x, s.ego.y, s.ego.v, s.ego.theta);
  h.upper += node.shortfall_left * std::max(0.0, start.g.dot(z0) - start.upper);
  return h;
}

void fill_car_rows(const Scenario& s, const Config& config, const TrafficPrediction& p,
                   const NodeContext& node, const Gap& gap, CarRows r) {
  r.ego_lane.clear();
  r.target_lane.clear();
  for (CarIndex c = 0; c < s.car_count(); ++c) {
    if (s.cars[c].lane != Lane::Ego) continue;
    const CarTrack& car = p.car(c);
    if (s.car(c).x > s.ego.x) {
      const SafeDistance d = s.centre_safe_distance(c, s.safe_distance.leader);
      r.ego_lane.push_back(restoring(s, node, node.in_ego_lane,
                                     [&](std::size_t at) { return behind(d, car.x[at]); }));
    } else {
      const SafeDistance d = s.centre_safe_distance(c, s.safe_distance.follower);
      r.ego_lane.push_back(ahead_of(d, car.x[static_cast<std::size_t>(node.index)],
                                    car.v[static_cast<std::size_t>(node.index)]));
    }
  }
  for (const CarIndex c : gap.behind) {
    const SafeDistance d = s.centre_safe_distance(c, s.safe_distance.follower);
    const CarTrack& car = p.car(c);
    const auto at = static_cast<std::size_t>(node.index);
    r.target_lane.push_back(ahead_of(d, car.x[at], car.v[at]));
  }
  // Only the nearest car behind follows the ego; the others follow it.
  if (const auto c = gap.car_behind()) {
    const auto at = static_cast<std::size_t>(node.index);
    const auto cut_in =
        cut_in_row(s, config, *c, p.car(*c).x[at], p.car(*c).v[at], node.ego_speed, node.dt);
    if (cut_in) r.target_lane.push_back(*cut_in);
  }
  for (const CarIndex c : gap.ahead) {
    const SafeDistance d = s.centre_safe_distance(c, s.safe_distance.target);
    const CarTrack& car = p.car(c);
    r.target_lane.push_back(restoring(s, node, node.in_target_lane,
                                      [&](std::size_t at) { return behind(d, car.x[at]); }));
  }
}

// Where the lane line is and what the body is, at one node.
struct LaneGeometry {
  double boundary = 0.0;     ///< y of the lane line
  double half_width = 0.0;   ///< of the ego's body
  double half_length = 0.0;  ///< of the ego's body
  Interval heading;          ///< the headings the node can have
};

void append(std::vector<HalfSpace>& rows, std::initializer_list<HalfSpace> more) {
  rows.insert(rows.end(), more.begin(), more.end());
}

// The y rows of each mode (see fill_node_modes), after its car rows.
void add_lane_rows(LaneRule rule, const LaneGeometry& lane, std::vector<LaneMode>& modes) {
  const double b = lane.boundary;
  const double w = lane.half_width;
  auto& ego = modes.front().rows;
  auto& target = modes.back().rows;
  if (rule == LaneRule::EitherOr) {
    append(ego, {row(0, 1, 0, b)});
    append(target, {row(0, -1, 0, -b)});
    return;
  }
  auto& both = modes[1].rows;
  if (rule == LaneRule::Footprint) {
    // Footprint: the body is in every lane it touches. Touching both lanes
    // needs every row; the y rows of the one-lane modes keep the body clear of
    // the lane line. The both-lanes mode is limited to the band where the body
    // does touch the line: outside it, its points already belong to a one-lane
    // mode (they keep that mode's rows and more), so the union of the modes is
    // the same, but a relaxation no longer lets a "both lanes" node sit anywhere
    // across the road, and the modes no longer overlap.
    append(ego, {row(0, 1, 0, b - w)});
    append(both, {row(0, 1, 0, b + w), row(0, -1, 0, -(b - w))});
    append(target, {row(0, -1, 0, -(b + w))});
    return;
  }
  // The body turned by theta reaches half_width cos(theta) + half_length
  // |sin(theta)| to either side of its centre; half_width + half_length |theta|
  // is never less, so a one-lane mode's two rows (one per sign of theta) keep
  // every corner in its lane. The both-lanes set, |y - line| <= half_width +
  // half_length |theta|, is not convex; its rows are its convex hull over the
  // node's headings (|theta| replaced by its chord there), so the three modes
  // still cover the road and the search stays exact. Where the headings have one
  // sign, as under monotone_lateral, the chord is |theta| itself.
  const double l = lane.half_length;
  const double lo = lane.heading.lo;
  const double hi = lane.heading.hi;
  // |theta| <= chord_at_lo + chord_slope (theta - lo) on [lo, hi].
  const double chord_slope = hi > lo ? (std::abs(hi) - std::abs(lo)) / (hi - lo) : 0.0;
  const double chord_offset = std::abs(lo) - chord_slope * lo;
  const double reach = w + l * chord_offset;
  const double slope = l * chord_slope;
  append(ego, {row(0, 1, 0, b - w, l), row(0, 1, 0, b - w, -l)});
  append(both, {row(0, 1, 0, b + reach, -slope), row(0, -1, 0, reach - b, -slope)});
  append(target, {row(0, -1, 0, -(b + w), l), row(0, -1, 0, -(b + w), -l)});
}

// A node's modes in lane_mode_index's order, each with its rows: the ego
// lane's car rows, the target lane's (both for the both-lanes mode), then its
// y rows. Filled in place, so a node's lists keep their memory from one
// build to the next.
void fill_node_modes(const Scenario& s, const Config& config, const TrafficPrediction& p,
                     const NodeContext& node, const Gap& gap, const LaneGeometry& lane,
                     std::vector<LaneMode>& modes) {
  const LaneRule rule = config.expert.lane_rule;
  const bool both_lanes = rule != LaneRule::EitherOr;
  modes.resize(both_lanes ? 3 : 2);
  modes.front().occupancy = LaneOccupancy::EgoLane;
  modes.back().occupancy = LaneOccupancy::TargetLane;
  fill_car_rows(s, config, p, node, gap, {modes.front().rows, modes.back().rows});
  if (both_lanes) {
    LaneMode& both = modes[1];
    both.occupancy = LaneOccupancy::BothLanes;
    both.rows.assign(modes.front().rows.begin(), modes.front().rows.end());
    both.rows.insert(both.rows.end(), modes.back().rows.begin(), modes.back().rows.end());
  }
  add_lane_rows(rule, lane, modes);
}

// The headings a node at time t can have: its bounds, cut to what the yaw
// rate can reach from the ego's heading.
Interval reachable_headings(const Scenario& s, Interval bounds, double t) {
  const double lo = std::max(bounds.lo, s.ego.theta + s.limits.omega.lo * t);
  const double hi = std::min(bounds.hi, s.ego.theta + s.limits.omega.hi * t);
  return lo <= hi ? Interval{lo, hi} : bounds;
}

}  // namespace

std::optional<CarIndex> Gap::car_behind() const {
  return behind.empty() ? std::nullopt : std::optional<CarIndex>(behind.back());
}

std::optional<CarIndex> Gap::car_ahead() const {
  return ahead.empty() ? std::nullopt : std::optional<CarIndex>(ahead.front());
}

Gap paper_gap(const Scenario& s) {
  Gap gap;
  paper_gap(s, gap);
  return gap;
}

void paper_gap(const Scenario& s, Gap& out) {
  out.behind.clear();
  out.ahead.clear();
  if (s.has(Role::Follower)) out.behind.push_back(s.index_of(Role::Follower));
  if (s.has(Role::Target)) out.ahead.push_back(s.index_of(Role::Target));
}

std::vector<Gap> target_lane_gaps(const Scenario& s, GapChoice choice) {
  std::vector<Gap> gaps;
  target_lane_gaps(s, choice, gaps);
  return gaps;
}

void target_lane_gaps(const Scenario& s, GapChoice choice, std::vector<Gap>& out,
                      Spare<Gap>* spare) {
  const auto resize = [&](std::size_t n) {
    if (spare != nullptr) {
      resize_keeping(out, n, *spare);
    } else {
      out.resize(n);
    }
  };
  if (choice == GapChoice::Fixed) {
    resize(1);
    paper_gap(s, out[0]);
    return;
  }
  std::size_t count = 0;
  for (CarIndex c = 0; c < s.car_count(); ++c) count += s.cars[c].lane == Lane::Target ? 1 : 0;
  resize(count + 1);
  // Every list with room for the whole lane: a caller that reorders the gaps
  // (the planner puts the likeliest first) then finds room in each.
  for (Gap& gap : out) {
    gap.behind.reserve(count);
    gap.ahead.reserve(count);
  }
  // The lane from the back, in the first gap's list (the one ahead of every
  // car): an insertion sort, stable and without the buffer stable_sort takes.
  std::vector<CarIndex>& lane = out[0].ahead;
  lane.clear();
  for (CarIndex c = 0; c < s.car_count(); ++c) {
    if (s.cars[c].lane != Lane::Target) continue;
    auto at = lane.end();
    while (at != lane.begin() && s.car(*(at - 1)).x > s.car(c).x) --at;
    lane.insert(at, c);
  }
  out[0].behind.clear();
  for (std::size_t split = 1; split <= count; ++split) {
    const auto at = lane.begin() + static_cast<std::ptrdiff_t>(split);
    out[split].behind.assign(lane.begin(), at);
    out[split].ahead.assign(at, lane.end());
  }
}

GapAim aim_into(const Scenario& s, const Config& c, const TrafficPrediction& p, const Gap& gap,
                int node) {
  const auto at = static_cast<std::size_t>(node);
  if (const auto ahead = gap.car_ahead()) {
    const CarTrack& car = p.car(*ahead);
    GapAim aim{car.x[at], car.v[at], car.a[at]};
    if (c.expert.aim_behind_target) {
      const SafeDistance d = s.centre_safe_distance(*ahead, s.safe_distance.target);
      aim.x -= d.standstill + d.time_headway * std::min(car.v[at], s.limits.v.hi);
    }
    return aim;
  }
  if (const auto behind = gap.car_behind()) {
    const CarTrack& car = p.car(*behind);
    GapAim aim{car.x[at], car.v[at], car.a[at]};
    if (c.expert.aim_behind_target) {
      const SafeDistance d = s.centre_safe_distance(*behind, s.safe_distance.follower);
      aim.x += d.standstill + d.time_headway * car.v[at];
    }
    return aim;
  }
  return {s.ego.x + s.ego.v * s.horizon, s.ego.v, 0.0};
}

double footprint_half_width(const Scenario& s, const ExpertSettings& e) {
  return 0.5 * s.vehicle.width + e.line_clearance;
}

std::string describe(const Scenario& s, const Gap& gap) {
  const auto name = [&s](std::optional<CarIndex> c) {
    return c ? s.cars[*c].id : std::string("none");
  };
  return name(gap.car_behind()) + "-" + name(gap.car_ahead());
}

int lane_mode_index(LaneRule rule, LaneOccupancy occupancy) {
  // The order in which lane_modes lists them.
  if (rule == LaneRule::EitherOr) {
    if (occupancy == LaneOccupancy::BothLanes) return -1;
    return occupancy == LaneOccupancy::EgoLane ? 0 : 1;
  }
  return static_cast<int>(occupancy);
}

LaneChangeQp build_lane_change_qp(const Scenario& s, const Config& config, const Iterate& point,
                                  const TrafficPrediction& prediction) {
  return build_lane_change_qp(s, config, point, prediction, paper_gap(s));
}

LaneChangeQp build_lane_change_qp(const Scenario& s, const Config& config, const Iterate& point,
                                  const TrafficPrediction& prediction, const Gap& gap) {
  LaneChangeQp qp;
  build_lane_change_qp(s, config, point, prediction, gap, qp);
  return qp;
}

void build_lane_change_qp(const Scenario& s, const Config& config, const Iterate& point,
                          const TrafficPrediction& prediction, const Gap& gap, LaneChangeQp& qp) {
  const ExpertSettings& e = config.expert;
  qp.steps = s.steps;
  qp.dt = s.horizon / s.steps;
  const int n = qp.steps;
  qp.initial_state << s.ego.x, s.ego.y, s.ego.v, s.ego.theta;
  qp.dynamics.resize(n);
  for (int k = 0; k < n; ++k) {
    qp.dynamics[k] = trapezoid_step(point.states[k], point.states[k + 1], qp.dt);
  }
  qp.accel_weight = e.weight_accel * qp.dt;
  qp.jerk_weight =
      e.jerk_weighting == JerkWeighting::Derivative ? e.weight_jerk / qp.dt : e.weight_jerk * qp.dt;
  // Left Riemann sum of c3 (y - w)^2 dt, as the authors' code sums it.
  qp.lateral_weight.assign(n + 1, e.weight_lateral * qp.dt);
  qp.lateral_weight[n] = 0.0;
  qp.lateral_reference = s.lane_width;
  qp.terminal_x_weight = e.weight_terminal_x;
  qp.yaw_rate_weight = e.weight_yaw_rate * qp.dt;
  qp.terminal_x_reference = aim_into(s, config, prediction, gap, prediction.nodes() - 1).x;
  // x has no bound of its own; these never bind and give the big-M rows a box.
  constexpr double kXSlack = 50.0;
  qp.state_lower.resize(n + 1);
  qp.state_upper.resize(n + 1);
  for (int k = 0; k <= n; ++k) {
    const double t = k * qp.dt;
    State& lo = qp.state_lower[k];
    State& hi = qp.state_upper[k];
    // "y never decreases" as a constraint: a heading of at least 0, from the
    // first node the yaw rate can bring it there.
    // Once the ego is at the target-lane centre it may settle back onto it
    // (the labeller allows that too), so the bound holds only below it.
    const bool monotone = e.monotone_lateral && s.ego.y < s.lane_width - config.labels.reach;
    const double lowest_heading =
        monotone ? std::min(0.0, s.ego.theta + s.limits.omega.hi * t) : -std::numbers::pi / 2;
    // Like the heading's, from the first node the ego can meet it.
    const Interval speed = s.speed_bounds_at(t);
    lo << s.ego.x - kXSlack, -s.limits.lateral_margin, speed.lo, lowest_heading;
    hi << s.ego.x + std::max(s.limits.v.hi, s.ego.v) * t + kXSlack,
        s.lane_width + s.limits.lateral_margin, speed.hi, std::numbers::pi / 2;
  }
  qp.control_lower << s.limits.a.lo, s.limits.omega.lo;
  qp.control_upper << s.limits.a.hi, s.limits.omega.hi;
  qp.terminal_lateral_fixed = e.fix_terminal_lateral;
  qp.yaw_rate_per_speed = e.min_turn_radius > 0.0 ? 1.0 / e.min_turn_radius : 0.0;
  qp.node_modes.resize(n + 1);
  if (!e.constrain_initial_node) qp.node_modes[0].clear();
  const int last_prediction = prediction.nodes() - 1;
  for (int k = e.constrain_initial_node ? 0 : 1; k <= n; ++k) {
    const int index = std::min(k + e.prediction_lead_steps, last_prediction);
    const Interval heading{qp.state_lower[k][kTheta], qp.state_upper[k][kTheta]};
    const LaneGeometry lane{0.5 * s.lane_width, footprint_half_width(s, e), 0.5 * s.vehicle.length,
                            reachable_headings(s, heading, k * qp.dt)};
    // Node 0 is the given state: checked whole where the config constrains it.
    const double restore = e.restore_distance_within;
    const NodeContext node{
        index, point.states[k][kV], qp.dt,
        restore > 0.0 && k > 0 ? std::max(0.0, 1.0 - k * qp.dt / restore) : 0.0,
        s.ego.y - lane.half_width<lane.boundary, s.ego.y + lane.half_width> lane.boundary};
    fill_node_modes(s, config, prediction, node, gap, lane, qp.node_modes[k]);
  }
}

double LaneChangeQp::objective(const Iterate& path) const {
  double total = 0.0;
  for (int k = 0; k < steps; ++k) {
    const Control& u = path.controls[k];
    total += accel_weight * u[kA] * u[kA] + yaw_rate_weight * u[kOmega] * u[kOmega];
  }
  for (int k = 0; k + 1 < steps; ++k) {
    const double jerk = path.controls[k + 1][kA] - path.controls[k][kA];
    total += jerk_weight * jerk * jerk;
  }
  for (int k = 0; k <= steps; ++k) {
    const double dy = path.states[k][kY] - lateral_reference;
    total += lateral_weight[k] * dy * dy;
  }
  const double dx = path.states[steps][kX] - terminal_x_reference;
  return total + terminal_x_weight * dx * dx;
}

double LaneChangeQp::objective_constant() const {
  double constant = terminal_x_weight * terminal_x_reference * terminal_x_reference;
  for (double w : lateral_weight) constant += w * lateral_reference * lateral_reference;
  return constant;
}

namespace {

double mode_violation(const LaneMode& mode, const State& z) {
  double worst = 0.0;
  for (const HalfSpace& h : mode.rows) worst = std::max(worst, h.g.dot(z) - h.upper);
  return worst;
}

}  // namespace

int LaneChangeQp::best_mode(const Iterate& path, int node, unsigned allowed) const {
  const auto& modes = node_modes[node];
  int best = -1;
  double best_violation = kInfinity;
  for (int m = 0; m < static_cast<int>(modes.size()); ++m) {
    if (((allowed >> m) & 1U) == 0) continue;
    const double v = mode_violation(modes[m], path.states[node]);
    if (v < best_violation) {
      best_violation = v;
      best = m;
    }
  }
  return best;
}

double LaneChangeQp::max_violation(const Iterate& path) const {
  double worst = (path.states[0] - initial_state).cwiseAbs().maxCoeff();
  for (int k = 0; k < steps; ++k) {
    const StageDynamics& d = dynamics[k];
    const State next = d.A * path.states[k] + d.B * path.controls[k] + d.c;
    worst = std::max(worst, (next - path.states[k + 1]).cwiseAbs().maxCoeff());
    worst = std::max(worst, (control_lower - path.controls[k]).maxCoeff());
    worst = std::max(worst, (path.controls[k] - control_upper).maxCoeff());
    if (yaw_rate_per_speed > 0.0) {
      const double turn = std::abs(path.controls[k][kOmega]);
      worst = std::max(worst, turn - yaw_rate_per_speed * path.states[k][kV]);
    }
  }
  for (int k = 1; k <= steps; ++k) {
    worst = std::max(worst, (state_lower[k] - path.states[k]).maxCoeff());
    worst = std::max(worst, (path.states[k] - state_upper[k]).maxCoeff());
  }
  for (int k = 0; k <= steps; ++k) {
    const int m = best_mode(path, k);
    if (m >= 0) worst = std::max(worst, mode_violation(node_modes[k][m], path.states[k]));
  }
  if (terminal_lateral_fixed) {
    worst = std::max(worst, std::abs(path.states[steps][kY] - lateral_reference));
  }
  return worst;
}

namespace {

// The most a row g'z <= upper can be violated over the box [lo, hi].
double largest_excess(const HalfSpace& h, const State& lo, const State& hi) {
  double most = -h.upper;
  for (int i = 0; i < 4; ++i) most += std::max(h.g[i] * lo[i], h.g[i] * hi[i]);
  return most;
}

using Triplets = std::vector<Eigen::Triplet<double>>;

struct RowBuilder {
  Triplets entries;
  std::vector<double> lower, upper;
  int add(double lo, double hi) {
    lower.push_back(lo);
    upper.push_back(hi);
    return static_cast<int>(lower.size()) - 1;
  }
};

void add_dynamics_rows(const LaneChangeQp& qp, const MiqpLayout& at, RowBuilder& rows) {
  for (int k = 0; k < qp.steps; ++k) {
    const StageDynamics& d = qp.dynamics[k];
    for (int i = 0; i < 4; ++i) {
      const int r = rows.add(d.c[i], d.c[i]);
      rows.entries.emplace_back(r, at.state(k + 1, i), 1.0);
      for (int j = 0; j < 4; ++j) {
        if (d.A(i, j) != 0.0) rows.entries.emplace_back(r, at.state(k, j), -d.A(i, j));
      }
      for (int j = 0; j < 2; ++j) {
        if (d.B(i, j) != 0.0) rows.entries.emplace_back(r, at.control(k, j), -d.B(i, j));
      }
    }
  }
}

// -omega_k - kappa v_k <= 0 and omega_k - kappa v_k <= 0.
void add_turn_rows(const LaneChangeQp& qp, const MiqpLayout& at, RowBuilder& rows) {
  if (qp.yaw_rate_per_speed <= 0.0) return;
  for (int k = 0; k < qp.steps; ++k) {
    for (const double sign : {1.0, -1.0}) {
      const int r = rows.add(-kInfinity, 0.0);
      rows.entries.emplace_back(r, at.control(k, kOmega), sign);
      rows.entries.emplace_back(r, at.state(k, kV), -qp.yaw_rate_per_speed);
    }
  }
}

void add_lane_rows(const LaneChangeQp& qp, double big_m, const MiqpLayout& at, RowBuilder& rows) {
  for (int k = 0; k <= qp.steps; ++k) {
    const auto& modes = qp.node_modes[k];
    if (modes.empty()) continue;
    const State lo = k == 0 ? qp.initial_state : qp.state_lower[k];
    const State hi = k == 0 ? qp.initial_state : qp.state_upper[k];
    const int choose_one = rows.add(1.0, 1.0);
    for (int m = 0; m < static_cast<int>(modes.size()); ++m) {
      rows.entries.emplace_back(choose_one, at.mode(k, m), 1.0);
      for (const HalfSpace& h : modes[m].rows) {
        const double excess = largest_excess(h, lo, hi);
        if (excess <= 0.0) continue;  // holds everywhere in the box
        // g'z + M delta <= upper + M: the row binds when delta = 1.
        const double m_row = std::min(big_m, excess);
        const int r = rows.add(-kInfinity, h.upper + m_row);
        for (int i = 0; i < 4; ++i) {
          if (h.g[i] != 0.0) rows.entries.emplace_back(r, at.state(k, i), h.g[i]);
        }
        rows.entries.emplace_back(r, at.mode(k, m), m_row);
      }
    }
  }
}

void add_objective(const LaneChangeQp& qp, const MiqpLayout& at, MiqpProblem& p) {
  Triplets h;
  const int n = qp.steps;
  for (int k = 0; k < n; ++k) {
    h.emplace_back(at.control(k, kA), at.control(k, kA), 2.0 * qp.accel_weight);
    h.emplace_back(at.control(k, kOmega), at.control(k, kOmega), 2.0 * qp.yaw_rate_weight);
  }
  for (int k = 0; k + 1 < n; ++k) {
    const int a0 = at.control(k, kA);
    const int a1 = at.control(k + 1, kA);
    const double w = 2.0 * qp.jerk_weight;
    h.emplace_back(a0, a0, w);
    h.emplace_back(a1, a1, w);
    h.emplace_back(a0, a1, -w);
    h.emplace_back(a1, a0, -w);
  }
  for (int k = 0; k <= n; ++k) {
    const double w = qp.lateral_weight[k];
    if (w == 0.0) continue;
    const int y = at.state(k, kY);
    h.emplace_back(y, y, 2.0 * w);
    p.gradient[y] -= 2.0 * w * qp.lateral_reference;
    p.constant += w * qp.lateral_reference * qp.lateral_reference;
  }
  if (qp.terminal_x_weight > 0.0) {
    const int x = at.state(n, kX);
    h.emplace_back(x, x, 2.0 * qp.terminal_x_weight);
    p.gradient[x] -= 2.0 * qp.terminal_x_weight * qp.terminal_x_reference;
    p.constant += qp.terminal_x_weight * qp.terminal_x_reference * qp.terminal_x_reference;
  }
  p.hessian.setFromTriplets(h.begin(), h.end());
}

void set_bounds(const LaneChangeQp& qp, const MiqpLayout& at, MiqpProblem& p) {
  const int n = qp.steps;
  for (int i = 0; i < 4; ++i) {
    p.col_lower[at.state(0, i)] = p.col_upper[at.state(0, i)] = qp.initial_state[i];
    for (int k = 1; k <= n; ++k) {
      p.col_lower[at.state(k, i)] = qp.state_lower[k][i];
      p.col_upper[at.state(k, i)] = qp.state_upper[k][i];
    }
  }
  if (qp.terminal_lateral_fixed) {
    p.col_lower[at.state(n, kY)] = p.col_upper[at.state(n, kY)] = qp.lateral_reference;
  }
  for (int k = 0; k < n; ++k) {
    for (int j = 0; j < 2; ++j) {
      p.col_lower[at.control(k, j)] = qp.control_lower[j];
      p.col_upper[at.control(k, j)] = qp.control_upper[j];
    }
  }
  for (int b = at.mode_offset[0]; b < at.size(); ++b) {
    p.col_lower[b] = 0.0;
    p.col_upper[b] = 1.0;
    p.kinds[b] = VariableKind::Binary;
  }
}

}  // namespace

MiqpProblem to_miqp(const LaneChangeQp& qp, double big_m, MiqpLayout& layout) {
  const int n = qp.steps;
  layout.steps = n;
  layout.mode_offset.assign(n + 2, 0);
  layout.mode_offset[0] = 4 * (n + 1) + 2 * n;
  for (int k = 0; k <= n; ++k) {
    layout.mode_offset[k + 1] = layout.mode_offset[k] + static_cast<int>(qp.node_modes[k].size());
  }
  const int size = layout.size();
  MiqpProblem p;
  p.gradient = Eigen::VectorXd::Zero(size);
  p.hessian.resize(size, size);
  p.col_lower = Eigen::VectorXd::Constant(size, -kInfinity);
  p.col_upper = Eigen::VectorXd::Constant(size, kInfinity);
  p.kinds.assign(size, VariableKind::Continuous);
  add_objective(qp, layout, p);
  set_bounds(qp, layout, p);
  RowBuilder rows;
  add_dynamics_rows(qp, layout, rows);
  add_turn_rows(qp, layout, rows);
  add_lane_rows(qp, big_m, layout, rows);
  const int m = static_cast<int>(rows.lower.size());
  p.constraints.resize(m, size);
  p.constraints.setFromTriplets(rows.entries.begin(), rows.entries.end());
  p.row_lower = Eigen::Map<Eigen::VectorXd>(rows.lower.data(), m);
  p.row_upper = Eigen::Map<Eigen::VectorXd>(rows.upper.data(), m);
  return p;
}

Iterate iterate_from_miqp(const Eigen::VectorXd& x, const MiqpLayout& at) {
  Iterate path;
  for (int k = 0; k <= at.steps; ++k) {
    path.states.emplace_back(x[at.state(k, kX)], x[at.state(k, kY)], x[at.state(k, kV)],
                             x[at.state(k, kTheta)]);
  }
  for (int k = 0; k < at.steps; ++k) {
    path.controls.emplace_back(x[at.control(k, kA)], x[at.control(k, kOmega)]);
  }
  return path;
}

}  // namespace lanechange::expert
