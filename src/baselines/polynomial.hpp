#pragma once
// Jerk-optimal polynomials of time (Werling et al. 2010): the quintic between
// two states (position, velocity, acceleration) and the quartic from a state
// to a velocity and acceleration, each over a duration T, held at constant
// velocity beyond T.
#include <array>

namespace lanechange::baselines {

/// Position, velocity and acceleration of one axis.
struct AxisState {
  double p = 0.0;
  double v = 0.0;
  double a = 0.0;
};

class Polynomial {
 public:
  /// The quintic from `from` to `to` in T seconds.
  static Polynomial quintic(AxisState from, AxisState to, double duration);
  /// The quartic from `from` to the velocity and acceleration of `to` (its
  /// position is free) in T seconds.
  static Polynomial quartic(AxisState from, AxisState to, double duration);

  /// The state at t >= 0; beyond the duration the end velocity is held.
  [[nodiscard]] AxisState at(double t) const;
  [[nodiscard]] double jerk(double t) const;
  /// The integral of the squared jerk over [0, T]: Werling's comfort cost.
  [[nodiscard]] double squared_jerk_integral() const;
  [[nodiscard]] double duration() const { return duration_; }

 private:
  /// Only the start's terms: every polynomial here begins at `from`.
  static Polynomial starting_at(AxisState from, double duration);

  std::array<double, 6> c_{};  // c_[i] multiplies t^i
  double duration_ = 0.0;
};

}  // namespace lanechange::baselines
