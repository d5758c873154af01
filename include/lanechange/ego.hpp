#pragma once
// The ego as a unicycle: state [x, y, v, theta], control [a, omega].
#include "lanechange/scenario.hpp"

namespace lanechange {

struct EgoControl {
  double a = 0.0;      ///< m/s^2
  double omega = 0.0;  ///< rad/s
};

/// The planner's discrete model: v and theta take the exact step of a
/// constant control, x and y the trapezoidal rule on v cos(theta) and
/// v sin(theta) between the two nodes. With a and omega held over the step
/// this is explicit, so a plan's states follow from its controls by it.
[[nodiscard]] EgoState step_trapezoidal(const EgoState& state, EgoControl control, double dt);

/// The continuous unicycle integrated by classical Runge-Kutta in `substeps`
/// pieces: the "real" car of the closed loop.
[[nodiscard]] EgoState step_exact(const EgoState& state, EgoControl control, double dt,
                                  int substeps = 4);

}  // namespace lanechange
