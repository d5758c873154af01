// Every closed-loop planner in traffic of many cars: a 12-car scene rolls out
// consistently (the ego follows its controls, every car its behavior), and
// no planner runs into a car it can see.
#include <gtest/gtest.h>

#include "lanechange/baselines/baselines.hpp"
#include "lanechange/sim/simulator.hpp"
#include "rollout_checks.hpp"
#include "test_helpers.hpp"

namespace lanechange {
namespace {

class ManyCars : public ::testing::TestWithParam<const char*> {};

// Ten cars in the target lane, 16 m apart and as fast as the ego, a leader
// and a car behind in the ego lane: every gap is shorter than the 26 m the
// ego needs, so the rollouts test the loop and the traffic, not the change.
TEST_P(ManyCars, RollsOutATwelveCarSceneConsistently) {
  const Config config = testing::untimed_config();
  for (const Behavior behavior : {Behavior::ConstantSpeed, Behavior::Idm}) {
    const Scenario s = testing::dense_scenario(10, -80.0, 16.0, 9.0, behavior);
    ASSERT_EQ(s.car_count(), 12U);
    const auto planner = baselines::make_planner(GetParam(), config);
    const sim::Rollout r = sim::simulate(s, *planner, config);
    SCOPED_TRACE(std::string(GetParam()) + " " + std::string(to_string(behavior)));
    testing::expect_consistent(r, s);
    ASSERT_EQ(r.trajectory.others.car_count(), 12U);
    ASSERT_EQ(r.trajectory.cars.size(), 12U);
    EXPECT_EQ(r.trajectory.cars[2].id, "t0");
    EXPECT_FALSE(r.collision_at_fault) << r.reason;
  }
}

INSTANTIATE_TEST_SUITE_P(EveryPlanner, ManyCars,
                         ::testing::Values("miqp", "keep-lane", "mpc", "dwa", "lattice"));

// The expert re-plans every step over every gap: where only a gap far back
// is open it drops back to it, and the plan it took names its cars.
TEST(ManyCars, TheExpertChangesLanesIntoTheOnlyOpenGapOfADenseLane) {
  const Config config = testing::untimed_config();
  // Eight cars 16 m apart (Krauss's safe gap at 9 m/s), t0 to t2 30 m further back.
  nlohmann::json j = scenario_to_json(testing::dense_scenario(8, -56.0, 16.0));
  for (std::size_t i = 2; i < 5; ++i) j["cars"][i]["x"] = j["cars"][i]["x"].get<double>() - 30.0;
  j["cars"][1]["x"] = -45.0;  // the car behind leaves the ego room to drop back
  const Scenario s = scenario_from_json(j, config);
  const auto planner = baselines::make_planner("miqp", config);
  const sim::Rollout r = sim::simulate(s, *planner, config);
  testing::expect_consistent(r, s);
  EXPECT_EQ(r.outcome, sim::Outcome::WellPosed) << r.reason;
  EXPECT_FALSE(r.trajectory.collision);
  const EgoState& end = r.trajectory.ego.back();
  const auto& t2 = r.trajectory.others.car(*s.find("t2")).x.back();
  const auto& t3 = r.trajectory.others.car(*s.find("t3")).x.back();
  EXPECT_GT(end.x, t2);
  EXPECT_LT(end.x, t3);
  // The rollout names the gap it ended in, for the plots.
  EXPECT_EQ(r.trajectory.details["gap"]["behind"], "t2");
  EXPECT_EQ(r.trajectory.details["gap"]["ahead"], "t3");
}

}  // namespace
}  // namespace lanechange
