#include <algorithm>
#include <array>
#include <cmath>

#include "lanechange/expert/planner.hpp"

namespace lanechange::expert {
namespace {

// The quintic p(t) on [0, T] with p, p', p'' given at both ends.
struct Quintic {
  std::array<double, 6> c{};
  Quintic(double p0, double v0, double a0, double p1, double v1, double a1, double T) {
    c[0] = p0;
    c[1] = v0;
    c[2] = 0.5 * a0;
    const double T2 = T * T, T3 = T2 * T, T4 = T3 * T, T5 = T4 * T;
    const double dp = p1 - p0 - v0 * T - 0.5 * a0 * T2;
    const double dv = v1 - v0 - a0 * T;
    const double da = a1 - a0;
    c[3] = (10 * dp - 4 * dv * T + 0.5 * da * T2) / T3;
    c[4] = (-15 * dp + 7 * dv * T - da * T2) / T4;
    c[5] = (6 * dp - 3 * dv * T + 0.5 * da * T2) / T5;
  }
  [[nodiscard]] double value(double t) const {
    return c[0] + t * (c[1] + t * (c[2] + t * (c[3] + t * (c[4] + t * c[5]))));
  }
  [[nodiscard]] double rate(double t) const {
    return c[1] + t * (2 * c[2] + t * (3 * c[3] + t * (4 * c[4] + t * 5 * c[5])));
  }
};

// Controls that move the states of a path, step by step.
void fill_controls(Iterate& path, double dt) {
  path.controls.clear();
  for (std::size_t k = 0; k + 1 < path.states.size(); ++k) {
    path.controls.emplace_back((path.states[k + 1][kV] - path.states[k][kV]) / dt,
                               (path.states[k + 1][kTheta] - path.states[k][kTheta]) / dt);
  }
}

// The ego's lateral motion in a warm start: the quintic from y0 to y1 with
// zero end rates and accelerations over [start, start + duration], flat
// outside.
class LateralMove {
 public:
  LateralMove(double y0, double y1, double start, double duration)
      : shape_(y0, 0.0, 0.0, y1, 0.0, 0.0, duration), start_(start), duration_(duration) {}
  [[nodiscard]] double value(double t) const {
    return shape_.value(std::clamp(t - start_, 0.0, duration_));
  }
  [[nodiscard]] double rate(double t) const {
    const double s = t - start_;
    return s <= 0.0 || s >= duration_ ? 0.0 : shape_.rate(s);
  }

 private:
  Quintic shape_;
  double start_, duration_;
};

// Where on [0, 1] the smooth-step quintic from 0 to 1 reaches `level`.
double quintic_time_at(double level) {
  const Quintic unit(0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0);
  double lo = 0.0, hi = 1.0;
  for (int i = 0; i < 50; ++i) {
    const double mid = 0.5 * (lo + hi);
    (unit.value(mid) < level ? lo : hi) = mid;
  }
  return 0.5 * (lo + hi);
}

// Where the warm start ends: the gap's aim (behind its car ahead).
GapAim gap_aim(const Scenario& s, const Config& c, const TrafficPrediction& p, const Gap& gap) {
  return aim_into(s, c, p, gap, std::min(s.steps, p.nodes() - 1));
}

// Whether the ego can be at x at the horizon's end, between braking to its
// lowest speed and speeding up to its highest.
bool reachable(const Scenario& s, double x) {
  const double T = s.horizon;
  const double v0 = s.ego.v * std::cos(s.ego.theta);
  const auto travel = [&](double accel, double bound) {
    const double t = std::clamp((bound - v0) / accel, 0.0, T);
    return v0 * t + 0.5 * accel * t * t + bound * (T - t);
  };
  return x >= s.ego.x + travel(s.limits.a.lo, s.limits.v.lo) &&
         x <= s.ego.x + travel(s.limits.a.hi, s.limits.v.hi);
}

// Where the ego's own pace takes it, if that lies in the gap (ahead of its
// car behind, behind its car ahead, each by its safe distance); else the
// gap's nearer end, at that car's speed; the gap's aim where the gap is
// shorter than the two safe distances.
GapAim paced_aim(const Scenario& s, const Config& c, const TrafficPrediction& p, const Gap& gap) {
  const GapAim edge = gap_aim(s, c, p, gap);
  const double pace = s.ego.x + s.ego.v * std::cos(s.ego.theta) * s.horizon;
  const GapAim own{pace, s.ego.v, 0.0};
  const auto behind = gap.car_behind();
  if (!gap.car_ahead()) return behind && pace < edge.x ? edge : own;
  if (behind) {
    const CarTrack& car = p.car(*behind);
    const auto at = static_cast<std::size_t>(std::min(s.steps, p.nodes() - 1));
    const SafeDistance d = s.centre_safe_distance(*behind, s.safe_distance.follower);
    const double margin =
        c.expert.aim_behind_target ? d.standstill + d.time_headway * car.v[at] : 0.0;
    const GapAim back{car.x[at] + margin, car.v[at], car.a[at]};
    if (back.x > edge.x) return edge;
    if (pace < back.x) return back;
  }
  return pace > edge.x ? edge : own;
}

// The warm start's states: x and speed from a quintic toward `end_state`,
// with the given lateral motion (value and rate in t). The caller fills the
// controls once its states are final.
template <class Lateral>
void quintic_path(const Scenario& s, const Lateral& lateral, const GapAim& end_state,
                  Iterate& path) {
  const double T = s.horizon;
  const double dt = T / s.steps;
  const double end_speed = std::clamp(end_state.v, s.limits.v.lo, s.limits.v.hi);
  // A target far behind would make the path run backwards; the guess is only a
  // linearization point, so keep it moving forward.
  const double aim = std::max(end_state.x, s.ego.x + 0.5 * (s.ego.v + end_speed) * T * 0.25);
  const Quintic x(s.ego.x, s.ego.v * std::cos(s.ego.theta), s.ego.a, aim, end_speed, end_state.a,
                  T);
  path.states.clear();
  for (int k = 0; k <= s.steps; ++k) {
    const double t = k * dt;
    const double vx = std::max(x.rate(t), 0.1);
    const double vy = lateral.rate(t);
    path.states.emplace_back(x.value(t), lateral.value(t), std::hypot(vx, vy), std::atan2(vy, vx));
  }
}

void quintic_warm_start(const Scenario& s, const GapAim& end_state, Iterate& path) {
  const Quintic y(s.ego.y, s.ego.v * std::sin(s.ego.theta), 0.0, s.lane_width, 0.0, 0.0, s.horizon);
  quintic_path(s, y, end_state, path);
  fill_controls(path, s.horizon / s.steps);
}

// The authors' code: x = v0 t, a quintic y with zero end rates, v linear to
// the target's speed, theta constant.
void authors_warm_start(const Scenario& s, const TrafficPrediction& p, Iterate& path) {
  const double T = s.horizon;
  const double dt = T / s.steps;
  const Quintic y(s.ego.y, 0.0, 0.0, s.lane_width, 0.0, 0.0, T);
  const double v_end = s.has(Role::Target) ? p.car(s.index_of(Role::Target)).v.front() : s.ego.v;
  path.states.clear();
  for (int k = 0; k <= s.steps; ++k) {
    const double t = k * dt;
    path.states.emplace_back(s.ego.x + s.ego.v * t, y.value(t), s.ego.v + (v_end - s.ego.v) * t / T,
                             s.ego.theta);
  }
  fill_controls(path, dt);
}

// The lateral move whose body first touches the line at node `touches` and
// is first wholly across it at node `across` (either -1: never).
LateralMove move_timed_to(const Scenario& s, int touches, int across) {
  const double y0 = s.ego.y;
  // No lane change: back to (or along) the ego lane's centre.
  if (touches < 0) return {y0, 0.0, 0.0, s.horizon};
  const double span = s.lane_width - y0;
  // Already at (or past) the target lane's centre: nothing to time.
  if (span <= 1e-6) return {y0, s.lane_width, 0.0, s.horizon};
  if (across < 0) across = s.steps + 2;  // past the horizon
  const double dt = s.horizon / s.steps;
  const double line = 0.5 * s.lane_width;
  const double half = 0.5 * s.vehicle.width;
  const double tau_touch = quintic_time_at(std::clamp((line - half - y0) / span, 0.0, 1.0));
  const double tau_across = quintic_time_at(std::clamp((line + half - y0) / span, 0.0, 1.0));
  const double gap = std::max(tau_across - tau_touch, 0.05);
  const double duration = std::max((across - touches) * dt / gap, 2.0 * dt);
  return {y0, s.lane_width, touches * dt - tau_touch * duration, duration};
}

}  // namespace

Iterate warm_start_for_modes(const Scenario& scenario, const Config& config,
                             const TrafficPrediction& prediction, const std::vector<int>& modes,
                             const Gap& gap) {
  const LaneRule rule = config.expert.lane_rule;
  const int ego_lane = lane_mode_index(rule, LaneOccupancy::EgoLane);
  const int target_lane = lane_mode_index(rule, LaneOccupancy::TargetLane);
  int touches = -1, across = -1;
  for (int k = 1; k < static_cast<int>(modes.size()); ++k) {
    const int m = modes[static_cast<std::size_t>(k)];
    if (m < 0) continue;
    if (touches < 0 && m != ego_lane) touches = k;
    if (across < 0 && m == target_lane) across = k;
  }
  // Under the either-or rule a node is in one lane or the other.
  if (touches >= 0 && across < 0 && rule == LaneRule::EitherOr) across = touches;
  Iterate path;
  quintic_path(scenario, move_timed_to(scenario, touches, across),
               gap_aim(scenario, config, prediction, gap), path);
  // The flat start would give node 0 no heading; it has the ego's.
  path.states.front() = State(scenario.ego.x, scenario.ego.y, scenario.ego.v, scenario.ego.theta);
  fill_controls(path, scenario.horizon / scenario.steps);
  return path;
}

Iterate warm_start_for_modes(const Scenario& scenario, const Config& config,
                             const TrafficPrediction& prediction, const std::vector<int>& modes) {
  return warm_start_for_modes(scenario, config, prediction, modes, paper_gap(scenario));
}

void warm_start(const Scenario& scenario, const Config& config, const TrafficPrediction& prediction,
                const Gap& gap, Iterate& out) {
  if (config.expert.warm_start == WarmStart::Authors) {
    authors_warm_start(scenario, prediction, out);
  } else {
    quintic_warm_start(scenario, gap_aim(scenario, config, prediction, gap), out);
  }
}

// A round about a path the ego cannot drive (aimed behind a car far ahead, or
// ahead of one far behind) can call a gap infeasible that is not.
bool paced_warm_start(const Scenario& scenario, const Config& config,
                      const TrafficPrediction& prediction, const Gap& gap, Iterate& out) {
  if (config.expert.warm_start == WarmStart::Authors ||
      reachable(scenario, gap_aim(scenario, config, prediction, gap).x)) {
    return false;
  }
  quintic_warm_start(scenario, paced_aim(scenario, config, prediction, gap), out);
  return true;
}

Iterate warm_start(const Scenario& scenario, const Config& config,
                   const TrafficPrediction& prediction, const Gap& gap) {
  Iterate out;
  warm_start(scenario, config, prediction, gap, out);
  return out;
}

Iterate warm_start(const Scenario& scenario, const Config& config,
                   const TrafficPrediction& prediction) {
  return warm_start(scenario, config, prediction, paper_gap(scenario));
}

}  // namespace lanechange::expert
