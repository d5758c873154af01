#include <gtest/gtest.h>

#include <nlohmann/json.hpp>

#include "baselines/lattice.hpp"
#include "baselines/sampling.hpp"
#include "lanechange/ego.hpp"
#include "lanechange/error.hpp"
#include "test_helpers.hpp"

namespace lanechange {
namespace {

using baselines::AxisState;
using baselines::Polynomial;

void expect_state(AxisState got, AxisState want) {
  EXPECT_NEAR(got.p, want.p, 1e-9);
  EXPECT_NEAR(got.v, want.v, 1e-9);
  EXPECT_NEAR(got.a, want.a, 1e-9);
}

TEST(Lattice, QuinticHitsItsBoundaryConditions) {
  const AxisState from{0.3, -0.2, 0.5};
  const AxisState to{3.75, 0.0, 0.0};
  const Polynomial d = Polynomial::quintic(from, to, 4.0);
  expect_state(d.at(0.0), from);
  expect_state(d.at(4.0), to);
  expect_state(d.at(6.0), to);  // held beyond its duration
}

TEST(Lattice, QuarticReachesItsSpeed) {
  const AxisState from{10.0, 8.0, -0.4};
  const Polynomial s = Polynomial::quartic(from, {0.0, 10.0, 0.0}, 3.0);
  expect_state(s.at(0.0), from);
  EXPECT_NEAR(s.at(3.0).v, 10.0, 1e-9);
  EXPECT_NEAR(s.at(3.0).a, 0.0, 1e-9);
  EXPECT_NEAR(s.at(5.0).p, s.at(3.0).p + 20.0, 1e-9);
}

TEST(Lattice, JerkIntegralMatchesQuadrature) {
  const Polynomial d = Polynomial::quintic({0.0, 0.4, 0.1}, {3.75, 0.0, 0.0}, 3.5);
  double sum = 0.0;
  constexpr int kPieces = 20000;
  const double h = 3.5 / kPieces;
  for (int i = 0; i < kPieces; ++i) sum += std::pow(d.jerk((i + 0.5) * h), 2) * h;
  EXPECT_NEAR(d.squared_jerk_integral(), sum, 1e-6 * sum);
  // The rest-to-rest quintic's known optimum: 720 h^2 / T^5.
  const Polynomial rest = Polynomial::quintic({}, {3.75, 0.0, 0.0}, 4.0);
  EXPECT_NEAR(rest.squared_jerk_integral(), 720.0 * 3.75 * 3.75 / std::pow(4.0, 5), 1e-9);
}

planner::Observation observe(const Scenario& s) {
  planner::Observation o;
  o.scene = &s;
  o.ego = s.ego;
  o.cars = {s.leader(), s.follower(), s.target()};
  return o;
}

TEST(Lattice, CandidatesStartAtTheEgoAndComeCheapestFirst) {
  const Config config;
  Scenario s = testing::open_road_scenario();
  s.ego.theta = 0.05;
  s.ego.a = 0.3;
  const planner::Observation o = observe(s);
  const auto cars = baselines::predict_from(o, config, 50);
  const auto candidates = baselines::lattice_candidates(o, 0.02, cars, config);
  ASSERT_FALSE(candidates.empty());
  for (std::size_t i = 1; i < candidates.size(); ++i) {
    EXPECT_LE(candidates[i - 1].cost, candidates[i].cost);
  }
  // Cheapest ends in the target lane, as the cost prefers.
  EXPECT_NEAR(candidates.front().lateral.at(10.0).p, s.lane_width, 1e-9);
  const auto path = baselines::candidate_path(candidates.front(), 50, config.dt());
  EXPECT_NEAR(path[0].x, s.ego.x, 1e-12);
  EXPECT_NEAR(path[0].y, s.ego.y, 1e-12);
  EXPECT_NEAR(path[0].v, s.ego.v, 1e-12);
  EXPECT_NEAR(path[0].theta, s.ego.theta, 1e-12);
  EXPECT_EQ(baselines::candidate_problem(path, cars, s, config.lattice), "");
  // The first control takes the unicycle to the path's next node.
  EgoState next = s.ego;
  const EgoControl u = baselines::first_control(path, config.dt());
  next = step_trapezoidal(next, u, config.dt());
  EXPECT_NEAR(next.v, path[1].v, 1e-12);
  EXPECT_NEAR(next.theta, path[1].theta, 1e-12);
  EXPECT_NEAR(next.y, path[1].y, 2e-3);
  EXPECT_NEAR(next.x, path[1].x, 2e-3);
}

TEST(Lattice, ACandidateIntoACarIsInvalid) {
  const Config config;
  const Scenario s = testing::no_gap_scenario();
  const planner::Observation o = observe(s);
  const auto cars = baselines::predict_from(o, config, 50);
  const auto candidates = baselines::lattice_candidates(o, 0.0, cars, config);
  int into_target_lane = 0;
  for (const auto& c : candidates) {
    if (c.lateral.at(10.0).p < s.lane_width / 2) continue;
    ++into_target_lane;
    const auto path = baselines::candidate_path(c, 50, config.dt());
    EXPECT_NE(baselines::candidate_problem(path, cars, s, config.lattice), "");
  }
  EXPECT_GT(into_target_lane, 0);
}

// Either side of each target-lane car will do, at its Eq. 1 distance.
TEST(SafeDistances, HoldOnEitherSideOfEachCar) {
  Scenario s = testing::open_road_scenario();
  s.target() = {-30.0, 8.0, 0.0};  // far behind the ego, in the target lane
  s.follower() = {-60.0, 8.0, 0.0};
  const Config config;
  const auto cars = baselines::predict_from(observe(s), config, 10);
  // The ego already in the target lane, holding its speed: far ahead of both.
  std::vector<EgoState> path;
  for (int k = 0; k <= 10; ++k) path.push_back({8.0 * 0.1 * k, s.lane_width, 8.0, 0.0, 0.0});
  EXPECT_TRUE(baselines::keeps_target_lane_distances(path, cars, s));
  // Between the two, at their safe distances.
  s.target() = {40.0, 8.0, 0.0};
  const auto between = baselines::predict_from(observe(s), config, 10);
  EXPECT_TRUE(baselines::keeps_target_lane_distances(path, between, s));
  // Ahead of the target by less than 8.4 m + 0.5 s x its speed.
  s.target() = {-8.0, 8.0, 0.0};
  const auto close_behind = baselines::predict_from(observe(s), config, 10);
  EXPECT_FALSE(baselines::keeps_target_lane_distances(path, close_behind, s));
}

TEST(Lattice, BadSettingsAreInputErrors) {
  for (const char* bad :
       {R"({"lattice": {"min_duration": 0}})", R"({"lattice": {"max_duration": 1}})",
        R"({"lattice": {"speed_samples": 0}})", R"({"lattice": {"max_heading": 2}})"}) {
    EXPECT_THROW((void)config_from_json(nlohmann::json::parse(bad)), InputError) << bad;
  }
}

}  // namespace
}  // namespace lanechange
