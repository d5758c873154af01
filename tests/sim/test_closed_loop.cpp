#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <thread>

#include "lanechange/checks.hpp"
#include "lanechange/ego.hpp"
#include "lanechange/planner/planner.hpp"
#include "lanechange/sampler.hpp"
#include "lanechange/sim/simulator.hpp"
#include "lanechange/traffic.hpp"
#include "lanechange/trajectory.hpp"
#include "planner/miqp_planner.hpp"
#include "rollout_checks.hpp"
#include "test_helpers.hpp"

namespace lanechange {
namespace {

using planner::ActStatus;
using planner::Decision;
using planner::Observation;
using sim::Outcome;
using testing::expect_consistent;

Scenario open_road(Behavior behavior = Behavior::ConstantSpeed) {
  return testing::open_road_scenario(behavior);
}
Scenario no_gap() { return testing::no_gap_scenario(); }

// A planner given as a function of the observation (tests only).
class ScriptedPlanner final : public planner::ClosedLoopPlanner {
 public:
  using Script = std::function<Decision(const Observation&)>;
  explicit ScriptedPlanner(Script script) : script_(std::move(script)) {}
  [[nodiscard]] std::string_view name() const override { return "scripted"; }
  [[nodiscard]] std::unique_ptr<planner::PlannerSession> start(const Scenario&) const override {
    class Session final : public planner::PlannerSession {
     public:
      explicit Session(const Script& s) : script_(s) {}
      Decision act(const Observation& o) override { return script_(o); }

     private:
      const Script& script_;
    };
    return std::make_unique<Session>(script_);
  }

 private:
  Script script_;
};

TEST(ClosedLoop, ExpertChangesLanesIntoAWideOpenGap) {
  const Config config = testing::untimed_config();
  const Scenario s = open_road();
  const auto miqp = planner::make_planner("miqp", config);
  const sim::Rollout r = sim::simulate(s, *miqp, config);
  testing::expect_consistent(r, s);
  EXPECT_EQ(r.outcome, Outcome::WellPosed) << r.reason;
  EXPECT_FALSE(r.trajectory.collision);
  EXPECT_GT(r.manoeuvre_over_at, 0.0);
  EXPECT_NEAR(r.trajectory.ego.back().y, s.lane_width, config.labels.reach);
}

// A planner that overshoots the target-lane centre and comes back firmly
// must not be handed to the lane keeper while the keeper's slower heading
// response would carry the ego on below the centre: that reversal would be
// the keeper's, judged as the planner's.
TEST(ClosedLoop, TheKeeperTakesOverOnlyWhereItHoldsTheLane) {
  const Config config = testing::untimed_config();
  const Scenario s = open_road();
  const double w = s.lane_width;
  bool coming_back = false;
  const ScriptedPlanner overshooting([&](const Observation& o) {
    coming_back = coming_back || o.ego.y >= w + 0.3;
    const double wanted = coming_back ? std::clamp(-0.4 * (o.ego.y - w), -0.1, 0.1) : 0.2;
    return Decision{{0.0, 4.0 * (wanted - o.ego.theta)}, ActStatus::Planned, ""};
  });
  const sim::Rollout r = sim::simulate(s, overshooting, config);
  ASSERT_TRUE(coming_back);
  testing::expect_consistent(r, s);
  std::vector<double> y;
  for (const EgoState& e : r.trajectory.ego) y.push_back(e.y);
  EXPECT_LE(largest_lateral_reversal(y, w), config.labels.reversal);
  EXPECT_EQ(r.outcome, Outcome::WellPosed) << r.reason;
  EXPECT_GT(r.manoeuvre_over_at, 0.0);
}

TEST(ClosedLoop, NoGapIsAbortedWithoutCollision) {
  const Config config = testing::no_gap_config(testing::untimed_config());
  const Scenario s = no_gap();
  for (const char* name : {"miqp", "keep-lane"}) {
    const auto p = planner::make_planner(name, config);
    const sim::Rollout r = sim::simulate(s, *p, config);
    testing::expect_consistent(r, s, config);
    EXPECT_EQ(r.outcome, Outcome::Aborted) << name << ": " << r.reason;
    EXPECT_FALSE(r.trajectory.collision) << name;
    EXPECT_GT(r.metrics.fallbacks, 0) << name;
  }
}

// Where Eq. 1's gap is closed, the expert that chooses its gap merges into
// another one, behind the follower or ahead of the target.
TEST(ClosedLoop, TheExpertTakesAnotherGapWhereThePapersIsClosed) {
  const Config config = testing::untimed_config();
  // Too short for the ego, but no shorter than the follower keeps behind the
  // target: no_gap()'s 0.6 m would have it brake hard at once.
  Scenario s = no_gap();
  s.follower().x = -7.0;
  s.target().x = 6.0;
  const auto miqp = planner::make_planner("miqp", config);
  const sim::Rollout r = sim::simulate(s, *miqp, config);
  testing::expect_consistent(r, s);
  EXPECT_EQ(r.outcome, Outcome::WellPosed) << r.reason;
  EXPECT_FALSE(r.trajectory.collision);
  EXPECT_TRUE(r.metrics.target_lane_slot == "behind_follower" ||
              r.metrics.target_lane_slot == "ahead_of_target")
      << r.metrics.target_lane_slot;
}

// A sampled scene whose follower, faster than the ego, Eq. 1 alone lets the
// ego cut in ahead of so closely that it must brake at its physical limit;
// the default expert keeps the gap at which it brakes no harder than
// expert.cut_in_decel.
TEST(ClosedLoop, TheExpertCutsInNoCloserThanTheCarBehindCanTakeCalmly) {
  const Config config = testing::untimed_config();
  const Scenario s = ScenarioSampler(config, 2026).sample(13, Behavior::ConstantSpeed);
  Config eq1_only = config;
  eq1_only.expert.cut_in_decel = std::nullopt;
  const sim::Rollout close = sim::simulate(s, *planner::make_planner("miqp", eq1_only), eq1_only);
  ASSERT_TRUE(close.metrics.unsafe_cut_in) << close.metrics.forced_decel;
  const sim::Rollout calm = sim::simulate(s, *planner::make_planner("miqp", config), config);
  testing::expect_consistent(calm, s);
  EXPECT_EQ(calm.outcome, Outcome::WellPosed) << calm.reason;
  ASSERT_TRUE(config.expert.cut_in_decel.has_value());
  EXPECT_LE(calm.metrics.forced_decel, config.closed_loop.unsafe_decel);
  EXPECT_FALSE(calm.trajectory.collision);
}

// A dense scene whose first plan is cut by the step's budget of work; the gap
// it aimed for closes, and no lane change meets that plan's deadline. The
// expert gives the next gap the whole horizon from then and changes lanes
// (with the deadline kept, the lane keeper drove to the end).
TEST(ClosedLoop, WhereTheFirstDeadlinesGapClosesTheExpertTakesAnotherWithANewDeadline) {
  Config config;  // the deadline of work: the same steps on any load
  config.sampler.target_lane_cars = {4.0, 10.0};
  const Scenario s = ScenarioSampler(config, 2026).sample(272);
  const sim::Rollout r = sim::simulate(s, *planner::make_planner("miqp", config), config);
  testing::expect_consistent(r, s);
  EXPECT_EQ(r.outcome, Outcome::WellPosed) << r.reason;
  EXPECT_FALSE(r.trajectory.collision);
}

// The re-plan after a missed deadline stops the ego to let the follower pass
// and turns in steeply behind it at walking pace; the lane rows bound the
// body's lateral extent but not its corners at that heading. The session
// checks each plan's own path with oriented boxes and follows none that
// meets a car.
TEST(ClosedLoop, TheExpertFollowsNoPlanWhosePathMeetsACar) {
  const Config config;
  const Scenario s = ScenarioSampler(config, 2026).sample(128);
  ASSERT_EQ(s.behavior, Behavior::ConstantAccel);
  const sim::Rollout r = sim::simulate(s, *planner::make_planner("miqp", config), config);
  testing::expect_consistent(r, s);
  EXPECT_FALSE(r.trajectory.collision) << r.reason;
}

TEST(ClosedLoop, SampledRolloutsAreConsistent) {
  const Config config = testing::untimed_config();
  const ScenarioSampler sampler(config, 5);
  const auto miqp = planner::make_planner("miqp", config);
  for (std::uint64_t i = 0; i < 4; ++i) {
    const Scenario s = sampler.sample(i);
    const sim::Rollout r = sim::simulate(s, *miqp, config);
    SCOPED_TRACE("scenario " + std::to_string(i));
    testing::expect_consistent(r, s);
  }
}

TEST(ClosedLoop, IdmFollowerBrakesForAnEgoThatCutsIn) {
  // The ego steers into the target lane right in front of the follower.
  Scenario s = open_road(Behavior::Idm);
  s.follower() = {-12.0, 9.0, 0.0};
  s.target() = {60.0, 9.0, 0.0};
  const Config config = testing::untimed_config();
  const ScriptedPlanner cut_in([](const Observation& o) {
    const double wanted = o.ego.y < 3.0 ? 0.2 : 0.0;
    return Decision{{0.0, 2.0 * (wanted - o.ego.theta)}, ActStatus::Planned, ""};
  });
  const sim::Rollout r = sim::simulate(s, cut_in, config, {4.0});
  testing::expect_consistent(r, s);
  const CarTrack& follower = r.trajectory.others.car(car_of(Role::Follower));
  double hardest = 0.0;
  for (double a : follower.a) hardest = std::min(hardest, a);
  EXPECT_LT(hardest, -1.0);  // IDM brakes hard for a car cutting in 7 m ahead
  // The judge counts that braking as the ego's doing.
  EXPECT_NEAR(r.metrics.forced_decel, -hardest, 1e-9);
  EXPECT_EQ(r.metrics.unsafe_cut_in, -hardest > config.closed_loop.unsafe_decel);
  EXPECT_GE(r.metrics.max_car_decel, -hardest);
  EXPECT_FALSE(r.metrics.cars_collide);
  // With the ego staying in its lane, the follower never brakes.
  const ScriptedPlanner stay([](const Observation&) { return Decision{}; });
  const sim::Rollout alone = sim::simulate(s, stay, config, {4.0});
  for (double a : alone.trajectory.others.car(car_of(Role::Follower)).a) EXPECT_GE(a, -1e-9);
  EXPECT_DOUBLE_EQ(alone.metrics.forced_decel, 0.0);
  EXPECT_FALSE(alone.metrics.unsafe_cut_in);
}

TEST(ClosedLoop, AThrowingOrSlowPlannerIsRecordedAndTheFallbackActs) {
  Config config;
  config.closed_loop.deadline = Deadline::WallClock;
  config.closed_loop.step_budget_ms = 5.0;
  const Scenario s = open_road();
  const ScriptedPlanner bad([](const Observation& o) -> Decision {
    if (o.step == 3) throw std::runtime_error("boom");
    if (o.step == 5) std::this_thread::sleep_for(std::chrono::milliseconds(20));
    return {{0.0, 0.4}, ActStatus::Planned, ""};
  });
  const sim::Rollout r = sim::simulate(s, bad, config, {1.0});
  testing::expect_consistent(r, s);
  EXPECT_EQ(r.steps[3].status, ActStatus::Failed);
  EXPECT_NE(r.steps[3].reason.find("boom"), std::string::npos);
  EXPECT_TRUE(r.steps[5].overrun);
  EXPECT_EQ(r.metrics.overruns, 1);
  EXPECT_EQ(r.metrics.failures, 1);
  // The fallback steers back to the lane centre where the planner steered out.
  EXPECT_LT(r.trajectory.controls[3].omega, 0.0);
  // Out-of-limit wishes are clipped and recorded.
  EXPECT_TRUE(r.steps[0].clipped);  // 0.4 rad/s is above the 15 deg/s limit
  EXPECT_NEAR(r.trajectory.controls[0].omega, s.limits.omega.hi, 1e-12);
}

// Under a deadline of work the outcome must not depend on the machine: a
// step over the wall-clock budget is marked, and its decision stands.
TEST(ClosedLoop, UnderADeadlineOfWorkASlowStepIsMarkedAndItsDecisionStands) {
  Config config;
  ASSERT_EQ(config.closed_loop.deadline, Deadline::Work);
  config.closed_loop.step_budget_ms = 5.0;
  const ScriptedPlanner slow([](const Observation& o) -> Decision {
    if (o.step == 2) std::this_thread::sleep_for(std::chrono::milliseconds(20));
    return {{0.5, 0.0}, ActStatus::Planned, ""};
  });
  const sim::Rollout r = sim::simulate(open_road(), slow, config, {1.0});
  ASSERT_TRUE(r.steps[2].overrun);
  EXPECT_EQ(r.steps[2].status, ActStatus::Planned);
  EXPECT_EQ(r.metrics.overruns, 1);
  EXPECT_EQ(r.metrics.failures, 0);
  EXPECT_DOUBLE_EQ(r.trajectory.controls[2].a, 0.5);
}

// Anytime: a re-plan cut by its budget drives with the incumbent it found;
// only one that found nothing hands the step to the fallback.
TEST(ClosedLoop, AReplanCutByItsBudgetDrivesWithItsIncumbent) {
  const Scenario s = open_road();
  const Config config;
  auto cut = [](bool with_incumbent) {
    return [with_incumbent](const Scenario& scene, const expert::PlanLimits&,
                            const expert::PlanHints&, expert::ExpertResult& r) {
      r = expert::ExpertResult{};
      r.status = expert::PlanStatus::WorkLimit;
      r.reason = "the plan's interior-point iterations are spent";
      if (with_incumbent) {
        r.path.states.assign(static_cast<std::size_t>(scene.steps) + 1, expert::State::Zero());
        r.path.controls.assign(static_cast<std::size_t>(scene.steps), expert::Control(0.7, 0.0));
      }
    };
  };
  Observation o;
  o.scene = &s;
  o.ego = s.ego;
  o.cars.assign(s.cars.size(), {});
  for (CarIndex c = 0; c < s.car_count(); ++c) o.cars[c] = s.car(c);
  planner::MiqpSession with(cut(true), config);
  const Decision d = with.act(o);
  EXPECT_EQ(d.status, ActStatus::Planned) << d.reason;
  EXPECT_DOUBLE_EQ(d.control.a, 0.7);
  EXPECT_EQ(with.last_status(), expert::PlanStatus::WorkLimit);
  planner::MiqpSession without(cut(false), config);
  const Decision none = without.act(o);
  EXPECT_EQ(none.status, ActStatus::Fallback);
  EXPECT_NE(none.reason.find("work_limit"), std::string::npos) << none.reason;
}

// A take-over whose first plan overran its budget was still made at that
// step: the count and its time must not depend on the machine's load.
TEST(ClosedLoop, ATakeOverCountsWhereItWasDecidedEvenIfItsStepOverran) {
  Config config;
  config.closed_loop.deadline = Deadline::WallClock;
  config.closed_loop.step_budget_ms = 5.0;
  const ScriptedPlanner taking_over([](const Observation& o) -> Decision {
    if (o.step == 0) std::this_thread::sleep_for(std::chrono::milliseconds(20));
    if (o.step > 3) return {};
    return {{}, ActStatus::TookOver, o.step == 0 ? "take-over: the check failed" : "drives on"};
  });
  const sim::Rollout r = sim::simulate(open_road(), taking_over, config, {1.0});
  ASSERT_TRUE(r.steps[0].overrun);
  EXPECT_EQ(r.steps[0].status, ActStatus::Failed);
  EXPECT_EQ(r.steps[0].decided, ActStatus::TookOver);
  EXPECT_NE(r.steps[0].reason.find("the check failed"), std::string::npos) << r.steps[0].reason;
  EXPECT_EQ(r.metrics.first_takeover_t, 0.0);
  EXPECT_EQ(r.metrics.takeovers, 1);
}

TEST(ClosedLoop, JudgeTellsAbortFromFailure) {
  Config config;
  Trajectory t;
  t.lane_width = 3.75;
  t.dt = 0.1;
  for (int k = 0; k < 20; ++k) {
    t.t.push_back(k * 0.1);
    t.ego.push_back({k * 1.0, 0.05 * std::sin(k * 0.3), 8.0, 0.0, 0.0});
  }
  std::string reason;
  EXPECT_EQ(sim::judge(t, config, reason), Outcome::Aborted);
  t.ego[10].y = 1.2;  // the body crossed the line and came back
  EXPECT_EQ(sim::judge(t, config, reason), Outcome::Failure);
  for (int k = 10; k < 20; ++k) t.ego[k].y = 3.75;
  EXPECT_EQ(sim::judge(t, config, reason), Outcome::WellPosed);
  t.collision = true;
  EXPECT_EQ(sim::judge(t, config, reason), Outcome::Failure);
}

TEST(ClosedLoop, SimulateCliWritesARolloutAndRefusesBadInput) {
  testing::TempDir dir;
  testing::write_text(dir.file("s.json"), testing::example_scenario_json().dump());
  const auto r = testing::run_cli("simulate --planner keep-lane --scenario " + dir.file("s.json") +
                                  " --out " + dir.file("r.json"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto rollout = nlohmann::json::parse(testing::read_text(dir.file("r.json")));
  EXPECT_EQ(rollout["planner"], "keep-lane");
  EXPECT_EQ(rollout["outcome"], "aborted");
  EXPECT_EQ(rollout["t"].size(), rollout["ego"]["x"].size());
  EXPECT_EQ(
      testing::run_cli("simulate --planner nobody --scenario " + dir.file("s.json")).exit_code, 2);
  EXPECT_EQ(testing::run_cli("simulate --scenario " + dir.file("absent.json")).exit_code, 2);
}

// A scene whose target lane is to the right is planned as its mirror image
// and written back in its own frame: the ego ends in the lane to its right,
// the plot draws that lane below, and the rollout reads back as it was held.
TEST(ClosedLoop, ARightHandChangeEndsInTheLaneToTheRight) {
  testing::TempDir dir;
  nlohmann::json scene = testing::example_cars_json();
  scene["road"]["target_lane"] = "right";
  testing::write_text(dir.file("s.json"), scene.dump());
  const auto r =
      testing::run_cli("--config " + testing::untimed_config_file(dir) + " simulate --scenario " +
                       dir.file("s.json") + " --out " + dir.file("r.json"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto rollout = nlohmann::json::parse(testing::read_text(dir.file("r.json")));
  EXPECT_EQ(rollout["outcome"], "well_posed") << rollout["reason"];
  EXPECT_EQ(rollout["target_lane"], "right");
  const double lane_width = scene["road"]["lane_width"].get<double>();
  EXPECT_NEAR(rollout["ego"]["y"].back().get<double>(), -lane_width, 0.3);
  const Trajectory held = trajectory_from_json(rollout);
  EXPECT_EQ(held.target_side, Side::Right);
  EXPECT_NEAR(held.ego.back().y, lane_width, 0.3);
  EXPECT_EQ(trajectory_to_json(held)["ego"], rollout["ego"]);
}

}  // namespace
}  // namespace lanechange
