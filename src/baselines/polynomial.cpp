#include "baselines/polynomial.hpp"

#include <Eigen/Dense>
#include <algorithm>

namespace lanechange::baselines {

Polynomial Polynomial::starting_at(AxisState from, double duration) {
  Polynomial p;
  p.duration_ = duration;
  p.c_[0] = from.p;
  p.c_[1] = from.v;
  p.c_[2] = from.a / 2.0;
  return p;
}

Polynomial Polynomial::quintic(AxisState from, AxisState to, double duration) {
  Polynomial p = starting_at(from, duration);
  const double t = duration;
  const double t2 = t * t;
  const double t3 = t2 * t;
  Eigen::Matrix3d m;
  m << t3, t3 * t, t3 * t2, 3 * t2, 4 * t3, 5 * t3 * t, 6 * t, 12 * t2, 20 * t3;
  const Eigen::Vector3d rest(to.p - (p.c_[0] + p.c_[1] * t + p.c_[2] * t2),
                             to.v - (p.c_[1] + 2 * p.c_[2] * t), to.a - 2 * p.c_[2]);
  const Eigen::Vector3d high = m.partialPivLu().solve(rest);
  for (int i = 0; i < 3; ++i) p.c_[3 + i] = high[i];
  return p;
}

Polynomial Polynomial::quartic(AxisState from, AxisState to, double duration) {
  Polynomial p = starting_at(from, duration);
  const double t = duration;
  Eigen::Matrix2d m;
  m << 3 * t * t, 4 * t * t * t, 6 * t, 12 * t * t;
  const Eigen::Vector2d rest(to.v - from.v - from.a * t, to.a - from.a);
  const Eigen::Vector2d high = m.partialPivLu().solve(rest);
  p.c_[3] = high[0];
  p.c_[4] = high[1];
  return p;
}

AxisState Polynomial::at(double t) const {
  const double within = std::min(t, duration_);
  const auto& c = c_;
  const double u = within;
  AxisState s;
  s.p = c[0] + u * (c[1] + u * (c[2] + u * (c[3] + u * (c[4] + u * c[5]))));
  s.v = c[1] + u * (2 * c[2] + u * (3 * c[3] + u * (4 * c[4] + u * 5 * c[5])));
  s.a = 2 * c[2] + u * (6 * c[3] + u * (12 * c[4] + u * 20 * c[5]));
  if (t > duration_) {
    // Held at the end velocity: every sampled end state has a = 0.
    s.p += s.v * (t - duration_);
    s.a = 0.0;
  }
  return s;
}

double Polynomial::jerk(double t) const {
  if (t > duration_) return 0.0;
  return 6 * c_[3] + t * (24 * c_[4] + t * 60 * c_[5]);
}

double Polynomial::squared_jerk_integral() const {
  // jerk = j0 + j1 t + j2 t^2, squared and integrated term by term.
  const double j0 = 6 * c_[3];
  const double j1 = 24 * c_[4];
  const double j2 = 60 * c_[5];
  const double t = duration_;
  return t * (j0 * j0 + t * (j0 * j1 + t * ((j1 * j1 + 2 * j0 * j2) / 3.0 +
                                            t * (j1 * j2 / 2.0 + t * j2 * j2 / 5.0))));
}

}  // namespace lanechange::baselines
