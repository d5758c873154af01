// The sampling baselines in the loop: a lane change into a wide-open gap,
// staying in lane without a gap, and the consistency check of every rollout.
#include <gtest/gtest.h>

#include "lanechange/baselines/baselines.hpp"
#include "lanechange/sampler.hpp"
#include "lanechange/sim/simulator.hpp"
#include "rollout_checks.hpp"
#include "test_helpers.hpp"

namespace lanechange {
namespace {

using sim::Outcome;

class SamplingBaseline : public ::testing::TestWithParam<const char*> {};

TEST_P(SamplingBaseline, ChangesLanesIntoAWideOpenGap) {
  const Config config = testing::untimed_config();
  const Scenario s = testing::open_road_scenario();
  const auto p = baselines::make_planner(GetParam(), config);
  const sim::Rollout r = sim::simulate(s, *p, config);
  testing::expect_consistent(r, s);
  EXPECT_EQ(r.outcome, Outcome::WellPosed) << r.reason;
  EXPECT_FALSE(r.trajectory.collision);
  EXPECT_GT(r.manoeuvre_over_at, 0.0);
}

// The target lane packed around the ego, and the ego held to within 0.5 m/s
// of the cars' speed: no gap comes within reach (braking behind the follower,
// a gap a planner may rightly take, is ruled out).
Scenario walled_in_scenario() {
  Scenario s = testing::no_gap_scenario();
  s.limits.v = {7.5, 8.5};
  return s;
}

TEST_P(SamplingBaseline, StaysInItsLaneWithoutAGap) {
  const Config config = testing::untimed_config();
  const Scenario s = walled_in_scenario();
  const auto p = baselines::make_planner(GetParam(), config);
  const sim::Rollout r = sim::simulate(s, *p, config);
  testing::expect_consistent(r, s);
  EXPECT_EQ(r.outcome, Outcome::Aborted) << r.reason;
  EXPECT_FALSE(r.trajectory.collision);
}

TEST_P(SamplingBaseline, NeverHitsTheCarsBesideIt) {
  // Without the speed bounds the ego may brake behind the follower and
  // change there, or wait; either way without collision.
  const Config config = testing::untimed_config();
  const Scenario s = testing::no_gap_scenario();
  const sim::Rollout r = sim::simulate(s, *baselines::make_planner(GetParam(), config), config);
  testing::expect_consistent(r, s);
  EXPECT_FALSE(r.trajectory.collision);
  EXPECT_NE(r.outcome, Outcome::Failure) << r.reason;
}

TEST_P(SamplingBaseline, SampledRolloutsAreConsistent) {
  const Config config = testing::untimed_config();
  const ScenarioSampler sampler(config, 5);
  const auto p = baselines::make_planner(GetParam(), config);
  for (std::uint64_t i = 0; i < 4; ++i) {
    const Scenario s = sampler.sample(i);
    SCOPED_TRACE("scenario " + std::to_string(i));
    testing::expect_consistent(sim::simulate(s, *p, config), s);
  }
}

INSTANTIATE_TEST_SUITE_P(Baselines, SamplingBaseline, ::testing::Values("dwa", "lattice"));

}  // namespace
}  // namespace lanechange
