#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "lanechange/ego.hpp"
#include "lanechange/geometry.hpp"

namespace lanechange {
namespace {

TEST(Geometry, TouchingBoxesCollideAndSeparatedBoxesDoNot) {
  const OrientedBox a{0.0, 0.0, 0.0, 4.0, 2.0};
  EXPECT_TRUE(boxes_collide(a, {4.0, 0.0, 0.0, 4.0, 2.0}));  // bumpers touch
  EXPECT_NEAR(overlap_depth(a, {4.0, 0.0, 0.0, 4.0, 2.0}), 0.0, 1e-12);
  EXPECT_FALSE(boxes_collide(a, {4.001, 0.0, 0.0, 4.0, 2.0}));  // 1 mm apart
  EXPECT_TRUE(boxes_collide(a, {0.0, 2.0, 0.0, 4.0, 2.0}));     // sides touch
  EXPECT_FALSE(boxes_collide(a, {0.0, 2.01, 0.0, 4.0, 2.0}));
  EXPECT_TRUE(boxes_collide(a, {1.0, 0.5, 0.0, 4.0, 2.0}));  // overlap
}

TEST(Geometry, RotatedBoxReachesFurtherAcross) {
  // A box turned by 90 degrees spans y in [-2, 2]: it reaches a box that
  // spans [1.9, 3.9], which the unturned one (y in [-1, 1]) does not.
  const OrientedBox other{0.0, 2.9, 0.0, 4.0, 2.0};
  EXPECT_FALSE(boxes_collide({0.0, 0.0, 0.0, 4.0, 2.0}, other));
  EXPECT_TRUE(boxes_collide({0.0, 0.0, std::numbers::pi / 2, 4.0, 2.0}, other));
  // A diagonal corner gap: the separating axis is an edge of the turned box.
  const OrientedBox turned{0.0, 0.0, std::numbers::pi / 4, 2.0, 2.0};
  const double corner_reach = std::sqrt(2.0);
  EXPECT_FALSE(boxes_collide(turned, {corner_reach + 1.0 + 0.01, 0.0, 0.0, 2.0, 2.0}));
  EXPECT_TRUE(boxes_collide(turned, {corner_reach + 1.0 - 0.01, 0.0, 0.0, 2.0, 2.0}));
}

TEST(Ego, TrapezoidalStepIsExactForStraightConstantAcceleration) {
  EgoState s{0.0, 0.0, 5.0, 0.0, 0.0};
  for (int k = 0; k < 10; ++k) s = step_trapezoidal(s, {1.0, 0.0}, 0.1);
  EXPECT_NEAR(s.v, 6.0, 1e-12);
  EXPECT_NEAR(s.x, 5.0 + 0.5, 1e-12);
  EXPECT_DOUBLE_EQ(s.y, 0.0);
}

TEST(Ego, ExactStepFollowsACircle) {
  // Constant speed and yaw rate: a circle of radius v / omega.
  const double v = 10.0;
  const double omega = 0.2;
  EgoState s{0.0, 0.0, v, 0.0, 0.0};
  for (int k = 0; k < 50; ++k) s = step_exact(s, {0.0, omega}, 0.1);
  const double t = 5.0;
  const double r = v / omega;
  EXPECT_NEAR(s.x, r * std::sin(omega * t), 1e-6);
  EXPECT_NEAR(s.y, r * (1.0 - std::cos(omega * t)), 1e-6);
  EXPECT_NEAR(s.theta, omega * t, 1e-12);
  // The trapezoidal model is a second-order approximation of the same motion.
  EgoState trap{0.0, 0.0, v, 0.0, 0.0};
  for (int k = 0; k < 50; ++k) trap = step_trapezoidal(trap, {0.0, omega}, 0.1);
  EXPECT_NEAR(trap.x, s.x, 0.05);
  EXPECT_NEAR(trap.y, s.y, 0.05);
}

}  // namespace
}  // namespace lanechange
