#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "lanechange/traffic.hpp"
#include "test_helpers.hpp"

namespace lanechange {
namespace {

Scenario two_lane_scene(Behavior behavior) {
  Scenario s = scenario_from_json(testing::example_scenario_json(), Config{});
  s.set_behavior(behavior);
  return s;
}

TEST(Idm, EquilibriumGapIsMinGapPlusHeadwayWithoutSpeedLimit) {
  IdmParameters p;
  p.desired_speed = std::numeric_limits<double>::infinity();
  for (double v : {2.0, 8.0, 15.0}) {
    const double gap = p.min_gap + v * p.time_headway;
    EXPECT_NEAR(idm_acceleration(p, v, gap, v), 0.0, 1e-12) << "v = " << v;
    EXPECT_LT(idm_acceleration(p, v, gap - 0.5, v), 0.0);
    EXPECT_GT(idm_acceleration(p, v, gap + 0.5, v), 0.0);
  }
}

TEST(Idm, ClosedLoopHoldsTheEquilibriumGapBehindTheEgo) {
  // The follower trails the ego (in the target lane, at constant speed) at
  // exactly s0 + vT with equal speeds; without a free-road term it must keep
  // that gap and speed for as long as we drive.
  Scenario s = two_lane_scene(Behavior::Idm);
  s.idm.desired_speed = 1e9;
  const double v = 8.0;
  const double gap = s.idm.min_gap + v * s.idm.time_headway;
  s.follower() = {0.0, v, 0.0};
  s.target() = {500.0, v, 0.0};
  TrafficModel model(s, Config{});
  EgoFootprint ego{s.follower().x + s.vehicle.length + gap, s.lane_width, v};
  for (int k = 0; k < 100; ++k) {
    model.step(0.1, ego);
    ego.x += v * 0.1;
    EXPECT_NEAR(model.car(car_of(Role::Follower)).a, 0.0, 1e-9);
  }
  EXPECT_NEAR(ego.x - model.car(car_of(Role::Follower)).x - s.vehicle.length, gap, 1e-9);
  EXPECT_NEAR(model.car(car_of(Role::Follower)).v, v, 1e-9);
}

TEST(Idm, EquilibriumWithFiniteDesiredSpeed) {
  const IdmParameters p;
  const double v = 6.0;
  const double gap =
      (p.min_gap + v * p.time_headway) / std::sqrt(1.0 - std::pow(v / p.desired_speed, p.exponent));
  EXPECT_NEAR(idm_acceleration(p, v, gap, v), 0.0, 1e-12);
}

TEST(Idm, PlatoonAtEquilibriumStaysThere) {
  Scenario s = two_lane_scene(Behavior::Idm);
  const double v = 7.0;
  const IdmParameters& p = s.idm;
  const double gap =
      (p.min_gap + v * p.time_headway) / std::sqrt(1.0 - std::pow(v / p.desired_speed, p.exponent));
  s.target().v = s.follower().v = v;
  s.target().x = s.follower().x + s.vehicle.length + gap;
  // The target has a free road, so it accelerates towards v0; predict only the
  // follower's first steps, where its gap and speed are still at equilibrium.
  TrafficModel model(s, Config{});
  model.step(0.1, {-1000.0, 0.0, 0.0});
  EXPECT_NEAR(model.car(car_of(Role::Follower)).a, 0.0, 1e-9);
}

TEST(Idm, FollowerReactsToTheEgoOnlyOnceItsBodyIsInTheLane) {
  Scenario s = two_lane_scene(Behavior::Idm);
  s.follower().x = -12.0;
  const EgoFootprint ego_in_own_lane{0.0, 0.0, 8.0};
  const EgoFootprint ego_across{0.0, s.lane_width / 2.0, 8.0};
  TrafficModel ignoring(s, Config{});
  TrafficModel reacting(s, Config{});
  ignoring.step(0.1, ego_in_own_lane);
  reacting.step(0.1, ego_across);
  EXPECT_LT(reacting.car(car_of(Role::Follower)).a, ignoring.car(car_of(Role::Follower)).a - 0.5);
  EXPECT_DOUBLE_EQ(reacting.car(car_of(Role::Target)).a, ignoring.car(car_of(Role::Target)).a);
  EXPECT_TRUE(body_in_lane(s.lane_width / 2.0 - 0.84, 1.7, s.lane_width, s.lane_width));
  EXPECT_FALSE(body_in_lane(s.lane_width / 2.0 - 0.86, 1.7, s.lane_width, s.lane_width));
}

TEST(Idm, ALongerCarAheadLeavesAShorterGapAndBrakesItsFollower) {
  Scenario s = two_lane_scene(Behavior::Idm);
  const Config config;
  const EgoFootprint far_away{-1000.0, 0.0, 0.0};
  TrafficModel cars(s, config);
  cars.step(0.1, far_away);
  s.cars[car_of(Role::Target)].size = VehicleSize{12.0, 2.5};
  TrafficModel behind_a_truck(s, config);
  behind_a_truck.step(0.1, far_away);
  EXPECT_LT(behind_a_truck.car(car_of(Role::Follower)).a, cars.car(car_of(Role::Follower)).a);
  EXPECT_DOUBLE_EQ(behind_a_truck.car(car_of(Role::Target)).a, cars.car(car_of(Role::Target)).a);
}

TEST(ConstantAccel, ClampsAtZeroWithExactPosition) {
  CarState car{0.0, 2.0, -1.0};
  advance_constant_accel(car, 5.0, 20.0);
  EXPECT_DOUBLE_EQ(car.v, 0.0);
  EXPECT_DOUBLE_EQ(car.x, 2.0);  // stops after 2 s, having covered v^2 / 2|a|
  advance_constant_accel(car, 1.0, 20.0);
  EXPECT_DOUBLE_EQ(car.x, 2.0);  // and never reverses
}

TEST(ConstantAccel, ClampsAtTheSpeedLimit) {
  CarState car{0.0, 15.0, 2.0};
  advance_constant_accel(car, 2.0, 16.0);
  EXPECT_DOUBLE_EQ(car.v, 16.0);
  // 0.5 s to reach 16 m/s (7.75 m), then 1.5 s at 16 m/s (24 m).
  EXPECT_NEAR(car.x, 7.75 + 24.0, 1e-12);
}

// Recorded highway traffic runs above the paper's 60 km/h: the prediction
// must keep a car's speed rather than cap it at a bound meant for the ego.
TEST(ConstantSpeed, AFastCarKeepsItsSpeedWhateverTheCap) {
  Scenario s = two_lane_scene(Behavior::ConstantSpeed);
  s.follower().v = 16.73;  // above the default cap of 60 km/h
  const Config config;
  ASSERT_TRUE(config.traffic_max_speed.has_value());
  ASSERT_GT(s.follower().v, *config.traffic_max_speed);
  const TrafficPrediction p = predict_traffic(s, config, 50, 0.1);
  EXPECT_DOUBLE_EQ(p.car(car_of(Role::Follower)).v.back(), 16.73);
  EXPECT_NEAR(p.car(car_of(Role::Follower)).x.back(), s.follower().x + 16.73 * 5.0, 1e-9);
}

TEST(ConstantAccel, ACarAboveTheCapIsNotSlowedAndNoCapMeansNone) {
  CarState above{0.0, 20.0, 1.0};
  advance_constant_accel(above, 1.0, 16.0);
  EXPECT_DOUBLE_EQ(above.v, 20.0);
  EXPECT_DOUBLE_EQ(above.x, 20.0);
  Scenario s = two_lane_scene(Behavior::ConstantAccel);
  s.target().v = 15.0;
  s.target().a = 2.0;
  Config uncapped;
  uncapped.traffic_max_speed.reset();
  const TrafficPrediction p = predict_traffic(s, uncapped, 50, 0.1);
  EXPECT_NEAR(p.car(car_of(Role::Target)).v.back(), 25.0, 1e-9);
  const TrafficPrediction capped = predict_traffic(s, Config{}, 50, 0.1);
  EXPECT_NEAR(capped.car(car_of(Role::Target)).v.back(), 60.0 / 3.6, 1e-9);
}

TEST(ConstantAccel, PredictionMatchesClosedForm) {
  Scenario s = two_lane_scene(Behavior::ConstantAccel);
  s.leader().a = 0.5;
  const Config config;
  const TrafficPrediction p = predict_traffic(s, config, 50, 0.1);
  ASSERT_EQ(p.nodes(), 51);
  const double t = 5.0;
  EXPECT_NEAR(p.car(car_of(Role::Leader)).x.back(), s.leader().x + s.leader().v * t + 0.25 * t * t,
              1e-9);
  EXPECT_NEAR(p.car(car_of(Role::Leader)).v.back(), s.leader().v + 0.5 * t, 1e-9);
}

TEST(ConstantSpeed, IgnoresAccelerationFields) {
  Scenario s = two_lane_scene(Behavior::ConstantSpeed);
  s.target().a = 2.0;
  const TrafficPrediction p = predict_traffic(s, Config{}, 10, 0.1);
  EXPECT_NEAR(p.car(car_of(Role::Target)).x.back(), s.target().x + s.target().v * 1.0, 1e-9);
  EXPECT_DOUBLE_EQ(p.car(car_of(Role::Target)).v.back(), s.target().v);
}

}  // namespace
}  // namespace lanechange
