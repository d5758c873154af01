#include "baselines/dwa.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "baselines/sampling.hpp"
#include "lanechange/ego.hpp"
#include "lanechange/traffic.hpp"

namespace lanechange::baselines {

namespace {

// Separations beyond this count alike in the clearance term (m).
constexpr double kClearanceCap = 5.0;

// One sampled control and what its rollout found.
struct Candidate {
  EgoControl u;
  EgoState end;
  double separation = 0.0;
  bool enters_target_lane = false;
};

// Evenly spaced samples of an interval; its midpoint for a single sample.
double sample(const Interval& range, int i, int count) {
  if (count <= 1) return 0.5 * (range.lo + range.hi);
  return range.lo + (range.hi - range.lo) * i / (count - 1);
}

// The admissible velocities of Fox et al.: from the rollout's end, the ego
// can still brake behind the car ahead in each lane its body touches, both
// braking at the same rate.
bool can_stop_safely(const EgoState& end, const TrafficPrediction& cars, const Scenario& scene,
                     const DwaSettings& s) {
  const auto last = static_cast<std::size_t>(cars.nodes() - 1);
  for (CarIndex c = 0; c < cars.car_count(); ++c) {
    const double center = scene.lane_center(c);
    if (!body_in_lane(end.y, scene.vehicle.width, center, scene.lane_width)) continue;
    const double ahead_by = cars.car(c).x[last] - end.x;
    if (ahead_by < 0) continue;  // behind the ego: not a car to stop for
    const double gap = scene.bumper_gap(c, ahead_by);
    const double v_car = cars.car(c).v[last];
    const double braking = std::max(0.0, end.v * end.v - v_car * v_car) / (2.0 * s.braking_decel);
    if (gap - s.margin < braking) return false;
  }
  return true;
}

bool reaches_target_lane(const std::vector<EgoState>& path, const Scenario& scene) {
  return std::any_of(path.begin() + 1, path.end(), [&](const EgoState& e) {
    return body_in_lane(e.y, scene.vehicle.width, scene.lane_width, scene.lane_width);
  });
}

bool stays_on_road(const std::vector<EgoState>& path, const Scenario& scene) {
  return std::all_of(path.begin(), path.end(),
                     [&](const EgoState& e) { return planner::body_on_road(e.y, scene); });
}

class DwaSession final : public planner::PlannerSession {
 public:
  explicit DwaSession(const Config& config) : config_(config), keeper_(config) {}

  [[nodiscard]] planner::Decision act(const planner::Observation& o) override {
    const Scenario& scene = *o.scene;
    const double dt = scene.horizon / scene.steps;
    std::vector<Candidate> admissible = admissible_candidates(o, dt);
    if (admissible.empty()) {
      return fallback(o, "no control in the dynamic window is admissible", dt);
    }
    const double goal_y = goal_lane(o, admissible);
    const Candidate* best = nullptr;
    double best_cost = std::numeric_limits<double>::infinity();
    for (const Candidate& c : admissible) {
      const double cost = score(c, goal_y);
      if (cost < best_cost) {
        best_cost = cost;
        best = &c;
      }
    }
    EgoControl u = best->u;
    (void)planner::clip_to_limits(u, o.ego, scene.limits, dt);
    last_omega_ = u.omega;
    return {u, planner::ActStatus::Planned, ""};
  }

 private:
  std::vector<Candidate> admissible_candidates(const planner::Observation& o, double dt) const {
    const DwaSettings& s = config_.dwa;
    const Scenario& scene = *o.scene;
    const int steps = std::max(1, static_cast<int>(std::lround(s.horizon / dt)));
    const TrafficPrediction cars = predict_from(o, config_, steps);
    const DynamicWindow window = dynamic_window({o.ego.a, last_omega_}, scene.limits, s, dt);
    std::vector<Candidate> out;
    for (int i = 0; i < s.accel_samples; ++i) {
      for (int j = 0; j < s.yaw_rate_samples; ++j) {
        const EgoControl u{sample(window.a, i, s.accel_samples),
                           sample(window.omega, j, s.yaw_rate_samples)};
        const std::vector<EgoState> path =
            constant_control_rollout(o.ego, u, steps, dt, scene.limits);
        if (!stays_on_road(path, scene) || !can_stop_safely(path.back(), cars, scene, s) ||
            (s.keep_safe_distances && !keeps_target_lane_distances(path, cars, scene))) {
          continue;
        }
        const double separation = min_separation(path, cars, scene, kClearanceCap);
        if (separation < s.margin) continue;
        out.push_back({u, path.back(), separation, reaches_target_lane(path, scene)});
      }
    }
    return out;
  }

  // The target lane is the goal while the change is on and some admissible
  // control can enter it (or the ego is already over the line); otherwise the
  // ego waits in its lane's centre: a goal the ego cannot reach would leave it
  // astride the line.
  [[nodiscard]] static double goal_lane(const planner::Observation& o,
                                        const std::vector<Candidate>& admissible) {
    const double w = o.scene->lane_width;
    const bool can_enter = std::any_of(admissible.begin(), admissible.end(),
                                       [](const Candidate& c) { return c.enters_target_lane; });
    return (can_enter && lane_change_on(o)) || o.ego.y > w / 2.0 ? w : 0.0;
  }

  // G of Fox et al. as a cost: heading to a goal on the goal lane's centre
  // line ahead of the rollout's end, lateral progress, clearance and speed.
  [[nodiscard]] double score(const Candidate& c, double goal_y) const {
    const DwaSettings& s = config_.dwa;
    const double ahead = std::max(c.end.v, 1.0) * s.goal_preview;
    const double heading_error = std::abs(std::atan2(goal_y - c.end.y, ahead) - c.end.theta);
    return s.weight_lateral * std::abs(c.end.y - goal_y) + s.weight_heading * heading_error +
           s.weight_clearance / c.separation + s.weight_speed * std::abs(c.end.v - s.desired_speed);
  }

  planner::Decision fallback(const planner::Observation& o, const char* why, double dt) {
    EgoControl u = planner::fallback_control(keeper_, o);
    (void)planner::clip_to_limits(u, o.ego, o.scene->limits, dt);
    last_omega_ = u.omega;
    return {u, planner::ActStatus::Fallback, why};
  }

  const Config& config_;
  planner::LaneKeeper keeper_;
  double last_omega_ = 0.0;  // the observation carries the last a, not the last omega
};

}  // namespace

DynamicWindow dynamic_window(EgoControl last, const Limits& limits, const DwaSettings& settings,
                             double dt) {
  auto reachable = [](double from, double change, const Interval& bound) {
    Interval r{std::max(from - change, bound.lo), std::min(from + change, bound.hi)};
    // A last control outside the limits (never applied as such) starts at the nearest bound.
    if (r.lo > r.hi) r.lo = r.hi = std::clamp(from, bound.lo, bound.hi);
    return r;
  };
  return {reachable(last.a, settings.max_jerk * dt, limits.a),
          reachable(last.omega, settings.max_yaw_accel * dt, limits.omega)};
}

std::vector<EgoState> constant_control_rollout(const EgoState& from, EgoControl u, int steps,
                                               double dt, const Limits& limits) {
  std::vector<EgoState> path;
  path.reserve(static_cast<std::size_t>(steps) + 1);
  path.push_back(from);
  for (int k = 0; k < steps; ++k) {
    EgoControl applied = u;
    (void)planner::clip_to_limits(applied, path.back(), limits, dt);
    EgoState next = step_trapezoidal(path.back(), applied, dt);
    next.a = applied.a;
    path.push_back(next);
  }
  return path;
}

std::unique_ptr<planner::PlannerSession> DwaPlanner::start(const Scenario& /*scene*/) const {
  return std::make_unique<DwaSession>(config_);
}

std::shared_ptr<const planner::ClosedLoopPlanner> make_dwa_planner(const Config& config) {
  return std::make_shared<const DwaPlanner>(config);
}

}  // namespace lanechange::baselines
