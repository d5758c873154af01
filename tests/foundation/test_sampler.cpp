#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "lanechange/sampler.hpp"

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

}  // namespace
}  // namespace lanechange
