#include <gtest/gtest.h>

#include <cmath>

#include "lanechange/error.hpp"
#include "lanechange/scenario.hpp"
#include "test_helpers.hpp"

namespace lanechange {
namespace {

using nlohmann::json;
using testing::example_scenario_json;

using testing::expect_rejected;

TEST(Scenario, ParsesTheFormatsExample) {
  const Scenario s = scenario_from_json(example_scenario_json(), Config{});
  EXPECT_DOUBLE_EQ(s.lane_width, 3.5);
  EXPECT_EQ(s.behavior, Behavior::ConstantSpeed);
  EXPECT_DOUBLE_EQ(s.ego.v, 8.0);
  EXPECT_DOUBLE_EQ(s.follower().x, -12.0);
  EXPECT_DOUBLE_EQ(s.target().v, 9.5);
  EXPECT_DOUBLE_EQ(s.horizon, Config{}.expert.horizon);
  EXPECT_EQ(s.steps, Config{}.expert.steps);
}

TEST(Scenario, OptionalFieldsOverrideDefaults) {
  json j = example_scenario_json();
  j["horizon"] = 6.0;
  j["steps"] = 60;
  j["vehicle"] = {{"length", 5.0}, {"width", 2.0}};
  j["safe_distance"] = {{"leader", 10.0},
                        {"follower", {{"standstill", 7.0}, {"time_headway", 1.0}}}};
  j["limits"] = {{"v", {0.0, 20.0}}, {"a", {-3.0, 2.0}}, {"omega", {-0.2, 0.2}}};
  j["idm"] = {{"min_gap", 3.0}};
  const Scenario s = scenario_from_json(j, Config{});
  EXPECT_DOUBLE_EQ(s.horizon, 6.0);
  EXPECT_EQ(s.steps, 60);
  EXPECT_DOUBLE_EQ(s.vehicle.length, 5.0);
  EXPECT_DOUBLE_EQ(s.safe_distance.leader.standstill, 10.0);
  EXPECT_DOUBLE_EQ(s.safe_distance.leader.time_headway, 0.0);
  EXPECT_DOUBLE_EQ(s.safe_distance.follower.time_headway, 1.0);
  EXPECT_DOUBLE_EQ(s.safe_distance.target.standstill, Config{}.safety.target.standstill);
  EXPECT_DOUBLE_EQ(s.limits.a.lo, -3.0);
  EXPECT_DOUBLE_EQ(s.idm.min_gap, 3.0);
  EXPECT_DOUBLE_EQ(s.idm.time_headway, Config{}.idm.time_headway);
}

TEST(Scenario, RoundTripsThroughJson) {
  json j = example_scenario_json();
  j["behavior"] = "constant_accel";
  j["leader"]["a"] = 0.3;
  const Scenario s = scenario_from_json(j, Config{});
  const Scenario again = scenario_from_json(scenario_to_json(s), make_preset("authors"));
  EXPECT_EQ(scenario_to_json(again), scenario_to_json(s));
  EXPECT_DOUBLE_EQ(again.leader().a, 0.3);
}

// Recorded traffic mixes trucks and cars: each car may carry its own body.
TEST(Scenario, ACarMayCarryItsOwnSizeAndKeepsItThroughJson) {
  json j = example_scenario_json();
  j["leader"]["length"] = 12.0;
  j["leader"]["width"] = 2.5;
  j["target"]["length"] = 6.0;  // the width then is the vehicle's
  const Scenario s = scenario_from_json(j, Config{});
  EXPECT_DOUBLE_EQ(s.size_of(car_of(Role::Leader)).length, 12.0);
  EXPECT_DOUBLE_EQ(s.size_of(car_of(Role::Leader)).width, 2.5);
  EXPECT_DOUBLE_EQ(s.size_of(car_of(Role::Target)).length, 6.0);
  EXPECT_DOUBLE_EQ(s.size_of(car_of(Role::Target)).width, s.vehicle.width);
  EXPECT_DOUBLE_EQ(s.size_of(car_of(Role::Follower)).length, s.vehicle.length);
  const json written = scenario_to_json(s);
  EXPECT_DOUBLE_EQ(written["leader"]["length"].get<double>(), 12.0);
  EXPECT_FALSE(written["follower"].contains("length"));  // absent stays absent
  EXPECT_EQ(scenario_to_json(scenario_from_json(written, Config{})), written);
  // Bumper gaps and Eq. 1's centre distances count each car's half length.
  EXPECT_DOUBLE_EQ(s.bumper_gap(car_of(Role::Leader), 20.0),
                   20.0 - 0.5 * (s.vehicle.length + 12.0));
  EXPECT_DOUBLE_EQ(s.centre_safe_distances().leader.standstill,
                   s.safe_distance.leader.standstill + 0.5 * (12.0 - s.vehicle.length));
  EXPECT_DOUBLE_EQ(s.centre_safe_distances().follower.standstill,
                   s.safe_distance.follower.standstill);
}

TEST(ScenarioBadInput, ACarSizeOutOfRangeIsNamed) {
  json j = example_scenario_json();
  j["leader"]["width"] = 9.0;  // wider than the lane
  expect_rejected(j, "leader.width");
  json k = example_scenario_json();
  k["target"]["length"] = 0.0;
  expect_rejected(k, "target.length");
  json l = example_scenario_json();
  l["follower"]["length"] = "long";
  expect_rejected(l, "follower.length");
  // A longer leader reaches back to the ego: an overlap at t = 0.
  json m = example_scenario_json();
  m["leader"]["x"] = m["ego"]["x"].get<double>() + 6.0;
  EXPECT_NO_THROW((void)scenario_from_json(m, Config{}));
  m["leader"]["length"] = 9.0;
  expect_rejected(m, "leader.x");
}

TEST(ScenarioBadInput, NotJson) {
  EXPECT_THROW((void)scenario_from_text("{\"lane_width\": 3.5,", Config{}), InputError);
  EXPECT_THROW((void)scenario_from_text("[1, 2]", Config{}), InputError);
}

TEST(ScenarioBadInput, MissingRequiredFields) {
  for (const char* key : {"lane_width", "behavior", "ego", "leader", "follower", "target"}) {
    json j = example_scenario_json();
    j.erase(key);
    expect_rejected(j, key);
  }
  for (const char* key : {"x", "y", "v", "theta"}) {
    json j = example_scenario_json();
    j["ego"].erase(key);
    expect_rejected(j, std::string("ego.") + key);
  }
  json j = example_scenario_json();
  j["target"].erase("v");
  expect_rejected(j, "target.v");
}

TEST(ScenarioBadInput, AccelerationRequiredForConstantAccel) {
  json j = example_scenario_json();
  j["behavior"] = "constant_accel";
  j["follower"].erase("a");
  expect_rejected(j, "follower.a");
}

TEST(ScenarioBadInput, UnknownBehavior) {
  json j = example_scenario_json();
  j["behavior"] = "teleport";
  expect_rejected(j, "behavior");
}

TEST(ScenarioBadInput, NonFiniteNumbers) {
  // JSON has no NaN literal: a NaN arrives as text, or as a number too large for a double.
  json j = example_scenario_json();
  j["leader"]["v"] = "NaN";
  expect_rejected(j, "leader.v");
  const std::string text = R"({"format": "lanechange.scenario/1", "lane_width": 3.5,
    "behavior": "idm", "ego": {"x": 0, "y": 0, "v": 1e999, "theta": 0},
    "leader": {"x": 30, "v": 7}, "follower": {"x": -12, "v": 9}, "target": {"x": 20, "v": 9}})";
  try {
    (void)scenario_from_text(text, Config{});
    FAIL() << "accepted an infinite speed";
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "ego.v");
  }
  json nan_value = example_scenario_json();
  nan_value["ego"]["x"] = std::nan("");
  expect_rejected(nan_value, "ego.x");
}

TEST(ScenarioBadInput, NegativeSpeedOrLaneWidth) {
  for (const char* car : {"ego", "leader", "follower", "target"}) {
    json j = example_scenario_json();
    j[car]["v"] = -1.0;
    expect_rejected(j, std::string(car) + ".v");
  }
  json j = example_scenario_json();
  j["lane_width"] = -3.5;
  expect_rejected(j, "lane_width");
}

TEST(ScenarioBadInput, OverlappingCars) {
  json j = example_scenario_json();
  j["leader"]["x"] = 3.0;  // 3 m ahead of the ego's centre, cars 4.4 m long
  expect_rejected(j, "leader.x");
  json t = example_scenario_json();
  t["target"]["x"] = -9.0;  // 3 m ahead of the follower
  expect_rejected(t, "target.x");
  json e = example_scenario_json();
  e["ego"]["y"] = 3.0;  // the ego stands across the lane line, beside the follower
  e["follower"]["x"] = 1.0;
  expect_rejected(e, "follower.x");
}

TEST(ScenarioBadInput, WrongTypesAndUnknownFields) {
  json j = example_scenario_json();
  j["ego"] = "here";
  expect_rejected(j, "ego");
  json k = example_scenario_json();
  k["leader"]["speed"] = 3.0;
  expect_rejected(k, "leader.speed");
  json f = example_scenario_json();
  f["format"] = "lanechange.scenario/3";
  expect_rejected(f, "format");
  json s = example_scenario_json();
  s["steps"] = 2.5;
  expect_rejected(s, "steps");
}

}  // namespace
}  // namespace lanechange
