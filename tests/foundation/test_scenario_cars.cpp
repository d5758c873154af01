// Scenes of any number of cars: format 2, its validation, roles, and the
// traffic model over every car.
#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "lanechange/error.hpp"
#include "lanechange/scenario.hpp"
#include "lanechange/traffic.hpp"
#include "test_helpers.hpp"

namespace lanechange {
namespace {

using nlohmann::json;
using testing::dense_scenario;
using testing::example_cars_json;
using testing::example_scenario_json;
using testing::expect_rejected;

TEST(ScenarioCars, AFormat2FileMeansTheSameSceneAsItsFormat1Original) {
  const Scenario one = scenario_from_json(example_scenario_json(), Config{});
  const Scenario two = scenario_from_json(example_cars_json(), Config{});
  // The three cars in Role order with their roles: written back as format 1.
  EXPECT_EQ(scenario_to_json(two), scenario_to_json(one));
  EXPECT_EQ(scenario_to_json(one)["format"], "lanechange.scenario/1");
}

TEST(ScenarioCars, ManyCarsRoundTripThroughFormat2) {
  const Scenario s = dense_scenario(12);
  ASSERT_EQ(s.car_count(), 14U);
  const json written = scenario_to_json(s);
  EXPECT_EQ(written["format"], "lanechange.scenario/2");
  ASSERT_EQ(written["cars"].size(), 14U);
  const Scenario again = scenario_from_json(written, Config{});
  EXPECT_EQ(scenario_to_json(again), written);
  EXPECT_EQ(again.cars[5].id, "t3");
  EXPECT_EQ(again.cars[5].lane, Lane::Target);
}

TEST(ScenarioCars, RolesGoToTheNearestCarsWhereNoCarNamesOne) {
  const Scenario s = dense_scenario(8, -60.0, 16.0);  // t0 at -60 ... t7 at 52
  ASSERT_TRUE(s.has(Role::Leader));
  EXPECT_EQ(s.cars[s.index_of(Role::Leader)].id, "lead");
  // The target lane's cars nearest behind (x <= 0) and ahead of the ego.
  EXPECT_EQ(s.cars[s.index_of(Role::Follower)].id, "t3");  // at -12
  EXPECT_EQ(s.cars[s.index_of(Role::Target)].id, "t4");    // at 4
  const Scenario empty = dense_scenario(0);
  EXPECT_FALSE(empty.has(Role::Follower));
  EXPECT_FALSE(empty.has(Role::Target));
  EXPECT_THROW((void)empty.index_of(Role::Target), std::logic_error);
  // Named roles are kept, even where they are not the nearest cars.
  json j = example_cars_json();
  j["cars"].push_back({{"id", "near"}, {"lane", "target"}, {"x", 8.0}, {"v", 9.0}});
  const Scenario named = scenario_from_json(j, Config{});
  EXPECT_EQ(named.cars[named.index_of(Role::Target)].id, "target");
}

TEST(ScenarioCars, ACarMayCarryItsOwnBehavior) {
  json j = example_cars_json();
  j["cars"][0]["behavior"] = "constant_accel";
  j["cars"][0]["a"] = -0.5;
  j["cars"][1]["behavior"] = "idm";
  const Scenario s = scenario_from_json(j, Config{});
  EXPECT_EQ(s.cars[0].behavior, Behavior::ConstantAccel);
  EXPECT_EQ(s.cars[1].behavior, Behavior::Idm);
  EXPECT_EQ(s.cars[2].behavior, Behavior::ConstantSpeed);
  EXPECT_EQ(scenario_to_json(s)["format"], "lanechange.scenario/2");
  TrafficModel traffic(s, Config{});
  traffic.step(0.1, {s.ego.x, s.ego.y, s.ego.v});
  EXPECT_DOUBLE_EQ(traffic.car(0).a, -0.5);
  EXPECT_NE(traffic.car(1).a, 0.0);  // IDM: free road ahead until the target
  EXPECT_DOUBLE_EQ(traffic.car(2).a, 0.0);
  // A constant-acceleration car must give its acceleration.
  j["cars"][0].erase("a");
  expect_rejected(j, "cars[0].a", "missing");
}

// A change into the lane to the right is held as its mirror image: the
// ego's y and heading are negated when read and again when written, and the
// cars, which name their lanes, stay as they are.
TEST(ScenarioCars, ARightHandChangeIsHeldAsItsMirrorImage) {
  json left = example_cars_json();
  left["ego"]["y"] = 0.4;
  left["ego"]["theta"] = 0.05;
  json right = left;
  right["road"]["target_lane"] = "right";
  right["ego"]["y"] = -0.4;
  right["ego"]["theta"] = -0.05;
  const Scenario l = scenario_from_json(left, Config{});
  const Scenario r = scenario_from_json(right, Config{});
  EXPECT_EQ(r.target_side, Side::Right);
  EXPECT_DOUBLE_EQ(r.ego.y, l.ego.y);
  EXPECT_DOUBLE_EQ(r.ego.theta, l.ego.theta);
  const json written = scenario_to_json(r);
  EXPECT_EQ(written["format"], "lanechange.scenario/2");
  EXPECT_EQ(written["road"]["target_lane"], "right");
  EXPECT_DOUBLE_EQ(written["ego"]["y"].get<double>(), -0.4);
  EXPECT_EQ(scenario_to_json(scenario_from_json(written, Config{})), written);
}

TEST(ScenarioCarsBadInput, EachProblemNamesItsField) {
  json unknown = example_cars_json();
  unknown["cars"][1]["colour"] = "red";
  expect_rejected(unknown, "cars[1].colour", "unknown");
  json lane = example_cars_json();
  lane["cars"][2]["lane"] = "shoulder";
  expect_rejected(lane, "cars[2].lane", "ego");
  json twice = example_cars_json();
  twice["cars"][2]["id"] = "follower";
  expect_rejected(twice, "cars[2].id", "two cars");
  json overlap = example_cars_json();
  overlap["cars"].push_back({{"id", "x"}, {"lane", "target"}, {"x", 22.0}, {"v", 9.0}});
  expect_rejected(overlap, "cars[3].x", "overlaps");
  json role = example_cars_json();
  role["cars"][2]["role"] = "follower";
  expect_rejected(role, "cars[2].role", "another car");
  json wrong_lane = example_cars_json();
  wrong_lane["cars"][0]["role"] = "target";
  wrong_lane["cars"][2].erase("role");
  expect_rejected(wrong_lane, "cars[0].lane", "target lane");
  json negative = example_cars_json();
  negative["cars"][1]["v"] = -1.0;
  expect_rejected(negative, "cars[1].v", "negative");
  json side = example_cars_json();
  side["road"]["target_lane"] = "up";
  expect_rejected(side, "road.target_lane", "right");
  json off_road = example_cars_json();
  off_road["road"]["target_lane"] = "right";
  off_road["ego"]["y"] = 2.0;  // beyond the right-hand road's left edge, w/2
  expect_rejected(off_road, "ego.y", "[-3w/2, w/2]");
  json mixed = example_cars_json();
  mixed["leader"] = {{"x", 1.0}, {"v", 1.0}};
  expect_rejected(mixed, "leader", "unknown");
  json not_a_list = example_cars_json();
  not_a_list["cars"] = json::object();
  expect_rejected(not_a_list, "cars", "array");
}

TEST(ScenarioCars, ThirtyCarsAndNoneAreScenes) {
  const Scenario none = dense_scenario(0);
  EXPECT_EQ(none.car_count(), 2U);
  json j = scenario_to_json(none);
  j["cars"] = json::array();
  const Scenario empty = scenario_from_json(j, Config{});
  EXPECT_EQ(empty.car_count(), 0U);
  const Scenario thirty = dense_scenario(30, -200.0, 14.0);
  EXPECT_EQ(thirty.car_count(), 32U);
  const TrafficPrediction p = predict_traffic(thirty, Config{}, 10, 0.1);
  EXPECT_EQ(p.car_count(), 32U);
  EXPECT_EQ(p.nodes(), 11);
}

// Under IDM a car follows the nearest car ahead in its lane among many, and
// not a nearer one of the other lane.
TEST(ScenarioCars, AnIdmCarFollowsTheNearestCarAheadInItsLane) {
  json j = example_cars_json();
  j["behavior"] = "idm";
  j["cars"] = json::array({{{"id", "back"}, {"lane", "target"}, {"x", -30.0}, {"v", 12.0}},
                           {{"id", "slow"}, {"lane", "target"}, {"x", -18.0}, {"v", 2.0}},
                           {{"id", "far"}, {"lane", "target"}, {"x", 40.0}, {"v", 12.0}},
                           {{"id", "beside"}, {"lane", "ego"}, {"x", -26.0}, {"v", 2.0}}});
  j["ego"]["x"] = 60.0;
  const Scenario s = scenario_from_json(j, Config{});
  TrafficModel traffic(s, Config{});
  traffic.step(0.1, {s.ego.x, s.ego.y, s.ego.v});
  Config unlimited;
  unlimited.traffic.max_decel.reset();
  TrafficModel unbounded(s, unlimited);
  unbounded.step(0.1, {s.ego.x, s.ego.y, s.ego.v});
  const double behind_slow = idm_acceleration(s.idm, 12.0, 12.0 - s.vehicle.length, 2.0);
  EXPECT_DOUBLE_EQ(unbounded.car(0).a, behind_slow);
  EXPECT_DOUBLE_EQ(traffic.car(0).a, std::max(behind_slow, -*Config{}.traffic.max_decel));
  // "beside", in the other lane and closer, is not followed by "back";
  // "slow" follows "far", 58 m ahead.
  EXPECT_GT(traffic.car(1).a, 0.0);
}

}  // namespace
}  // namespace lanechange
