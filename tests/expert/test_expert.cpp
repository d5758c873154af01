// The expert: formulation, structured QP, fast solver against the reference,
// and whole plans checked by the independent audit.
#include <gtest/gtest.h>

#include <cmath>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>

#include "../foundation/test_helpers.hpp"
#include "lanechange/audit.hpp"
#include "lanechange/expert/crosscheck.hpp"
#include "lanechange/expert/planner.hpp"
#include "lanechange/sampler.hpp"

namespace lanechange::expert {
namespace {

Scenario open_road_scenario(Behavior behavior = Behavior::ConstantSpeed) {
  Scenario s = default_scenario(Config{});
  s.behavior = behavior;
  s.ego = {0.0, 0.0, 8.0, 0.0, 0.0};
  s.leader = {40.0, 8.0, 0.0};
  s.follower = {-60.0, 8.0, 0.0};
  s.target = {70.0, 8.0, 0.0};
  validate_scenario(s);
  return s;
}

// The target lane packed bumper to bumper around the ego: no gap at all.
Scenario no_gap_scenario() {
  Scenario s = open_road_scenario();
  s.follower = {-2.0, 8.0, 0.0};
  s.target = {3.0, 8.0, 0.0};
  validate_scenario(s);
  return s;
}

TEST(Formulation, LinearizedStepIsExactAtItsOwnPoint) {
  // A path of the nonlinear model, linearized about itself, satisfies the
  // linearized dynamics exactly: the trapezoid of the linearization agrees
  // with the trapezoid of the model at the linearization point.
  const Scenario s = open_road_scenario();
  Iterate path;
  EgoState z = s.ego;
  for (int k = 0; k <= s.steps; ++k) {
    path.states.emplace_back(z.x, z.y, z.v, z.theta);
    const Control u(0.3 * std::sin(0.1 * k), 0.05 * std::cos(0.2 * k));
    if (k < s.steps) {
      path.controls.push_back(u);
      z = step_trapezoidal(z, {u[kA], u[kOmega]}, s.horizon / s.steps);
    }
  }
  const auto prediction = predict_traffic(s, Config{}, s.steps, 0.1);
  const LaneChangeQp qp = build_lane_change_qp(s, Config{}, path, prediction);
  for (int k = 0; k < s.steps; ++k) {
    const StageDynamics& d = qp.dynamics[k];
    const State next = d.A * path.states[k] + d.B * path.controls[k] + d.c;
    EXPECT_LT((next - path.states[k + 1]).cwiseAbs().maxCoeff(), 1e-12) << "step " << k;
  }
}

TEST(Formulation, MiqpFormHasTheSameObjective) {
  for (const LaneRule rule : {LaneRule::EitherOr, LaneRule::Footprint}) {
    Config config;
    config.expert.lane_rule = rule;
    const Scenario s = ScenarioSampler(config, 4).sample(0);
    const LaneChangeQp qp = first_round_problem(s, config);
    MiqpLayout layout;
    const MiqpProblem miqp = to_miqp(qp, 1000.0, layout);
    ASSERT_TRUE(miqp.check().empty()) << miqp.check();
    Eigen::VectorXd x = Eigen::VectorXd::Zero(miqp.num_variables());
    for (int i = 0; i < x.size(); ++i) x[i] = std::sin(1.0 + i);
    const Iterate path = iterate_from_miqp(x, layout);
    EXPECT_NEAR(miqp.objective(x), qp.objective(path), 1e-9 * std::abs(qp.objective(path)));
    // A binary per mode and node, node 0 excluded: two modes under the
    // either-or rule, three (ego lane, both, target lane) under footprint.
    const int modes = rule == LaneRule::EitherOr ? 2 : 3;
    EXPECT_EQ(miqp.num_binaries(), modes * s.steps);
  }
}

TEST(Formulation, WarmStartMeetsItsBoundaryConditions) {
  const Scenario s = open_road_scenario();
  const auto prediction = predict_traffic(s, Config{}, s.steps, 0.1);
  const Iterate w = warm_start(s, Config{}, prediction);
  ASSERT_EQ(static_cast<int>(w.states.size()), s.steps + 1);
  EXPECT_NEAR(w.states.front()[kY], 0.0, 1e-12);
  EXPECT_NEAR(w.states.back()[kY], s.lane_width, 1e-9);
  EXPECT_NEAR(w.states.front()[kV], s.ego.v, 1e-9);
  // Aimed behind the target by its safe distance, at the target's speed.
  const SafeDistance& d = s.safe_distance.target;
  EXPECT_NEAR(w.states.back()[kX],
              prediction.car(Car::Target).x.back() - d.standstill - d.time_headway * s.target.v,
              1e-6);
}

// The fast solver and Bonmin on the same first-round MIQPs, small enough for
// the reference to take seconds: N = 10 with the either-or rule (20
// binaries), N = 6 with the footprint rule (18 binaries; Bonmin's B-BB needs
// minutes for its 30 at N = 10). The full cross-check is `lanechange
// crosscheck`; docs/expert_results.md has its results.
class CrossCheck : public ::testing::TestWithParam<std::tuple<LaneRule, int>> {};

TEST_P(CrossCheck, FastSolverMatchesTheReference) {
  const auto [rule, index] = GetParam();
  Config config;
  config.expert.steps = rule == LaneRule::EitherOr ? 10 : 6;
  config.expert.lane_rule = rule;
  const Scenario s = ScenarioSampler(config, 17).sample(static_cast<std::uint64_t>(index));
  const LaneChangeQp qp = first_round_problem(s, config);
  const CrossCheckCase c =
      cross_check(qp, FastLaneChangeSolver{}, ReferenceLaneChangeSolver{}, {}, 1e-6);
  EXPECT_TRUE(c.agree) << "fast " << to_string(c.fast_status) << " " << c.fast_objective
                       << ", reference " << to_string(c.reference_status) << " "
                       << c.reference_objective;
}

TEST(CrossCheckReplayCli, CatchesAWrongStoredOptimumAndRejectsBadLines) {
  testing::TempDir dir;
  const std::string first = dir.file("first.jsonl");
  ASSERT_EQ(testing::run_cli("crosscheck --count 2 --seed 17 --steps 6 --out " + first).exit_code,
            0);
  EXPECT_EQ(testing::run_cli("crosscheck --replay " + first).exit_code, 0);
  // Shift every stored optimum by 1%: the replay must now disagree.
  std::ifstream in(first);
  std::ofstream tampered(dir.file("tampered.jsonl"));
  for (std::string line; std::getline(in, line);) {
    auto row = nlohmann::json::parse(line);
    if (row["reference_objective"].is_number()) {
      row["reference_objective"] = row["reference_objective"].get<double>() * 1.01 + 0.01;
    } else {
      row["reference_status"] = "Optimal";
      row["reference_objective"] = 1.0;
    }
    tampered << row.dump() << "\n";
  }
  tampered.close();
  const auto r = testing::run_cli("crosscheck --replay " + dir.file("tampered.jsonl"));
  EXPECT_NE(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("0 of 2 agree"), std::string::npos) << r.output;
  // A case must carry the config it was made with, and the reference's verdict.
  testing::write_text(dir.file("bad.jsonl"), "{\"index\": 1}\n");
  const auto bad = testing::run_cli("crosscheck --replay " + dir.file("bad.jsonl"));
  EXPECT_EQ(bad.exit_code, 2) << bad.output;
  EXPECT_NE(bad.output.find("config"), std::string::npos) << bad.output;
  testing::write_text(dir.file("bad2.jsonl"), "{\"index\": 1, \"config\": {}}\n");
  const auto bad2 = testing::run_cli("crosscheck --replay " + dir.file("bad2.jsonl"));
  EXPECT_EQ(bad2.exit_code, 2) << bad2.output;
  EXPECT_NE(bad2.output.find("reference_status"), std::string::npos) << bad2.output;
}

// A stored case is replayed under its own config: a --config that changes
// the lane rule does not change what the case checks.
TEST(CrossCheckReplayCli, UsesTheConfigStoredWithEachCase) {
  testing::TempDir dir;
  const std::string cases = dir.file("cases.jsonl");
  testing::write_text(dir.file("either_or.json"), R"({"expert": {"lane_rule": "either_or"}})");
  ASSERT_EQ(testing::run_cli("--config " + dir.file("either_or.json") +
                             " crosscheck --count 2 --seed 3 --steps 6 --out " + cases)
                .exit_code,
            0);
  std::ifstream in(cases);
  std::string line;
  ASSERT_TRUE(std::getline(in, line));
  EXPECT_EQ(nlohmann::json::parse(line)["config"]["expert"]["lane_rule"], "either_or");
  EXPECT_EQ(testing::run_cli("crosscheck --replay " + cases).exit_code, 0);
}

INSTANTIATE_TEST_SUITE_P(SampledScenarios, CrossCheck,
                         ::testing::Combine(::testing::Values(LaneRule::EitherOr,
                                                              LaneRule::Footprint),
                                            ::testing::Range(0, 4)),
                         [](const auto& info) {
                           return std::string(std::get<0>(info.param) == LaneRule::EitherOr
                                                  ? "either_or_"
                                                  : "footprint_") +
                                  std::to_string(std::get<1>(info.param));
                         });

TEST(FastSolver, ReportsAnInitialStateThatBreaksTheRules) {
  Scenario s = open_road_scenario();
  s.leader.x = 6.0;  // closer than the safe distance, though not touching
  Config config;
  config.expert.constrain_initial_node = true;
  const LaneChangeQp qp = first_round_problem(s, config);
  EXPECT_EQ(FastLaneChangeSolver{}.solve(qp, {}).status, MiqpStatus::Infeasible);
}

void expect_audit_passes(const Trajectory& t, const Scenario& s, const Config& c) {
  for (const std::string& problem : audit_trajectory(t, s, c)) ADD_FAILURE() << problem;
}

TEST(Planner, WideOpenGapIsWellPosed) {
  for (Behavior b : {Behavior::ConstantSpeed, Behavior::ConstantAccel, Behavior::Idm}) {
    const Scenario s = open_road_scenario(b);
    const ExpertPlanner planner(Config{}, std::make_shared<FastLaneChangeSolver>());
    const ExpertResult r = planner.plan(s);
    EXPECT_EQ(r.status, PlanStatus::Converged) << r.reason;
    const Trajectory t = planner.to_trajectory(r, s);
    EXPECT_EQ(t.label, Label::WellPosed) << to_string(b) << ": " << t.reason;
    EXPECT_FALSE(t.collision);
    expect_audit_passes(t, s, Config{});
  }
}

TEST(Planner, NoGapIsAFailure) {
  const Scenario s = no_gap_scenario();
  const ExpertPlanner planner(Config{}, std::make_shared<FastLaneChangeSolver>());
  const ExpertResult r = planner.plan(s);
  EXPECT_EQ(r.status, PlanStatus::Infeasible);
  const Trajectory t = planner.to_trajectory(r, s);
  EXPECT_EQ(t.label, Label::Failure);
  EXPECT_FALSE(t.reason.empty());
}

TEST(Planner, SampledPlansPassTheAudit) {
  const Config config;
  const ScenarioSampler sampler(config, 23);
  const ExpertPlanner planner(config, std::make_shared<FastLaneChangeSolver>());
  int solved = 0;
  for (std::uint64_t i = 0; i < 12; ++i) {
    const Scenario s = sampler.sample(i);
    const Trajectory t = planner.to_trajectory(planner.plan(s), s);
    solved += t.label != Label::Failure;
    for (const std::string& problem : audit_trajectory(t, s, config)) {
      ADD_FAILURE() << "scenario " << i << ": " << problem;
    }
  }
  EXPECT_GT(solved, 0);
}

// A sampled scenario (seed 2026, index 41) whose rounds settle into a 2-cycle:
// two lane-change paths about a metre apart, each the best answer to the other's
// linearization.
Scenario cycling_scenario() {
  return scenario_from_json(nlohmann::json::parse(R"({
    "format": "lanechange.scenario/1", "lane_width": 3.75, "behavior": "constant_accel",
    "ego": {"x": 0.0, "y": 0.0, "v": 8.683847126070834, "theta": 0.0, "a": 0.0},
    "leader": {"x": 36.46241631402696, "v": 8.534950072799933, "a": 0.20758741955206106},
    "follower": {"x": 8.626268446109087, "v": 6.195851938053886, "a": -0.32241094597418973},
    "target": {"x": 30.458004003365353, "v": 7.07590205780297, "a": 0.7107703710394668}})"),
                            Config{});
}

TEST(Planner, StopsRoundsThatAlternateBetweenTwoPaths) {
  Config config;
  config.expert.lane_rule = LaneRule::EitherOr;  // the rule it was found under
  config.expert.cycle_tolerance = 0.0;
  const ExpertPlanner patient(config, std::make_shared<FastLaneChangeSolver>());
  const ExpertResult full = patient.plan(cycling_scenario());
  ASSERT_EQ(full.status, PlanStatus::IterationLimit) << full.reason;
  ASSERT_EQ(full.iterations(), config.expert.max_iterations);

  config.expert.cycle_tolerance = 1e-3;
  const ExpertPlanner planner(config, std::make_shared<FastLaneChangeSolver>());
  const ExpertResult early = planner.plan(cycling_scenario());
  EXPECT_EQ(early.status, PlanStatus::Cycling) << early.reason;
  EXPECT_LT(early.iterations(), full.iterations());
  EXPECT_GT(early.rounds.back().max_change, config.expert.convergence_tolerance);
  // The rounds it skipped would have kept alternating: the last full round's
  // change is as large as the one where the early stop saw the cycle.
  EXPECT_GT(full.rounds.back().max_change, config.expert.convergence_tolerance);
  EXPECT_EQ(planner.to_trajectory(early, cycling_scenario()).label, Label::Failure);
}

TEST(Audit, CatchesTamperedPlans) {
  const Scenario s = open_road_scenario();
  const ExpertPlanner planner(Config{}, std::make_shared<FastLaneChangeSolver>());
  const Trajectory good = planner.to_trajectory(planner.plan(s), s);
  ASSERT_TRUE(audit_trajectory(good, s, Config{}).empty());
  Trajectory moved = good;
  moved.ego[20].x += 0.5;
  EXPECT_FALSE(audit_trajectory(moved, s, Config{}).empty());
  Trajectory relabelled = good;
  relabelled.label = Label::IllPosed;
  EXPECT_FALSE(audit_trajectory(relabelled, s, Config{}).empty());
  Trajectory crashed = good;
  crashed.others.cars[static_cast<int>(Car::Target)].x.assign(good.nodes(), good.ego.back().x);
  EXPECT_FALSE(audit_trajectory(crashed, s, Config{}).empty());
}

}  // namespace
}  // namespace lanechange::expert
