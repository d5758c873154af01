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

Iterate quintic_warm_start(const Scenario& s, const Config& c, const TrafficPrediction& p) {
  const double T = s.horizon;
  const double dt = T / s.steps;
  const CarTrack& target = p.car(Car::Target);
  const int end = std::min(s.steps, p.nodes() - 1);
  double aim = target.x[end];
  if (c.expert.aim_behind_target) {
    const SafeDistance d = s.centre_safe_distances().target;
    aim -= d.standstill + d.time_headway * std::min(target.v[end], s.limits.v.hi);
  }
  const double end_speed = std::clamp(target.v[end], s.limits.v.lo, s.limits.v.hi);
  // A target far behind would make the path run backwards; the guess is only a
  // linearization point, so keep it moving forward.
  aim = std::max(aim, s.ego.x + 0.5 * (s.ego.v + end_speed) * T * 0.25);
  const Quintic x(s.ego.x, s.ego.v * std::cos(s.ego.theta), s.ego.a, aim, end_speed, target.a[end],
                  T);
  const Quintic y(s.ego.y, s.ego.v * std::sin(s.ego.theta), 0.0, s.lane_width, 0.0, 0.0, T);
  Iterate path;
  for (int k = 0; k <= s.steps; ++k) {
    const double t = k * dt;
    const double vx = std::max(x.rate(t), 0.1);
    const double vy = y.rate(t);
    path.states.emplace_back(x.value(t), y.value(t), std::hypot(vx, vy), std::atan2(vy, vx));
  }
  fill_controls(path, dt);
  return path;
}

// The authors' code: x = v0 t, a quintic y with zero end rates, v linear to
// the target's speed, theta constant.
Iterate authors_warm_start(const Scenario& s, const TrafficPrediction& p) {
  const double T = s.horizon;
  const double dt = T / s.steps;
  const Quintic y(s.ego.y, 0.0, 0.0, s.lane_width, 0.0, 0.0, T);
  const double v_end = p.car(Car::Target).v.front();
  Iterate path;
  for (int k = 0; k <= s.steps; ++k) {
    const double t = k * dt;
    path.states.emplace_back(s.ego.x + s.ego.v * t, y.value(t), s.ego.v + (v_end - s.ego.v) * t / T,
                             s.ego.theta);
  }
  fill_controls(path, dt);
  return path;
}

}  // namespace

Iterate warm_start(const Scenario& scenario, const Config& config,
                   const TrafficPrediction& prediction) {
  return config.expert.warm_start == WarmStart::Authors
             ? authors_warm_start(scenario, prediction)
             : quintic_warm_start(scenario, config, prediction);
}

}  // namespace lanechange::expert
