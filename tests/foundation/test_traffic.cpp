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
  Config config;
  config.traffic = paper_traffic();  // it would catch up with the target and follow it
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

// A fast constant-speed car 20 m behind a slow one: the paper's traffic
// drives it through; with followers reacting it follows at a gap, and the
// prediction keeps the same model.
TEST(Followers, ACarNeverDrivesThroughTheCarAheadOfIt) {
  Scenario s = two_lane_scene(Behavior::ConstantSpeed);
  s.follower() = {0.0, 16.0, 0.0};
  s.target() = {20.0, 8.0, 0.0};
  s.ego.x = -40.0;
  const double reach = s.vehicle.length;  // both cars have the default body
  auto least_gap = [&](const Config& config) {
    const TrafficPrediction p = predict_traffic(s, config, 150, 0.1);
    double least = 1e9;
    const CarTrack& f = p.car(car_of(Role::Follower));
    const CarTrack& t = p.car(car_of(Role::Target));
    for (std::size_t k = 0; k < f.x.size(); ++k) least = std::min(least, t.x[k] - f.x[k] - reach);
    return std::pair{least, f.v.back()};
  };
  const auto [reacting_gap, reacting_speed] = least_gap(Config{});
  EXPECT_GT(reacting_gap, 1.0);
  EXPECT_NEAR(reacting_speed, 8.0, 0.5);  // it follows the target
  Config paper;
  paper.traffic = paper_traffic();
  EXPECT_LT(least_gap(paper).first, -20.0);  // the ghost
}

// An ego settled in a lane ahead of a faster constant-speed car: the car
// brakes for it (the ego set its step), and never runs into it.
TEST(Followers, AConstantSpeedCarBrakesForTheEgoAheadInItsLane) {
  Scenario s = two_lane_scene(Behavior::ConstantSpeed);
  s.follower() = {-30.0, 12.0, 0.0};
  s.target() = {80.0, 12.0, 0.0};
  s.ego = {0.0, s.lane_width, 8.0, 0.0, 0.0};
  TrafficModel traffic(s, Config{});
  bool braked_for_the_ego = false;
  for (int k = 0; k < 100; ++k) {
    const double ego_x = 8.0 * 0.1 * k;
    traffic.step(0.1, {ego_x, s.lane_width, 8.0});
    const CarState& f = traffic.car(car_of(Role::Follower));
    ASSERT_LT(f.x + s.vehicle.length, ego_x + 0.8) << k;  // behind the ego after its step
    braked_for_the_ego =
        braked_for_the_ego || (f.a < 0.0 && traffic.followed_ego(car_of(Role::Follower)));
  }
  EXPECT_TRUE(braked_for_the_ego);
  EXPECT_FALSE(traffic.followed_ego(car_of(Role::Target)));
}

// A constant-acceleration car that brakes to follow the car ahead is
// observed with its own acceleration, so that a prediction from what a
// planner observes moves it as the world does. With the braking step's
// acceleration, the prediction would brake it on to a stop.
TEST(Followers, APredictionFromTheObservedCarsMovesThemAsTheWorldDoes) {
  Scenario s = two_lane_scene(Behavior::ConstantAccel);
  const CarIndex follower = car_of(Role::Follower);
  s.follower() = {0.0, 14.0, 0.5};
  s.target() = {25.0, 9.0, 0.3};
  s.ego = {-60.0, 0.0, 10.0, 0.0, 0.0};
  const Config config;
  const double dt = 0.1;
  const auto ego_at = [&](int k) {
    return EgoFootprint{s.ego.x + s.ego.v * k * dt, s.ego.y, s.ego.v};
  };
  TrafficModel world(s, config);
  int k = 0;
  for (; k < 50 && world.car(follower).a >= 0.0; ++k) world.step(dt, ego_at(k));
  ASSERT_LT(world.car(follower).a, 0.0);  // it follows the target
  EXPECT_DOUBLE_EQ(world.observed(follower).a, 0.5);
  Scenario now = s;
  now.ego.x = ego_at(k).x;
  for (CarIndex c = 0; c < now.car_count(); ++c) now.cars[c].state = world.observed(c);
  const int steps = 40;
  const TrafficPrediction predicted = predict_traffic(now, config, steps, dt);
  for (int j = 1; j <= steps; ++j) {
    world.step(dt, ego_at(k + j - 1));
    ASSERT_NEAR(predicted.car(follower).x[j], world.car(follower).x, 1e-9) << j;
  }
}

// IDM asks for any braking a cut-in 2 m ahead calls for; the car brakes at
// most traffic.max_decel.
TEST(Followers, NoCarBrakesHarderThanItsPhysicalLimit) {
  Scenario s = two_lane_scene(Behavior::Idm);
  s.follower() = {-6.4, 11.3, 0.0};
  s.target() = {80.0, 11.3, 0.0};
  s.ego = {0.0, s.lane_width, 5.0, 0.0, 0.0};  // 2 m ahead of the follower's bumper
  const Config config;
  ASSERT_TRUE(config.traffic.max_decel.has_value());
  TrafficModel limited(s, config);
  limited.step(0.1, {s.ego.x, s.ego.y, s.ego.v});
  EXPECT_DOUBLE_EQ(limited.car(car_of(Role::Follower)).a, -*config.traffic.max_decel);
  EXPECT_TRUE(limited.followed_ego(car_of(Role::Follower)));
  Config unlimited;
  unlimited.traffic = paper_traffic();
  TrafficModel paper(s, unlimited);
  paper.step(0.1, {s.ego.x, s.ego.y, s.ego.v});
  EXPECT_LT(paper.car(car_of(Role::Follower)).a, -30.0);
}

// A lane of IDM cars of several lengths, listed out of their order on the
// road: each follows the car whose rear bumper is nearest ahead of it.
TEST(Followers, EachCarFollowsTheNearestCarAheadWhateverTheSceneOrder) {
  Scenario s = two_lane_scene(Behavior::Idm);
  s.cars.clear();
  const double xs[] = {40.0, -25.0, 95.0, 0.0, 61.0, 18.0, -60.0, 130.0};
  const double lengths[] = {4.5, 12.0, 5.0, 4.0, 16.5, 4.5, 5.0, 4.5};
  for (int i = 0; i < 8; ++i) {
    std::string id = "c";
    id += std::to_string(i);
    OtherCar car{id,
                 Lane::Target,
                 {xs[i], 8.0 + 0.5 * i, 0.0},
                 Behavior::Idm,
                 VehicleSize{lengths[i], 1.8},
                 std::nullopt};
    s.cars.push_back(car);
  }
  s.ego = {-200.0, 0.0, 10.0, 0.0, 0.0};  // in the other lane, behind them all
  const Config config;
  TrafficModel traffic(s, config);
  traffic.step(0.1, {s.ego.x, s.ego.y, s.ego.v});
  for (int i = 0; i < 8; ++i) {
    double gap = std::numeric_limits<double>::infinity();
    double leader_speed = 0.0;
    for (int j = 0; j < 8; ++j) {
      const double g = xs[j] - xs[i] - 0.5 * (lengths[i] + lengths[j]);
      if (xs[j] > xs[i] && g < gap) {
        gap = g;
        leader_speed = 8.0 + 0.5 * j;
      }
    }
    const double expected =
        std::max(idm_acceleration(s.idm, 8.0 + 0.5 * i, gap, leader_speed), -9.0);
    EXPECT_NEAR(traffic.car(static_cast<CarIndex>(i)).a, expected, 1e-12) << i;
  }
}

// An ego whose body has just crossed the line: a car that watches the line
// follows it; one that reacts to bodies in its path (SUMO's sublane model)
// only once the ego overlaps its own width.
TEST(Followers, WhenACarSeesTheEgoDependsOnTheSetting) {
  Scenario s = two_lane_scene(Behavior::ConstantSpeed);
  s.follower() = {0.0, 14.0, 0.0};
  s.target() = {200.0, 14.0, 0.0};
  const double car_width = s.size_of(car_of(Role::Follower)).width;
  const double crossed = 0.5 * s.lane_width - 0.5 * s.vehicle.width + 0.2;  // 0.2 m over the line
  const double overlapping = s.lane_width - 0.5 * (s.vehicle.width + car_width) + 0.2;
  auto follows_ego_at = [&](double y, SeesEgo sees) {
    Config config;
    config.traffic.sees_ego = sees;
    TrafficModel traffic(s, config);
    traffic.step(0.1, {14.0, y, 8.0});  // 14 m ahead of its centre, slower: it must brake
    return traffic.followed_ego(car_of(Role::Follower));
  };
  EXPECT_TRUE(follows_ego_at(crossed, SeesEgo::InLane));
  EXPECT_FALSE(follows_ego_at(crossed, SeesEgo::Overlapping));
  EXPECT_TRUE(follows_ego_at(overlapping, SeesEgo::Overlapping));
  EXPECT_FALSE(follows_ego_at(crossed - 0.4, SeesEgo::InLane));
}

TEST(Followers, KraussSafeSpeedStopsBehindAStoppedCar) {
  // At the gap a car needs to stop from v at b after tau, its safe speed is v.
  const double v = 10.0, tau = 1.0, b = 4.5;
  const double gap = v * tau + v * v / (2.0 * b);
  EXPECT_NEAR(krauss_safe_speed(gap, v, 0.0, tau, b), v, 1e-9);
  EXPECT_LT(krauss_safe_speed(gap - 1.0, v, 0.0, tau, b), v);
  // Behind a car at its own speed, the safe gap is v tau.
  EXPECT_NEAR(krauss_safe_speed(v * tau, v, v, tau, b), v, 1e-9);
}

// At the gap gap_braking_at_most gives, the model brakes the car behind the
// ego by just the deceleration asked; a metre closer, harder.
TEST(Followers, TheCutInGapIsWhereTheCarBrakesByTheGivenDeceleration) {
  Config config;
  const double decel = 3.5, dt = 0.1;
  for (const auto& [behavior, min_gap] :
       {std::pair{Behavior::ConstantSpeed, 0.0}, std::pair{Behavior::ConstantSpeed, 2.5},
        std::pair{Behavior::Idm, 0.0}}) {
    config.traffic.min_gap = min_gap;
    for (const auto& speeds : {std::pair{12.0, 8.0}, std::pair{9.0, 9.0}, std::pair{10.0, 4.0}}) {
      // Plain variables, not a structured binding: the lambda below captures them.
      const double car_v = speeds.first;
      const double ego_v = speeds.second;
      std::string trace(to_string(behavior));
      trace += " at " + std::to_string(car_v);
      trace += ", min gap " + std::to_string(min_gap);
      SCOPED_TRACE(trace);
      Scenario s = two_lane_scene(behavior);
      s.target() = {200.0, car_v, 0.0};
      const auto line =
          gap_braking_at_most(decel, behavior, car_v, ego_v, dt, s.idm, config.traffic);
      ASSERT_TRUE(line.has_value());
      ASSERT_GT(line->gap, 0.0);
      auto braking_at = [&](double gap) {
        s.follower() = {0.0, car_v, 0.0};
        s.ego = {gap + s.vehicle.length, s.lane_width, ego_v, 0.0, 0.0};
        TrafficModel traffic(s, config);
        traffic.step(dt, {s.ego.x, s.ego.y, s.ego.v});
        return -traffic.car(car_of(Role::Follower)).a;
      };
      EXPECT_NEAR(braking_at(line->gap), decel, 1e-6);
      EXPECT_GT(braking_at(line->gap - 1.0), decel);
      // The line asks at least the gap taken at any other ego speed.
      for (const double other : {ego_v - 2.0, ego_v + 2.0}) {
        const auto there =
            gap_braking_at_most(decel, behavior, car_v, other, dt, s.idm, config.traffic);
        EXPECT_GE(line->at(other, ego_v), there->gap - 1e-9) << other;
      }
    }
  }
  Config paper;
  paper.traffic = paper_traffic();
  EXPECT_FALSE(gap_braking_at_most(decel, Behavior::ConstantSpeed, 12.0, 8.0, dt, IdmParameters{},
                                   paper.traffic));
}

}  // namespace
}  // namespace lanechange
