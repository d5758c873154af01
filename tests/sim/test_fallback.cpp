// The fallback's choice of lane: over the line it keeps to the target lane,
// unless a cut-in went wrong there while its own lane is clear. And the lane
// keeper's speed, between the car ahead and a faster one behind.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "lanechange/ego.hpp"
#include "lanechange/planner/planner.hpp"
#include "test_helpers.hpp"

namespace lanechange {
namespace {

planner::Observation over_the_line(const Scenario& scene, double y) {
  planner::Observation o;
  o.scene = &scene;
  o.ego = scene.ego;
  o.ego.y = y;
  o.cars = {scene.leader(), scene.follower(), scene.target()};
  return o;
}

TEST(Fallback, KeepsItsLaneBeforeTheLineAndTheTargetLaneAfterItWhenThatIsClear) {
  const Scenario open = testing::open_road_scenario();
  const double w = open.lane_width;
  EXPECT_FALSE(planner::fallback_in_target_lane(over_the_line(open, 0.4 * w)));
  EXPECT_TRUE(planner::fallback_in_target_lane(over_the_line(open, 0.6 * w)));
}

TEST(Fallback, BacksOutOfACutInRightInFrontOfTheFollower) {
  Scenario scene = testing::open_road_scenario();
  scene.follower() = {-5.0, 11.0, 0.0};  // 0.6 m bumper to bumper, and faster
  const double w = scene.lane_width;
  EXPECT_FALSE(planner::fallback_in_target_lane(over_the_line(scene, 0.6 * w)));
  // With the leader as close as the follower, turning back gains nothing.
  scene.leader() = {2.5, 2.0, 0.0};  // beside the ego, its safe distance broken further
  EXPECT_TRUE(planner::fallback_in_target_lane(over_the_line(scene, 0.6 * w)));
}

TEST(Fallback, TheLaneKeeperSteersTowardTheChosenLane) {
  Scenario scene = testing::open_road_scenario();
  const planner::LaneKeeper keeper(testing::untimed_config());
  const double w = scene.lane_width;
  EXPECT_GT(planner::fallback_control(keeper, over_the_line(scene, 0.6 * w)).omega, 0.0);
  scene.follower() = {-5.0, 11.0, 0.0};
  EXPECT_LT(planner::fallback_control(keeper, over_the_line(scene, 0.6 * w)).omega, 0.0);
}

TEST(Fallback, BrakesForTheCarAheadInTheLaneItIsLeaving) {
  Scenario scene = testing::open_road_scenario();
  scene.follower() = {9.0, 6.0, 0.0};  // ahead of the ego in the target lane, slower
  const double w = scene.lane_width;
  const planner::LaneKeeper keeper(testing::untimed_config());
  const auto o = over_the_line(scene, 0.9 * w);
  ASSERT_FALSE(planner::fallback_in_target_lane(o));  // backs out toward its own lane
  const EgoControl u = planner::fallback_control(keeper, o);
  EXPECT_LT(u.omega, 0.0);
  EXPECT_LT(u.a, -1.0);  // the leader is far ahead; the follower is not
  // Once its body has left the target lane, only its own lane counts.
  EXPECT_GT(planner::fallback_control(keeper, over_the_line(scene, 0.0)).a, 0.0);
}

TEST(Fallback, DoesNotBrakeForACarAlreadyBesideItInTheLaneItIsLeaving) {
  // Braking cannot take the ego away from a car beside it, only stop it in
  // the way of the cars behind; its own lane and the cars wholly ahead decide.
  Scenario scene = testing::open_road_scenario();
  const double w = scene.lane_width;
  const planner::LaneKeeper keeper(testing::untimed_config());
  scene.follower() = {-200.0, 6.0, 0.0};
  const EgoControl alone = planner::fallback_control(keeper, over_the_line(scene, 0.4 * w));
  scene.follower() = {2.0, 6.0, 0.0};  // beside the ego's body, slower
  const auto beside = over_the_line(scene, 0.4 * w);
  ASSERT_FALSE(planner::fallback_in_target_lane(beside));
  ASSERT_GT(beside.ego.y + scene.vehicle.width / 2.0, w / 2.0);  // the body pokes across
  EXPECT_DOUBLE_EQ(planner::fallback_control(keeper, beside).a, alone.a);
  scene.follower() = {7.0, 6.0, 0.0};  // its rear 2.6 m ahead of the ego's front
  EXPECT_LT(planner::fallback_control(keeper, over_the_line(scene, 0.4 * w)).a, alone.a - 1.0);
}

// Seconds until the ego's body has left the target lane under the fallback,
// backing out of a cut-in in front of a faster follower (every car keeps its
// speed), and the largest |heading| and final offset from the ego lane on
// the way, over `seconds`.
struct BackOut {
  double time_out = std::numeric_limits<double>::infinity();
  double max_heading = 0.0;
  double final_y = 0.0;
};

BackOut back_out(const Config& config, double seconds) {
  Scenario scene = testing::open_road_scenario();
  scene.follower() = {-5.0, 11.0, 0.0};
  const planner::LaneKeeper keeper(config);
  planner::Observation o = over_the_line(scene, scene.lane_width);
  constexpr double kDt = 0.1;
  BackOut out;
  for (double t = 0.0; t < seconds; t += kDt) {
    EgoControl u = planner::fallback_control(keeper, o);
    planner::clip_to_limits(u, o.ego, config.limits, kDt);
    o.ego = step_exact(o.ego, u, kDt);
    for (CarState& car : o.cars) car.x += car.v * kDt;
    out.max_heading = std::max(out.max_heading, std::abs(o.ego.theta));
    if (o.ego.y + scene.vehicle.width / 2.0 < scene.lane_width / 2.0) {
      out.time_out = std::min(out.time_out, t + kDt);
    }
  }
  out.final_y = o.ego.y;
  return out;
}

TEST(Fallback, BacksOutAtTheBackOutHeadingAndSettlesInItsLane) {
  Config config = testing::untimed_config();
  const BackOut calm = back_out(config, 12.0);  // the default: the keeper's own heading
  EXPECT_LE(calm.max_heading, planner::LaneKeeper::kCalmHeading + 1e-9);
  config.closed_loop.keeper_backout_heading = 0.3;
  const BackOut sharp = back_out(config, 12.0);
  EXPECT_GT(sharp.max_heading, planner::LaneKeeper::kCalmHeading + 0.03);
  EXPECT_LE(sharp.max_heading, 0.3 + 1e-9);
  EXPECT_LT(std::abs(sharp.final_y), 0.25);  // no swerve past its own lane
  EXPECT_LT(sharp.time_out + 0.5, calm.time_out);
}

// In the target lane, a constant-speed car 6 m/s faster 15 m behind the ego,
// and the next car far ahead at that speed too.
Scenario pushed_from_behind() {
  Scenario scene = testing::open_road_scenario();
  scene.ego.y = scene.lane_width;
  scene.follower() = {-15.0 - scene.vehicle.length, 14.0, 0.0};
  scene.target() = {120.0, 14.0, 0.0};
  return scene;
}

planner::Observation in_the_target_lane(const Scenario& scene) {
  return over_the_line(scene, scene.lane_width);
}

// The smallest bumper gap to the car behind over `seconds` of the keeper in
// the target lane, every car keeping its speed (as the traffic models'
// constant-speed cars ignore the ego).
double closest_gap_behind(const Scenario& scene, const Config& config, double seconds) {
  const planner::LaneKeeper keeper(config);
  planner::Observation o = in_the_target_lane(scene);
  constexpr double kDt = 0.1;
  double closest = std::numeric_limits<double>::infinity();
  for (double t = 0.0; t < seconds; t += kDt) {
    EgoControl u = keeper.control(o.ego, scene.lane_width, planner::car_ahead(o, true),
                                  planner::car_behind(o, true));
    planner::clip_to_limits(u, o.ego, config.limits, kDt);
    o.ego = step_exact(o.ego, u, kDt);
    for (CarState& car : o.cars) car.x += car.v * kDt;
    const CarState& behind = o.cars[car_of(Role::Follower)];
    closest = std::min(closest, o.ego.x - behind.x - scene.vehicle.length);
  }
  return closest;
}

TEST(LaneKeeper, KeepsUpWithAFasterCarClosingInFromBehind) {
  const Scenario scene = pushed_from_behind();
  Config config = testing::untimed_config();
  const planner::LaneKeeper keeper(config);
  const auto o = in_the_target_lane(scene);
  const EgoControl ahead_only = keeper.control(o.ego, scene.lane_width, std::nullopt);
  const EgoControl with_behind =
      keeper.control(o.ego, scene.lane_width, std::nullopt, planner::car_behind(o, true));
  EXPECT_GT(with_behind.a, ahead_only.a + 0.5);
  EXPECT_GT(closest_gap_behind(scene, config, 15.0), config.idm.min_gap);  // bumper to bumper
  // A keeper that watches the car ahead only is driven into.
  config.closed_loop.keeper_rear_horizon = 0.0;
  EXPECT_LT(closest_gap_behind(scene, config, 15.0), 0.0);
}

// Cut in 1.5 m in front of a car 3 m/s faster: it matches the speed before
// contact, where a second's match would not.
TEST(LaneKeeper, OutrunsACarRightBehindItBeforeContact) {
  Scenario scene = pushed_from_behind();
  scene.follower() = {-1.5 - scene.vehicle.length, scene.ego.v + 3.0, 0.0};
  Config config = testing::untimed_config();
  EXPECT_GT(closest_gap_behind(scene, config, 5.0), 0.0);
  config.closed_loop.keeper_rear_horizon = 0.0;
  EXPECT_LT(closest_gap_behind(scene, config, 5.0), 0.0);
}

TEST(LaneKeeper, TheCarAheadStillLimitsItsSpeedWhenACarBehindPushes) {
  Scenario scene = pushed_from_behind();
  scene.target() = {12.0, 6.0, 0.0};  // a slower car close ahead in the target lane
  const planner::LaneKeeper keeper(testing::untimed_config());
  const auto o = in_the_target_lane(scene);
  const EgoControl u = keeper.control(o.ego, scene.lane_width, planner::car_ahead(o, true),
                                      planner::car_behind(o, true));
  EXPECT_LT(u.a, 0.0);
}

TEST(LaneKeeper, IgnoresASlowerOrDistantCarBehind) {
  const Config config = testing::untimed_config();
  const planner::LaneKeeper keeper(config);
  for (const CarState behind : {CarState{-15.0, 7.0, 0.0}, CarState{-200.0, 14.0, 0.0}}) {
    Scenario scene = pushed_from_behind();
    scene.follower() = behind;
    const auto o = in_the_target_lane(scene);
    const EgoControl ahead_only = keeper.control(o.ego, scene.lane_width, std::nullopt);
    const EgoControl with_behind =
        keeper.control(o.ego, scene.lane_width, std::nullopt, planner::car_behind(o, true));
    EXPECT_EQ(with_behind.a, ahead_only.a) << "car behind at " << behind.x;
  }
  // In the ego lane there is no car behind to watch.
  EXPECT_FALSE(planner::car_behind(in_the_target_lane(pushed_from_behind()), false));
}

}  // namespace
}  // namespace lanechange
