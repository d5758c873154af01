// The co-simulation with SUMO: each test is its own process (libsumo holds
// one simulation per process).
#include <gtest/gtest.h>

#include <algorithm>
#include <filesystem>
#include <string>

#include "lanechange/baselines/baselines.hpp"
#include "lanechange/error.hpp"
#include "lanechange/sim/evaluate.hpp"
#include "lanechange/sumo/cosim.hpp"
#include "lanechange/trajectory.hpp"
#include "test_helpers.hpp"

namespace lanechange::sumo {
namespace {

// Traffic on both lanes, in which the expert finds a gap: 30 cars per lane
// and km, seed 2.
HighwaySettings busy_highway() {
  HighwaySettings h;
  h.density = 30.0;
  h.seed = 2;
  return h;
}

CoSimResult run_planner(const std::string& name, const HighwaySettings& highway,
                        const testing::TempDir& dir, bool signal_change = true,
                        const Config& given = testing::untimed_config()) {
  const Config config = as_sumo_drives(given);
  const auto planner = baselines::make_planner(name, config);
  CoSimSettings settings;
  settings.signal_change = signal_change;
  settings.work_dir = dir.path().string() + "/sumo";
  return run_highway(*planner, config, highway, settings);
}

CoSimResult run_miqp(const HighwaySettings& highway, const testing::TempDir& dir,
                     bool signal_change = true) {
  return run_planner("miqp", highway, dir, signal_change);
}

HighwaySettings dense_highway(int seed) {
  HighwaySettings h;
  h.density = 40.0;
  h.seed = seed;
  return h;
}

TEST(SumoHighway, TheExpertChangesLanesAndTheCarBehindFollowsTheEgo) {
  const testing::TempDir dir;
  const CoSimResult r = run_miqp(busy_highway(), dir);
  const Trajectory& t = r.rollout.trajectory;
  ASSERT_EQ(r.rollout.outcome, sim::Outcome::WellPosed) << r.rollout.reason;
  EXPECT_EQ(r.sumo_collisions, 0);
  EXPECT_FALSE(t.collision);
  // The target-lane car nearest behind the ego at the end: SUMO made the ego
  // its leader (it reacted to the ego), and it stayed behind the ego.
  const auto last = static_cast<std::size_t>(t.nodes() - 1);
  const EgoState& ego = t.ego.back();
  std::optional<CarIndex> behind;
  for (CarIndex c = 0; c < r.scene.car_count(); ++c) {
    const CarTrack& track = t.others.car(c);
    if (r.scene.cars[c].lane != Lane::Target || !track.present_at(last)) continue;
    if (track.x[last] < ego.x && (!behind || track.x[last] > t.others.car(*behind).x[last])) {
      behind = c;
    }
  }
  ASSERT_TRUE(behind.has_value()) << "no SUMO car behind the ego in its new lane";
  const std::string id = r.scene.cars[*behind].id.substr(0, r.scene.cars[*behind].id.find('~'));
  EXPECT_TRUE(r.followers.count(id) == 1) << id << " never took the ego as its leader";
  for (std::size_t k = 0; k <= last; ++k) {
    if (!t.others.car(*behind).present_at(k)) continue;
    EXPECT_LT(t.others.car(*behind).x[k], t.ego[k].x) << "it passed the ego at node " << k;
  }
}

// Dense traffic (40 cars per lane and km, seed 2) opens no gap by itself:
// the expert merges where the ego asks SUMO for the change and SUMO's cars
// cooperate, and stays in its lane where it does not ask.
TEST(SumoHighway, TheTargetLaneOpensAGapForAnEgoThatSignals) {
  const HighwaySettings dense = dense_highway(2);
  const testing::TempDir dir;
  const CoSimResult signalled = run_miqp(dense, dir, true);
  EXPECT_EQ(signalled.rollout.outcome, sim::Outcome::WellPosed) << signalled.rollout.reason;
  EXPECT_FALSE(signalled.rollout.trajectory.collision);
  EXPECT_LE(signalled.rollout.forced_decel, testing::untimed_config().closed_loop.unsafe_decel);
  const testing::TempDir silent_dir;
  const CoSimResult silent = run_miqp(dense, silent_dir, false);
  EXPECT_EQ(silent.rollout.outcome, sim::Outcome::Aborted) << silent.rollout.reason;
}

// SUMO's car behind the gap yields to the ego's signal at its full 4.5
// m/s^2 (40 cars per lane and km, seed 16), where following the ego, once the
// ego leads it, demands no braking: the cut-in forced nothing.
TEST(SumoHighway, ACarYieldingToTheSignalIsNotCountedAsForcedByTheCutIn) {
  const double unsafe = testing::untimed_config().closed_loop.unsafe_decel;
  const testing::TempDir dir;
  const CoSimResult r = run_miqp(dense_highway(16), dir);
  ASSERT_EQ(r.rollout.outcome, sim::Outcome::WellPosed) << r.rollout.reason;
  EXPECT_GT(r.follower_braking, unsafe);
  EXPECT_LT(r.rollout.forced_decel, unsafe);
  EXPECT_FALSE(r.rollout.metrics.unsafe_cut_in);
}

// `mpc` cuts in so close ahead of a target-lane car (40 cars per lane and
// km, seed 4) that its own car-following must brake harder than the judge's
// safe deceleration. Under the default deadline of work: without it `mpc`
// stops at its own wall-clock limit, and a slower build would drive
// otherwise.
TEST(SumoHighway, ACutInCloseAheadOfACarIsCountedAsForcingItsBraking) {
  const double unsafe = Config{}.closed_loop.unsafe_decel;
  const testing::TempDir dir;
  const CoSimResult r = run_planner("mpc", dense_highway(4), dir, true, Config{});
  EXPECT_GT(r.rollout.forced_decel, unsafe);
  EXPECT_TRUE(r.rollout.metrics.unsafe_cut_in);
  EXPECT_FALSE(r.followers.empty());
}

TEST(SumoHighway, SumosEgoIsOursAfterEveryStep) {
  const testing::TempDir dir;
  const CoSimResult r = run_miqp(busy_highway(), dir);
  EXPECT_EQ(r.rollout.steps.size(), r.sumo_step_ms.size());
  EXPECT_LT(r.max_pose_error, 1e-6);
  // Every car the planner saw was recorded, one track per stay in a lane.
  EXPECT_GT(r.scene.car_count(), 0U);
  EXPECT_EQ(r.rollout.trajectory.others.car_count(), r.scene.car_count());
}

// The expert, recording the time of every observation it is handed and
// how many sessions the co-simulation started.
class TimedExpert final : public planner::ClosedLoopPlanner {
 public:
  struct Seen {
    int step;
    double t;
  };
  explicit TimedExpert(const Config& config) : inner_(baselines::make_planner("miqp", config)) {}
  [[nodiscard]] std::string_view name() const override { return "miqp"; }
  [[nodiscard]] std::unique_ptr<planner::PlannerSession> start(
      const Scenario& scene) const override {
    ++sessions;
    return std::make_unique<Session>(inner_->start(scene), seen);
  }
  mutable int sessions = 0;
  mutable std::vector<Seen> seen;

 private:
  class Session final : public planner::PlannerSession {
   public:
    Session(std::unique_ptr<planner::PlannerSession> inner, std::vector<Seen>& seen)
        : inner_(std::move(inner)), seen_(seen) {}
    [[nodiscard]] planner::Decision act(const planner::Observation& o) override {
      seen_.push_back({o.step, o.t});
      return inner_->act(o);
    }

   private:
    std::unique_ptr<planner::PlannerSession> inner_;
    std::vector<Seen>& seen_;
  };
  std::shared_ptr<const planner::ClosedLoopPlanner> inner_;
};

// Cars come into range and leave it, and each change starts a new session
// on the new scene; the clock runs on from the request through all of them,
// so the manoeuvre's deadline (t_f) stays where the request set it and a
// network that reads the time is not told that a change half done starts now.
TEST(SumoHighway, TheClockRunsOnFromTheRequestAcrossNewScenes) {
  const testing::TempDir dir;
  const Config config = as_sumo_drives(testing::untimed_config());
  const TimedExpert planner(config);
  CoSimSettings settings;
  settings.work_dir = dir.path().string() + "/sumo";
  const CoSimResult r = run_highway(planner, config, busy_highway(), settings);
  ASSERT_GT(r.scenes, 1);
  EXPECT_EQ(planner.sessions, r.scenes);
  ASSERT_FALSE(planner.seen.empty());
  const double dt = r.rollout.trajectory.dt;
  for (std::size_t k = 0; k < planner.seen.size(); ++k) {
    EXPECT_EQ(planner.seen[k].step, static_cast<int>(k));
    EXPECT_NEAR(planner.seen[k].t, static_cast<double>(k) * dt, 1e-9) << "step " << k;
  }
}

TEST(SumoHighway, TheRolloutFileReadsBackWithItsAbsentCars) {
  const testing::TempDir dir;
  const CoSimResult r = run_miqp(busy_highway(), dir);
  const std::string path = dir.path().string() + "/rollout.json";
  sim::save_rollout(r.rollout, path);
  const Trajectory back = load_trajectory(path);
  ASSERT_EQ(back.others.car_count(), r.rollout.trajectory.others.car_count());
  for (CarIndex c = 0; c < back.others.car_count(); ++c) {
    EXPECT_EQ(back.others.car(c).present, r.rollout.trajectory.others.car(c).present);
  }
  const auto plot =
      testing::run_cli("plot --trajectory " + path + " --out " + dir.path().string() + "/p.png");
  EXPECT_EQ(plot.exit_code, 0) << plot.output;
}

TEST(SumoEvaluate, WorkerProcessesWriteEveryEpisodeAndAResumeRunsNone) {
  const testing::TempDir dir;
  const std::string out = dir.path().string() + "/eval";
  const std::string command =
      "evaluate --sumo-highway 15,40 --count 2 --seed 3 --planner "
      "keep-lane,dwa --jobs 2 --shard-size 1 --out " +
      out;
  auto r = testing::run_cli(command);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const std::vector<sim::RolloutRow> rows = sim::read_rollouts(out + "/rollouts.csv");
  ASSERT_EQ(rows.size(), 8U);  // 2 densities x 2 episodes x 2 planners
  for (std::size_t i = 0; i < rows.size(); ++i) {
    EXPECT_EQ(rows[i].index, static_cast<long long>(i / 2));
    EXPECT_EQ(rows[i].behavior, i < 4 ? "highway_15" : "highway_40");
    // The lane keeper never leaves its lane.
    if (rows[i].planner == "keep-lane") {
      EXPECT_EQ(rows[i].outcome, "aborted");
    }
  }
  const std::string before = testing::read_text(out + "/rollouts.csv");
  r = testing::run_cli(command);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(testing::read_text(out + "/rollouts.csv"), before);
  r = testing::run_cli("evaluate --sumo-highway 15,x --count 2 --seed 3 --out " + out + "2");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("--sumo-highway"), std::string::npos) << r.output;
}

const std::string kInteractive = std::string(LANECHANGE_COMMONROAD_DIR) + "/interactive";

std::string listing(const std::string& dir) {
  std::string out;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    out += entry.path().filename().string() + " " + std::to_string(entry.file_size()) + "\n";
  }
  return out;
}

TEST(SumoCommonRoad, AnInteractiveScenarioRunsToAnOutcomeAndIsOnlyRead) {
  const std::string folder = kInteractive + "/USA_US101-31_1_I-1-1";
  if (!std::filesystem::is_directory(folder)) GTEST_SKIP() << folder << " is not here";
  const std::string before = listing(folder);
  const testing::TempDir dir;
  const Config config = testing::untimed_config();
  CoSimSettings settings;
  settings.work_dir = dir.path().string() + "/sumo";
  const CoSimResult r =
      run_commonroad(*baselines::make_planner("miqp", config), config, folder, settings);
  EXPECT_EQ(r.rollout.steps.size(), r.sumo_step_ms.size());
  EXPECT_GT(r.scene.car_count(), 0U);
  // The lane bends a little: SUMO's ego is ours after every step all the same.
  EXPECT_LT(r.max_pose_error, 1e-6);
  EXPECT_EQ(listing(folder), before);
}

// A folder's vehicle type is how SUMO drives its cars, and so how the
// planners predict them; what the type leaves out is SUMO's default.
TEST(SumoCommonRoad, TheCarModelIsTheFoldersVehicleType) {
  const testing::TempDir dir;
  const std::string folder = dir.path().string() + "/ONE_1";
  std::filesystem::create_directories(folder);
  EXPECT_EQ(commonroad_car_model(folder), SumoCarModel{});
  testing::write_text(folder + "/ONE_1.vehicles.rou.xml",
                      R"(<routes><vType id="car" decel="6" minGap="1.5" tau="0.8"/></routes>)");
  EXPECT_EQ(commonroad_car_model(folder), (SumoCarModel{6.0, 1.5, 0.8}));
  // NAME.add.xml comes first.
  testing::write_text(folder + "/ONE_1.add.xml",
                      R"(<additional><vTypeDistribution id="d"><vType id="p" decel="7.5" )"
                      R"(minGap="1.0"/></vTypeDistribution></additional>)");
  EXPECT_EQ(commonroad_car_model(folder), (SumoCarModel{7.5, 1.0, SumoCarModel{}.tau}));
  const Config config = as_sumo_drives(Config{}, commonroad_car_model(folder));
  EXPECT_EQ(config.traffic.follow_decel, 7.5);
  EXPECT_EQ(config.traffic.min_gap, 1.0);
  EXPECT_EQ(config.traffic.sees_ego, SeesEgo::Overlapping);
  testing::write_text(folder + "/ONE_1.add.xml",
                      R"(<additional><vType id="p" decel="-2"/></additional>)");
  try {
    (void)commonroad_car_model(folder);
    ADD_FAILURE() << "a negative decel was read";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("ONE_1.add.xml"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("decel"), std::string::npos) << e.what();
  }
}

// USA_US101-19_1's cars brake at up to 7.5 m/s^2 (its vType), which makes
// Krauss's response to a cut-in sharper than SUMO's default car's: predicted
// by the default, the expert cut in where the car behind had to brake at
// 4.39 m/s^2; predicted by the folder's type, it changes lanes calmly.
TEST(SumoCommonRoad, TheExpertPredictsTheFoldersCarsAndCutsInCalmly) {
  const std::string folder = kInteractive + "/USA_US101-19_1_I-1-1";
  if (!std::filesystem::is_directory(folder)) GTEST_SKIP() << folder << " is not here";
  const testing::TempDir dir;
  const Config config = as_sumo_drives(testing::untimed_config(), commonroad_car_model(folder));
  CoSimSettings settings;
  settings.work_dir = dir.path().string() + "/sumo";
  const CoSimResult r =
      run_commonroad(*baselines::make_planner("miqp", config), config, folder, settings);
  EXPECT_EQ(r.rollout.outcome, sim::Outcome::WellPosed) << r.rollout.reason;
  EXPECT_LT(r.rollout.forced_decel, config.closed_loop.unsafe_decel);
  EXPECT_FALSE(r.rollout.metrics.unsafe_cut_in);
}

TEST(SumoCommonRoad, AFolderWithoutItsScenarioFileExitsTwoNamingIt) {
  const testing::TempDir dir;
  const std::string folder = dir.path().string() + "/ONE_1";
  std::filesystem::create_directories(folder);
  testing::write_text(folder + "/ONE_1.net.xml", "<net/>");
  auto r =
      testing::run_cli("sumo --commonroad " + folder + " --out " + dir.path().string() + "/r.json");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("ONE_1.cr.xml"), std::string::npos) << r.output;
  testing::write_text(folder + "/ONE_1.cr.xml", "<commonRoad><broken");
  testing::write_text(folder + "/ONE_1.vehicles.rou.xml", "<routes/>");
  r = testing::run_cli("sumo --commonroad " + folder + " --out " + dir.path().string() + "/r.json");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_FALSE(std::filesystem::exists(dir.path() / "r.json"));
}

TEST(SumoHighway, BadSettingsExitTwoNamingTheOption) {
  const testing::TempDir dir;
  for (const std::string bad : {"--density -1", "--lanes 1", "--range 5", "--prediction replay"}) {
    const auto r =
        testing::run_cli("sumo --highway " + bad + " --out " + dir.path().string() + "/r.json");
    EXPECT_EQ(r.exit_code, 2) << bad << ": " << r.output;
  }
  const auto r = testing::run_cli("sumo --out " + dir.path().string() + "/r.json");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("--highway"), std::string::npos) << r.output;
  // SUMO's options name themselves when given to scenes of our own.
  for (const std::string sumo_only : {"--prediction idm", "--no-signal"}) {
    const auto scenes = testing::run_cli("evaluate --count 1 --seed 1 " + sumo_only + " --out " +
                                         dir.path().string() + "/eval");
    EXPECT_EQ(scenes.exit_code, 2) << scenes.output;
    EXPECT_NE(scenes.output.find(sumo_only.substr(0, sumo_only.find(' '))), std::string::npos)
        << scenes.output;
  }
}

}  // namespace
}  // namespace lanechange::sumo
