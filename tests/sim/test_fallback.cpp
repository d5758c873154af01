// The fallback's choice of lane: over the line it keeps to the target lane,
// unless a cut-in went wrong there while its own lane is clear.
#include <gtest/gtest.h>

#include "lanechange/planner/planner.hpp"
#include "test_helpers.hpp"

namespace lanechange {
namespace {

planner::Observation over_the_line(const Scenario& scene, double y) {
  planner::Observation o;
  o.scene = &scene;
  o.ego = scene.ego;
  o.ego.y = y;
  o.cars = {scene.leader, scene.follower, scene.target};
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
  scene.follower = {-5.0, 11.0, 0.0};  // 0.6 m bumper to bumper, and faster
  const double w = scene.lane_width;
  EXPECT_FALSE(planner::fallback_in_target_lane(over_the_line(scene, 0.6 * w)));
  // With the leader as close as the follower, turning back gains nothing.
  scene.leader = {2.5, 2.0, 0.0};  // beside the ego, its safe distance broken further
  EXPECT_TRUE(planner::fallback_in_target_lane(over_the_line(scene, 0.6 * w)));
}

TEST(Fallback, TheLaneKeeperSteersTowardTheChosenLane) {
  Scenario scene = testing::open_road_scenario();
  const planner::LaneKeeper keeper(testing::untimed_config());
  const double w = scene.lane_width;
  EXPECT_GT(planner::fallback_control(keeper, over_the_line(scene, 0.6 * w)).omega, 0.0);
  scene.follower = {-5.0, 11.0, 0.0};
  EXPECT_LT(planner::fallback_control(keeper, over_the_line(scene, 0.6 * w)).omega, 0.0);
}

TEST(Fallback, BrakesForTheCarAheadInTheLaneItIsLeaving) {
  Scenario scene = testing::open_road_scenario();
  scene.follower = {9.0, 6.0, 0.0};  // ahead of the ego in the target lane, slower
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

}  // namespace
}  // namespace lanechange
