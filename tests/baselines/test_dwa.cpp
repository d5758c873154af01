#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "baselines/dwa.hpp"
#include "lanechange/error.hpp"

namespace lanechange {
namespace {

using baselines::constant_control_rollout;
using baselines::dynamic_window;

TEST(Dwa, WindowIsWhatOneStepReachesWithinTheLimits) {
  const Config config;
  const Limits& limits = config.limits;
  const double dt = config.dt();
  const DwaSettings& s = config.dwa;
  const auto w = dynamic_window({0.5, 0.1}, limits, s, dt);
  EXPECT_NEAR(w.a.lo, 0.5 - s.max_jerk * dt, 1e-12);
  EXPECT_NEAR(w.a.hi, 0.5 + s.max_jerk * dt, 1e-12);
  EXPECT_NEAR(w.omega.lo, 0.1 - s.max_yaw_accel * dt, 1e-12);
  EXPECT_NEAR(w.omega.hi, limits.omega.hi, 1e-12);  // cut at the yaw-rate limit
  for (const EgoControl last : {EgoControl{limits.a.lo, limits.omega.lo},
                                EgoControl{limits.a.hi, limits.omega.hi}, EgoControl{50.0, -9.0}}) {
    const auto cut = dynamic_window(last, limits, s, dt);
    EXPECT_LE(cut.a.lo, cut.a.hi);
    EXPECT_TRUE(limits.a.contains(cut.a.lo) && limits.a.contains(cut.a.hi));
    EXPECT_TRUE(limits.omega.contains(cut.omega.lo) && limits.omega.contains(cut.omega.hi));
  }
}

TEST(Dwa, RolloutHoldsTheControlAndSaturatesTheSpeed) {
  const Config config;
  const EgoState start{0.0, 0.0, 16.0, 0.0, 0.0};
  const auto path = constant_control_rollout(start, {3.0, 0.1}, 20, config.dt(), config.limits);
  ASSERT_EQ(path.size(), 21U);
  for (const EgoState& e : path) EXPECT_LE(e.v, config.limits.v.hi + 1e-12);
  EXPECT_NEAR(path.back().theta, 0.1 * 20 * config.dt(), 1e-12);
  EXPECT_GT(path.back().y, 0.0);  // turning left
}

TEST(Dwa, BadSettingsAreInputErrors) {
  for (const char* bad : {R"({"dwa": {"horizon": -1}})", R"({"dwa": {"accel_samples": 0}})",
                          R"({"dwa": {"max_jerk": 0}})", R"({"dwa": {"weight_speed": -1}})"}) {
    EXPECT_THROW((void)config_from_json(nlohmann::json::parse(bad)), InputError) << bad;
  }
  const Config read = config_from_json(nlohmann::json::parse(R"({"dwa": {"horizon": 1.5}})"));
  EXPECT_EQ(read.dwa.horizon, 1.5);
}

}  // namespace
}  // namespace lanechange
