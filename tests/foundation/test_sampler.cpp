#include <gtest/gtest.h>

#include <algorithm>
#include <nlohmann/json.hpp>

#include "lanechange/error.hpp"
#include "lanechange/sampler.hpp"
#include "test_helpers.hpp"

namespace lanechange {
namespace {

TEST(Sampler, SameSeedGivesTheSameScenarios) {
  const ScenarioSampler a(Config{}, 42);
  const ScenarioSampler b(Config{}, 42);
  for (std::uint64_t i = 0; i < 50; ++i) {
    EXPECT_EQ(scenario_to_json(a.sample(i)), scenario_to_json(b.sample(i))) << "index " << i;
  }
}

TEST(Sampler, ScenarioDoesNotDependOnDrawOrder) {
  const ScenarioSampler sampler(Config{}, 7);
  const auto late_first = scenario_to_json(sampler.sample(31));
  for (std::uint64_t i = 0; i < 31; ++i) (void)sampler.sample(i);
  EXPECT_EQ(scenario_to_json(sampler.sample(31)), late_first);
}

TEST(Sampler, DifferentSeedsDiffer) {
  const ScenarioSampler a(Config{}, 1);
  const ScenarioSampler b(Config{}, 2);
  EXPECT_NE(scenario_to_json(a.sample(0)), scenario_to_json(b.sample(0)));
  EXPECT_NE(scenario_to_json(a.sample(0)), scenario_to_json(a.sample(1)));
}

TEST(Sampler, FollowsTheDocumentedDistribution) {
  const Config config;
  const ScenarioSampler sampler(config, 3);
  int by_behavior[3] = {0, 0, 0};
  for (std::uint64_t i = 0; i < 600; ++i) {
    const Scenario s = sampler.sample(i);
    ++by_behavior[static_cast<int>(s.behavior)];
    EXPECT_TRUE(config.sampler.leader_speed.contains(s.leader().v));
    EXPECT_TRUE(config.sampler.follower_speed.contains(s.follower().v));
    EXPECT_GE((s.leader().x - s.ego.x) / s.ego.v, 3.0 - 1e-9)
        << "three-second rule broken at " << i;
    EXPECT_GT(s.target().x - s.follower().x, s.vehicle.length);
    if (s.behavior != Behavior::ConstantAccel) {
      EXPECT_EQ(s.leader().a, 0.0);
    }
    EXPECT_NO_THROW(validate_scenario(s));
  }
  for (int count : by_behavior) EXPECT_GT(count, 150);
}

TEST(Sampler, FixedBehaviorKeepsTheCars) {
  const ScenarioSampler sampler(Config{}, 9);
  const Scenario idm = sampler.sample(4, Behavior::Idm);
  const Scenario cs = sampler.sample(4, Behavior::ConstantSpeed);
  EXPECT_EQ(idm.behavior, Behavior::Idm);
  EXPECT_DOUBLE_EQ(idm.target().x, cs.target().x);
  EXPECT_DOUBLE_EQ(idm.ego.v, cs.ego.v);
}

// sampler.target_lane_cars: a leader and a car behind in the ego lane, and
// every count of the range in the target lane, back to front.
TEST(Sampler, DenseTrafficDrawsEveryCountOfTheRange) {
  Config config;
  config.sampler.target_lane_cars = {4.0, 10.0};
  const ScenarioSampler sampler(config, 11);
  int fewest = 100;
  int most = 0;
  for (std::uint64_t i = 0; i < 300; ++i) {
    const Scenario s = sampler.sample(i);
    ASSERT_GE(s.car_count(), 2U);
    const int in_target_lane = static_cast<int>(s.car_count()) - 2;
    fewest = std::min(fewest, in_target_lane);
    most = std::max(most, in_target_lane);
    EXPECT_EQ(s.cars[0].lane, Lane::Ego);
    EXPECT_GT(s.cars[0].state.x, s.ego.x);
    EXPECT_LT(s.cars[1].state.x, s.ego.x);
    for (std::size_t c = 0; c < s.car_count(); ++c) {
      EXPECT_EQ(s.cars[c].behavior, s.behavior);
      if (c > 2) {
        EXPECT_GE(s.car(c).x - s.car(c - 1).x, s.vehicle.length + config.sampler.gap_length.lo);
      }
    }
    EXPECT_EQ(s.roles[0], nearest_in_role(s, Role::Leader));
    EXPECT_EQ(s.roles[1], nearest_in_role(s, Role::Follower));
    EXPECT_EQ(s.roles[2], nearest_in_role(s, Role::Target));
    EXPECT_NO_THROW(validate_scenario(s));
  }
  EXPECT_EQ(fewest, 4);
  EXPECT_EQ(most, 10);
  // The same index gives the same scene, and the default still the paper's.
  EXPECT_EQ(scenario_to_json(sampler.sample(7)), scenario_to_json(sampler.sample(7)));
  EXPECT_EQ(ScenarioSampler(Config{}, 11).sample(7).car_count(), 3U);
}

// No platoon car starts so close behind a slower one that braking at
// traffic.max_decel (less the car ahead's own braking) cannot stop it closing
// in: scene 786 of seed 2026 started a car 1 m behind one 5.5 m/s slower.
TEST(Sampler, APlatoonCarCanAlwaysStillStopClosingInOnTheCarAhead) {
  Config config;
  config.sampler.target_lane_cars = {4.0, 10.0};
  const ScenarioSampler sampler(config, 2026);
  for (std::uint64_t i = 0; i < 1500; ++i) {
    const Scenario s = sampler.sample(i);
    const double own_braking =
        s.behavior == Behavior::ConstantAccel ? -config.sampler.accel.lo : 0.0;
    const double brake = *config.traffic.max_decel - own_braking;
    const double dt = s.horizon / s.steps;
    for (std::size_t c = 3; c < s.car_count(); ++c) {
      const double gap = s.car(c).x - s.car(c - 1).x - s.vehicle.length;
      const double closing = s.car(c - 1).v - s.car(c).v;
      if (closing <= 0.0) continue;
      EXPECT_LE(closing * dt + closing * closing / (2.0 * brake), gap + 1e-9)
          << "scene " << i << ", cars " << c - 1 << " and " << c;
    }
  }
}

TEST(Sampler, ACountRangeMustBeWholeNumbers) {
  Config config;
  config.sampler.target_lane_cars = {2.5, 4.0};
  try {
    config.validate();
    FAIL() << "accepted a fractional count";
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "sampler.target_lane_cars");
  }
}

// The commands that draw scenes take the density as an option: sample writes
// scenes with that many cars in the target lane, and a bad count exits 2
// naming the option.
TEST(SamplerCli, TargetLaneCarsDrawsDenseScenesAndRefusesBadCounts) {
  testing::TempDir dir;
  const auto r = testing::run_cli("sample --count 3 --seed 4 --target-lane-cars 5,6 --out " +
                                  dir.file("dense"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  for (const char* name :
       {"scenario_000000.json", "scenario_000001.json", "scenario_000002.json"}) {
    const auto scene = nlohmann::json::parse(testing::read_text(dir.file("dense/") + name));
    int target_lane = 0;
    for (const auto& car : scene["cars"]) target_lane += car["lane"] == "target" ? 1 : 0;
    EXPECT_GE(target_lane, 5) << name;
    EXPECT_LE(target_lane, 6) << name;
  }
  for (const char* bad : {"3,x", "2.5", "7,4", "-1"}) {
    const auto refused =
        testing::run_cli(std::string("sample --count 1 --seed 4 --target-lane-cars=") + bad +
                         " --out " + dir.file("bad"));
    EXPECT_EQ(refused.exit_code, 2) << bad << ": " << refused.output;
    EXPECT_NE(refused.output.find("--target-lane-cars"), std::string::npos) << refused.output;
  }
}

}  // namespace
}  // namespace lanechange
