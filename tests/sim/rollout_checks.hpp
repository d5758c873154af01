#pragma once
// The closed-loop consistency check every planner's rollouts must pass
// (docs/closed_loop.md), shared by the tests of our planners and the baselines.
#include <gtest/gtest.h>

#include "../foundation/test_helpers.hpp"
#include "lanechange/checks.hpp"
#include "lanechange/ego.hpp"
#include "lanechange/sim/simulator.hpp"
#include "lanechange/traffic.hpp"

namespace lanechange::testing {

// The checks every rollout must pass: the ego follows its controls through
// the exact model, the cars follow their behavior (reacting to the real ego),
// the collision flag is what the boxes say, and the limits hold. `config`
// is the rollout's, for its traffic settings.
inline void expect_consistent(const sim::Rollout& r, const Scenario& s,
                              const Config& config = Config{}) {
  const Trajectory& t = r.trajectory;
  ASSERT_EQ(t.nodes(), static_cast<int>(r.steps.size()) + 1);
  TrafficModel traffic(s, config);
  EgoState ego = s.ego;
  for (int k = 0; k + 1 < t.nodes(); ++k) {
    const EgoControl u = t.controls[k];
    EXPECT_TRUE(s.limits.a.contains(u.a)) << "step " << k;
    EXPECT_TRUE(s.limits.omega.contains(u.omega)) << "step " << k;
    traffic.step(t.dt, {ego.x, ego.y, ego.v});
    ego = step_exact(ego, u, t.dt);
    EXPECT_NEAR(t.ego[k + 1].x, ego.x, 1e-9) << "step " << k;
    EXPECT_NEAR(t.ego[k + 1].y, ego.y, 1e-9) << "step " << k;
    EXPECT_GE(t.ego[k + 1].v, s.limits.v.lo - 1e-9);
    EXPECT_LE(t.ego[k + 1].v, s.limits.v.hi + 1e-9);
    for (CarIndex c = 0; c < s.car_count(); ++c) {
      EXPECT_NEAR(t.others.car(c).x[k + 1], traffic.car(c).x, 1e-9) << s.cars[c].id << " " << k;
    }
  }
  EXPECT_EQ(t.collision, first_collision(t.ego, t.others, s).has_value());
  if (t.collision) {
    EXPECT_EQ(r.outcome, sim::Outcome::Failure);
  }
}

}  // namespace lanechange::testing
