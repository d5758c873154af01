#include <gtest/gtest.h>

#include <algorithm>

#include "lanechange/sim/simulator.hpp"
#include "planner/mlp_miqp_planner.hpp"
#include "scripted_learner.hpp"
#include "test_helpers.hpp"

namespace lanechange {
namespace {

using planner::MlpMiqpPlanner;
using planner::Observation;
using sim::Outcome;

constexpr int kWorthTrying = static_cast<int>(Label::WellPosed);

using Drive = testing::ScriptedDrive;

MlpMiqpPlanner forced(Drive drive, int scene_class = kWorthTrying,
                      const Config& config = testing::untimed_config()) {
  return testing::scripted_learner(config, static_cast<Label>(scene_class), std::move(drive));
}

// A network that drives to any gap is handed the gap the expert's check of
// a refusal found, and drives it without a take-over.
TEST(MlpMiqp, AGapNetworkDrivesTheGapTheExpertsCheckFound) {
  const Config config = testing::untimed_config();
  const Scenario s = testing::open_road_scenario();
  const planner::LaneKeeper keeper(config);
  std::optional<expert::GapFrame> given;
  const MlpMiqpPlanner p(
      config,
      [](const Scenario&) {
        return MlpMiqpPlanner::SceneChoice{false, {}};
      },
      [&](const Observation& o, const expert::GapFrame& gap) {
        given = gap;
        return keeper.control(o.ego, o.scene->lane_width, std::nullopt);
      },
      std::make_shared<expert::FastLaneChangeSolver>(), "mlp-miqp", false);
  const sim::Rollout r = sim::simulate(s, p, config);
  EXPECT_EQ(r.outcome, Outcome::WellPosed) << r.reason;
  EXPECT_EQ(r.metrics.takeovers, 0);
  ASSERT_TRUE(given.has_value());
  // The open gap beside the ego, between the follower and the target.
  EXPECT_EQ(*given, (expert::GapFrame{s.index_of(Role::Follower), s.index_of(Role::Target)}));
  EXPECT_EQ(r.steps.front().status, planner::ActStatus::Planned) << r.steps.front().reason;
}

// Below the target lane's centre a gap network's heading never turns back
// past parallel: a network that swerves back towards the ego lane is held
// at a constant y instead of reading as a reversal.
TEST(MlpMiqp, AGapNetworksLateralMoveNeverTurnsBack) {
  const Config config = testing::untimed_config();
  ASSERT_TRUE(config.closed_loop.monotone_lateral);
  const auto wobble = [](const Observation& o) { return EgoControl{0.0, o.step < 8 ? 0.1 : -0.3}; };
  const MlpMiqpPlanner p = testing::scripted_learner(
      config, Label::WellPosed, wobble, std::make_shared<expert::FastLaneChangeSolver>(), false);
  const sim::Rollout r = sim::simulate(testing::open_road_scenario(), p, config);
  const auto& y = r.trajectory.ego;
  int network_steps = 0;
  for (std::size_t k = 0; k + 1 < r.steps.size() && k + 1 < y.size(); ++k) {
    if (r.steps[k].status != planner::ActStatus::Planned) break;
    ++network_steps;
    EXPECT_GE(y[k + 1].y, y[k].y - 1e-9) << "step " << k;
  }
  EXPECT_GT(network_steps, 8);
}

// A network that drives to a chosen gap reads the gap's two cars and the
// leader relative to the ego, wherever they are in the scene's list.
TEST(MlpMiqp, PolicyInputsReadTheChosenGapRelativeToTheEgo) {
  const Scenario s = testing::dense_scenario(6);
  Observation o;
  o.scene = &s;
  o.ego = s.ego;
  o.ego.x += 3.0;
  for (const OtherCar& car : s.cars) o.cars.push_back(car.state);
  const auto gap = expert::gap_slots(s).gaps[expert::kGapSlotBeside];
  ASSERT_TRUE(gap && gap->car_behind() && gap->car_ahead());
  const planner::PolicyInputs inputs({"v", "gap_behind_dx", "gap_ahead_dv", "leader_dx"});
  EXPECT_TRUE(inputs.reads_gap());
  const learn::Observation x = inputs.read(o, expert::frame_of(*gap));
  EXPECT_EQ(x[0], o.ego.v);
  EXPECT_EQ(x[1], o.car(*gap->car_behind()).x - o.ego.x);
  EXPECT_EQ(x[2], o.car(*gap->car_ahead()).v - o.ego.v);
  const auto leader = nearest_in_lane(s, o.cars, Lane::Ego, o.ego.x, true);
  ASSERT_TRUE(leader);
  EXPECT_EQ(x[3], o.car(*leader).x - o.ego.x);
  // A gap open on both sides reads as cars far behind and far ahead.
  const learn::Observation open = inputs.read(o, {});
  EXPECT_EQ(open[1], -expert::kOpenGapDistance);
  EXPECT_FALSE(planner::PolicyInputs({"v", "follower_x"}).reads_gap());
  EXPECT_THROW(planner::PolicyInputs({"gap_beside_dx"}), InputError);
}

// A gap network reads the car ahead from the gap view, as its data did: a
// scene without a leader (a free lane ahead, as SUMO's often are) reads as
// an open lane, not as a missing role.
TEST(MlpMiqp, AGapNetworkReadsASceneWithoutALeader) {
  Scenario s = testing::dense_scenario(6);
  std::erase_if(s.cars, [](const OtherCar& car) { return car.id == "lead"; });
  for (const Role role : kRoles) s.roles[static_cast<std::size_t>(role)] = nearest_in_role(s, role);
  ASSERT_FALSE(s.has(Role::Leader));
  Observation o;
  o.scene = &s;
  o.ego = s.ego;
  for (const OtherCar& car : s.cars) o.cars.push_back(car.state);
  const auto gap = expert::gap_slots(s).gaps[expert::kGapSlotBeside];
  ASSERT_TRUE(gap);
  const planner::PolicyInputs inputs({"v", "gap_behind_dx", "leader_dx", "leader_a"});
  ASSERT_TRUE(inputs.reads_gap());
  learn::Observation x;
  ASSERT_NO_THROW(x = inputs.read(o, expert::frame_of(*gap)));
  const auto& names = expert::gap_view_names();
  const auto view = expert::gap_view(s, o.cars, o.ego, expert::frame_of(*gap));
  const auto at = [&names](const char* name) {
    return static_cast<std::size_t>(std::find(names.begin(), names.end(), name) - names.begin());
  };
  EXPECT_EQ(x[2], view[at("leader_dx")]);
  EXPECT_EQ(x[3], view[at("leader_a")]);
  EXPECT_EQ(x[2], expert::kOpenGapDistance);
  // The paper's network reads the leader by its role, as before.
  EXPECT_FALSE(planner::PolicyInputs({"v", "leader_a"}).reads_gap());
}

// A "network" that steers hard into the target lane whatever is there.
EgoControl swerve_left(const Observation&) { return {0.0, 0.26}; }

// A gap network's look-ahead holds it to the expert's bound on the braking
// its cut-in forces on a car that reacts to it: a fast IDM follower, far
// enough back for Eq. 1, would brake harder than that behind the swerve.
TEST(MlpMiqp, AGapNetworkIsTakenOverBeforeItForcesHardBraking) {
  const Config config = testing::untimed_config();
  ASSERT_TRUE(config.expert.cut_in_decel.has_value());
  Scenario s = testing::open_road_scenario(Behavior::Idm);
  s.follower() = {-40.0, 16.0, 0.0};
  validate_scenario(s);
  const auto run = [&](bool reads_roles) {
    const MlpMiqpPlanner p =
        testing::scripted_learner(config, Label::WellPosed, swerve_left,
                                  std::make_shared<expert::FastLaneChangeSolver>(), reads_roles);
    return sim::simulate(s, p, config);
  };
  const sim::Rollout gap = run(false);
  ASSERT_GE(gap.metrics.takeovers, 1);
  const auto first = std::find_if(gap.steps.begin(), gap.steps.end(), [](const auto& k) {
    return k.status == planner::ActStatus::TookOver;
  });
  ASSERT_NE(first, gap.steps.end());
  EXPECT_NE(first->reason.find("brake at"), std::string::npos) << first->reason;
  // The paper's network is held to Eq. 1 alone.
  for (const auto& k : run(true).steps) EXPECT_EQ(k.reason.find("brake at"), std::string::npos);
}

TEST(MlpMiqp, ANetworkSteeringIntoACarIsTakenOverAndNothingIsHit) {
  const Scenario s = testing::no_gap_scenario();
  const Config paper = testing::no_gap_config(testing::untimed_config());
  const MlpMiqpPlanner p = forced(swerve_left, kWorthTrying, paper);
  const sim::Rollout r = sim::simulate(s, p, paper);
  EXPECT_GE(r.metrics.takeovers, 1);
  const auto first = std::find_if(r.steps.begin(), r.steps.end(), [](const sim::StepRecord& k) {
    return k.status == planner::ActStatus::TookOver;
  });
  ASSERT_NE(first, r.steps.end());
  EXPECT_EQ(r.metrics.first_takeover_t, r.trajectory.t[first - r.steps.begin()]);
  EXPECT_FALSE(r.trajectory.collision) << r.reason;
  // The expert finds no gap either, so the fallback keeps the ego lane.
  EXPECT_EQ(r.outcome, Outcome::Aborted) << r.reason;
  EXPECT_GT(r.metrics.fallbacks, 0);
}

// A planner whose classifier refuses every scene; its network counts its calls.
MlpMiqpPlanner refusing_counter(int& calls, const Config& config) {
  return forced(
      [&calls](const Observation& o) {
        ++calls;
        return swerve_left(o);
      },
      static_cast<int>(Label::Failure), config);
}

// The paper's Algorithm 1 leaves a refused scene to the fallback for good.
TEST(MlpMiqp, ASceneClassedAsFailureIsNotTriedUnderThePapersRule) {
  Config config = testing::untimed_config();
  config.closed_loop.refusal_check_period = 0;
  int calls = 0;
  const MlpMiqpPlanner p = refusing_counter(calls, config);
  const sim::Rollout r = sim::simulate(testing::open_road_scenario(), p, config);
  EXPECT_EQ(r.outcome, Outcome::Aborted);
  EXPECT_EQ(r.metrics.takeovers, 0);
  EXPECT_EQ(r.metrics.first_takeover_t, -1.0);
  EXPECT_EQ(calls, 0);
}

// By default the expert checks a refusal: where it finds a plan it drives,
// and the network is still never asked.
TEST(MlpMiqp, AWrongRefusalIsCaughtByTheExpertsCheck) {
  const Config config = testing::untimed_config();
  ASSERT_GT(config.closed_loop.refusal_check_period, 0);
  int calls = 0;
  const MlpMiqpPlanner p = refusing_counter(calls, config);
  const sim::Rollout r = sim::simulate(testing::open_road_scenario(), p, config);
  EXPECT_EQ(r.outcome, Outcome::WellPosed) << r.reason;
  EXPECT_EQ(r.metrics.takeovers, 1);
  EXPECT_EQ(r.metrics.first_takeover_t, 0.0);  // the check at the first step
  EXPECT_EQ(calls, 0);
  EXPECT_NE(r.steps.front().reason.find("the expert's check found a plan"), std::string::npos)
      << r.steps.front().reason;

  // Where the expert finds no plan either, the fallback keeps the lane and
  // the expert checks again every period, no more often.
  Config sparse = testing::no_gap_config(config);
  sparse.closed_loop.refusal_check_period = 3;
  const MlpMiqpPlanner checks_every_third = refusing_counter(calls, sparse);
  const sim::Rollout blocked =
      sim::simulate(testing::no_gap_scenario(), checks_every_third, sparse);
  EXPECT_EQ(blocked.outcome, Outcome::Aborted) << blocked.reason;
  EXPECT_FALSE(blocked.trajectory.collision);
  const std::size_t period = static_cast<std::size_t>(sparse.closed_loop.refusal_check_period);
  int checks = 0;
  for (std::size_t k = 0; k < blocked.steps.size(); ++k) {
    const bool checked =
        blocked.steps[k].reason.find("the expert's check agrees") != std::string::npos;
    EXPECT_EQ(checked, k % period == 0) << "step " << k << ": " << blocked.steps[k].reason;
    checks += checked ? 1 : 0;
  }
  EXPECT_GE(checks, 2);
}

TEST(MlpMiqp, ANetworkThatDrivesWellIsNotOverruled) {
  // A lane keeper aimed at the target lane stands in for a good network.
  const Config config = testing::untimed_config();
  const planner::LaneKeeper keeper(config);
  const MlpMiqpPlanner p = forced([&keeper](const Observation& o) {
    return keeper.control(o.ego, o.scene->lane_width, std::nullopt);
  });
  const Scenario s = testing::open_road_scenario();
  const sim::Rollout r = sim::simulate(s, p, config);
  EXPECT_EQ(r.metrics.takeovers, 0) << (r.steps.empty() ? "" : r.steps.front().reason);
  for (const auto& step : r.steps) {
    if (!step.reason.empty()) ADD_FAILURE() << step.reason;
  }
  EXPECT_FALSE(r.trajectory.collision);
  EXPECT_GT(r.manoeuvre_over_at, 0.0);
  EXPECT_EQ(r.outcome, Outcome::WellPosed) << r.reason;
}

// A check that ran out of time decided nothing, so the next step checks
// again; a check that found no plan waits for the period.
// The fast solver, except that a solve given less than a second reports its
// time limit without an answer: this keeps the test off the clock.
class OutOfTimeUnderASecond final : public expert::LaneChangeSolver {
 public:
  [[nodiscard]] std::string_view name() const override { return "out-of-time-under-a-second"; }
  [[nodiscard]] std::unique_ptr<expert::LaneChangeWorkspace> make_workspace() const override {
    return fast_.make_workspace();
  }
  [[nodiscard]] expert::LaneChangeSolution solve(const expert::LaneChangeQp& qp,
                                                 const expert::MiqpSettings& settings,
                                                 const expert::SolveHints& hints) const override {
    if (settings.time_limit_s >= 1.0) return fast_.solve(qp, settings, hints);
    expert::LaneChangeSolution out;
    out.status = expert::MiqpStatus::TimeLimit;
    out.message = "out of time";
    return out;
  }

 private:
  expert::FastLaneChangeSolver fast_;
};

TEST(MlpMiqp, ARefusalCheckCutShortByItsTimeLimitIsRepeatedAtOnce) {
  const Scenario s = testing::open_road_scenario();
  auto checks_in_first_steps = [&s](double budget_ms) {
    Config config = testing::untimed_config();
    config.closed_loop.step_budget_ms = budget_ms;
    config.closed_loop.deadline = Deadline::WallClock;
    int calls = 0;
    const MlpMiqpPlanner p = testing::scripted_learner(
        config, Label::Failure,
        [&calls](const Observation& o) {
          ++calls;
          return swerve_left(o);
        },
        std::make_shared<OutOfTimeUnderASecond>());
    const auto session = p.start(s);
    Observation o;
    o.scene = &s;
    o.ego = s.ego;
    o.cars = {s.leader(), s.follower(), s.target()};
    int checks = 0;
    for (o.step = 0; o.step < 4; ++o.step) {
      const planner::Decision d = session->act(o);
      checks += d.reason.find("the expert's check") != std::string::npos ? 1 : 0;
      if (d.status == planner::ActStatus::TookOver) break;
    }
    EXPECT_EQ(calls, 0);
    return checks;
  };
  EXPECT_EQ(checks_in_first_steps(1e-9), 4);  // every plan stops at its time limit
  EXPECT_EQ(checks_in_first_steps(1e9), 1);   // the first plan is found and takes over
}

// A network that overshoots the target lane and swings back hard towards
// the ego lane is taken over before the move back becomes a reversal.
TEST(MlpMiqp, ANetworkSwingingBackTowardsTheEgoLaneIsTakenOver) {
  const Config config = testing::untimed_config();
  const Scenario s = testing::open_road_scenario();
  const double w = s.lane_width;
  bool coming_back = false;
  const MlpMiqpPlanner p = forced([&](const Observation& o) {
    coming_back = coming_back || o.ego.y >= w + 0.3;
    return EgoControl{0.0, 3.0 * ((coming_back ? -0.2 : 0.2) - o.ego.theta)};
  });
  const sim::Rollout r = sim::simulate(s, p, config);
  ASSERT_EQ(r.metrics.takeovers, 1);
  std::string reason;
  for (const auto& step : r.steps) {
    if (step.status == planner::ActStatus::TookOver) {
      reason = step.reason;
      break;
    }
  }
  EXPECT_NE(reason.find("back towards the ego lane"), std::string::npos) << reason;
  EXPECT_FALSE(r.trajectory.collision);
}

// A network that stops short of the line, or across it, and drives on
// straight would end the run outside the target lane: the expert takes over
// once the look-ahead shows it (at t_f, or at the end of the run), while it
// still has the time to finish the change.
TEST(MlpMiqp, ANetworkThatStallsShortOfTheTargetLaneIsTakenOverInTime) {
  const Config config = testing::untimed_config();
  const Scenario s = testing::open_road_scenario();
  struct Case {
    double stall_y;
    double checked_at;  // the look-ahead node that finds it
    const char* reason;
  };
  const double run_end = s.horizon + config.closed_loop.settle_time;
  for (const Case& c : {Case{1.0, s.horizon, "not have crossed the lane line at t_f"},
                        Case{2.5, run_end, "off the target lane's centre"}}) {
    const MlpMiqpPlanner p = forced([&c](const Observation& o) {
      const double heading = o.ego.y < c.stall_y ? 0.1 : 0.0;
      return EgoControl{0.0, 3.0 * (heading - o.ego.theta)};
    });
    const sim::Rollout r = sim::simulate(s, p, config);
    ASSERT_EQ(r.metrics.takeovers, 1) << c.reason;
    const auto took_over = std::find_if(r.steps.begin(), r.steps.end(), [](const auto& step) {
      return step.status == planner::ActStatus::TookOver;
    });
    ASSERT_NE(took_over, r.steps.end());
    EXPECT_NE(took_over->reason.find(c.reason), std::string::npos) << took_over->reason;
    const double taken_at = static_cast<double>(took_over - r.steps.begin()) * s.horizon / s.steps;
    EXPECT_GE(taken_at, c.checked_at - config.closed_loop.lookahead - 1e-9) << c.reason;
    EXPECT_EQ(r.outcome, Outcome::WellPosed) << c.reason << ": " << r.reason;
  }
}

// The look-ahead kept from step to step (closed_loop.lookahead_tolerance)
// asks the network about twice per step instead of once per look-ahead
// node, and reaches the verdicts of a look-ahead rolled out every step.
TEST(MlpMiqp, AKeptLookAheadDecidesAsARolledOutOne) {
  const Config reusing = testing::untimed_config();
  ASSERT_GT(reusing.closed_loop.lookahead_tolerance, 0.0);
  Config rolling = reusing;
  rolling.closed_loop.lookahead_tolerance = 0.0;
  const planner::LaneKeeper keeper(reusing);
  const double w = testing::open_road_scenario().lane_width;
  struct Case {
    Scenario scene;
    Drive network;
  };
  const std::vector<Case> cases = {
      {testing::open_road_scenario(),
       [&keeper, w](const Observation& o) { return keeper.control(o.ego, w, std::nullopt); }},
      {testing::no_gap_scenario(), swerve_left},
      {testing::open_road_scenario(Behavior::Idm), swerve_left}};
  for (const Case& c : cases) {
    long long calls[2] = {0, 0};
    sim::Rollout runs[2];
    for (int i = 0; i < 2; ++i) {
      const Config& config = i == 0 ? reusing : rolling;
      const MlpMiqpPlanner p = forced(
          [&c, &calls, i](const Observation& o) {
            ++calls[i];
            return c.network(o);
          },
          kWorthTrying, config);
      runs[i] = sim::simulate(c.scene, p, config);
    }
    EXPECT_EQ(runs[0].outcome, runs[1].outcome) << runs[0].reason << " / " << runs[1].reason;
    EXPECT_EQ(runs[0].metrics.takeovers, runs[1].metrics.takeovers);
    EXPECT_EQ(runs[0].trajectory.collision, runs[1].trajectory.collision);
    ASSERT_EQ(runs[0].steps.size(), runs[1].steps.size());
    for (std::size_t k = 0; k < runs[0].steps.size(); ++k) {
      EXPECT_EQ(runs[0].steps[k].status, runs[1].steps[k].status) << "step " << k;
    }
    if (runs[0].metrics.takeovers == 0) {
      EXPECT_LT(3 * calls[0], calls[1]);
    }
  }
}

// The real thing: a model trained by the CLI on a small data set drives the
// loop without collision. (A 60-scene network need not finish the change;
// docs/closed_loop.md has the paper-scale model's results.)
TEST(MlpMiqp, ATrainedModelDrivesTheLoopWithoutCollision) {
  testing::TempDir dir;
  ASSERT_EQ(
      testing::run_cli("generate --count 60 --seed 3 --jobs 2 --out " + dir.file("data")).exit_code,
      0);
  const auto trained = testing::run_cli("train --quick --no-plots --max-epochs 20 --data " +
                                        dir.file("data") + " --out " + dir.file("model"));
  ASSERT_EQ(trained.exit_code, 0) << trained.output;
  testing::write_text(dir.file("s.json"), scenario_to_json(testing::open_road_scenario()).dump());
  testing::write_text(dir.file("untimed.json"),
                      nlohmann::json({{"closed_loop", {{"step_budget_ms", 1e9}}}}).dump());
  // One rollout of `planner` on the open road; exit code 2 without --model.
  auto drive = [&dir](const std::string& planner) {
    const std::string out = dir.file(planner + ".json");
    const auto run = testing::run_cli(
        "--config " + dir.file("untimed.json") + " simulate --planner " + planner + " --model " +
        dir.file("model") + " --scenario " + dir.file("s.json") + " --out " + out);
    EXPECT_EQ(run.exit_code, 0) << run.output;
    EXPECT_EQ(
        testing::run_cli("simulate --planner " + planner + " --scenario " + dir.file("s.json"))
            .exit_code,
        2);
    return run.exit_code == 0 ? nlohmann::json::parse(testing::read_text(out)) : nlohmann::json{};
  };
  const auto rollout = drive("mlp-miqp");
  ASSERT_FALSE(rollout.is_null());
  EXPECT_EQ(rollout["planner"], "mlp-miqp");
  EXPECT_FALSE(rollout["collision"].get<bool>());
  const std::string outcome = rollout["outcome"];
  EXPECT_NO_THROW((void)sim::outcome_from_string(outcome));
  EXPECT_EQ(rollout["t"].size(), rollout["ego"]["y"].size());

  // The oracle: the same classifier and check, the expert in the network's
  // place. On the open road the expert changes lanes, and so does it.
  const auto oracle = drive("mlp-miqp-oracle");
  ASSERT_FALSE(oracle.is_null());
  EXPECT_EQ(oracle["planner"], "mlp-miqp-oracle");
  EXPECT_EQ(oracle["outcome"], "well_posed");
  EXPECT_FALSE(oracle["collision"].get<bool>());

  // Twelve cars: the classifier and the network read the nearest gap's.
  testing::write_text(dir.file("s.json"),
                      scenario_to_json(testing::dense_scenario(10, -80.0, 16.0)).dump());
  const auto dense = drive("mlp-miqp");
  ASSERT_FALSE(dense.is_null());
  EXPECT_EQ(dense["others"].size(), 12U);
  EXPECT_FALSE(dense["collision"].get<bool>());
}

}  // namespace
}  // namespace lanechange
