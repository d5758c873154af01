#include <cmath>

#include "lanechange/ego.hpp"

namespace lanechange {

EgoState step_trapezoidal(const EgoState& s, EgoControl u, double dt) {
  EgoState next = s;
  next.v = s.v + dt * u.a;
  next.theta = s.theta + dt * u.omega;
  next.x = s.x + 0.5 * dt * (s.v * std::cos(s.theta) + next.v * std::cos(next.theta));
  next.y = s.y + 0.5 * dt * (s.v * std::sin(s.theta) + next.v * std::sin(next.theta));
  next.a = u.a;
  return next;
}

namespace {

struct Rate {
  double x, y, v, theta;
};

Rate rate(const EgoState& s, EgoControl u) {
  return {s.v * std::cos(s.theta), s.v * std::sin(s.theta), u.a, u.omega};
}

EgoState moved(const EgoState& s, const Rate& r, double h) {
  EgoState out = s;
  out.x += h * r.x;
  out.y += h * r.y;
  out.v += h * r.v;
  out.theta += h * r.theta;
  return out;
}

}  // namespace

EgoState step_exact(const EgoState& state, EgoControl u, double dt, int substeps) {
  EgoState s = state;
  const double h = dt / substeps;
  for (int i = 0; i < substeps; ++i) {
    const Rate k1 = rate(s, u);
    const Rate k2 = rate(moved(s, k1, 0.5 * h), u);
    const Rate k3 = rate(moved(s, k2, 0.5 * h), u);
    const Rate k4 = rate(moved(s, k3, h), u);
    s.x += h / 6.0 * (k1.x + 2 * k2.x + 2 * k3.x + k4.x);
    s.y += h / 6.0 * (k1.y + 2 * k2.y + 2 * k3.y + k4.y);
    s.v += h / 6.0 * (k1.v + 2 * k2.v + 2 * k3.v + k4.v);
    s.theta += h / 6.0 * (k1.theta + 2 * k2.theta + 2 * k3.theta + k4.theta);
  }
  s.a = u.a;
  return s;
}

}  // namespace lanechange
