// Scenes cut from CommonRoad recordings: the frame along the ego's lane, the
// cars it keeps, the driver's own lane change, and the CLI around it.
#include <gtest/gtest.h>

#include <filesystem>
#include <numbers>
#include <string>

#include "commonroad_fixture.hpp"
#include "lanechange/commonroad/import.hpp"
#include "lanechange/error.hpp"
#include "test_helpers.hpp"

namespace lanechange::commonroad {
namespace {

using lanechange::testing::two_lane_commonroad;

const OtherCar& car_named(const Scenario& s, const std::string& id) {
  const auto i = s.find(id);
  EXPECT_TRUE(i.has_value()) << id;
  return s.cars.at(i.value_or(0));
}

ImportReport import_text(const std::string& xml, const ImportSettings& settings = {}) {
  return import_scenes(recording_from_text(xml, "two.xml"), Config{}, settings);
}

TEST(CommonRoadImport, APlanningProblemBecomesASceneInTheFrameOfItsLane) {
  // Turned by 30 degrees, the road is the same road: the scene must not see it.
  for (const double turn : {0.0, std::numbers::pi / 6.0}) {
    const ImportReport report = import_text(two_lane_commonroad(turn));
    ASSERT_EQ(report.scenes.size(), 1u) << turn;
    const Scenario& s = report.scenes[0].scene;
    EXPECT_EQ(report.scenes[0].name, "TEST_Two-1_1_T-1_problem100_left");
    EXPECT_NEAR(s.lane_width, 3.5, 1e-9);
    EXPECT_EQ(s.target_side, Side::Left);
    EXPECT_NEAR(s.ego.y, 0.0, 1e-9);
    EXPECT_NEAR(s.ego.theta, 0.0, 1e-9);
    EXPECT_NEAR(s.ego.v, 10.0, 1e-9);
    ASSERT_EQ(s.car_count(), 4u);
    EXPECT_EQ(car_named(s, "2").lane, Lane::Ego);
    EXPECT_NEAR(car_named(s, "2").state.x, 30.0, 1e-6);
    EXPECT_NEAR(car_named(s, "2").state.v, 8.0, 1e-6);
    EXPECT_EQ(car_named(s, "5").lane, Lane::Ego);
    EXPECT_NEAR(car_named(s, "5").state.x, -30.0, 1e-6);
    const OtherCar& truck = car_named(s, "3");
    EXPECT_EQ(truck.lane, Lane::Target);
    EXPECT_NEAR(truck.state.x, -60.0, 1e-6);
    ASSERT_TRUE(truck.size.has_value());
    EXPECT_DOUBLE_EQ(truck.size->length, 12.0);
    EXPECT_EQ(s.roles[1], s.find("3"));  // the follower: nearest behind in the target lane
    EXPECT_EQ(s.roles[2], s.find("4"));
    ASSERT_TRUE(s.origin.has_value());
    EXPECT_TRUE(s.origin->ego_is_planning_problem);
    EXPECT_EQ(s.origin->ego, "100");
    EXPECT_FALSE(s.origin->human_change.has_value());
  }
}

TEST(CommonRoadImport, ARecordedCarsSceneRecordsWhenAndIntoWhichGapItsDriverChanged) {
  ImportSettings settings;
  settings.egos = EgoChoice::RecordedCars;
  settings.cars = {5, 2};
  const ImportReport report = import_text(two_lane_commonroad(0.4), settings);
  // Each car's record lasts 6 s; a scene needs 5 s of it after its start.
  ASSERT_EQ(report.scenes.size(), 2u);
  const Scenario& changer = report.scenes[0].scene;
  EXPECT_EQ(report.scenes[0].name, "TEST_Two-1_1_T-1_car5_t0_left");
  EXPECT_FALSE(changer.find("5").has_value());
  EXPECT_NEAR(car_named(changer, "3").state.x, -30.0, 1e-6);
  EXPECT_NEAR(changer.vehicle.length, 4.4, 1e-12);
  ASSERT_TRUE(changer.origin && changer.origin->human_change);
  const HumanLaneChange& h = *changer.origin->human_change;
  EXPECT_NEAR(h.after, 2.5, 1e-9);
  EXPECT_EQ(h.behind, "3");
  EXPECT_EQ(h.ahead, "4");
  // Car 2 keeps its lane to the end of its record.
  const Scenario& stayer = report.scenes[1].scene;
  ASSERT_TRUE(stayer.origin.has_value());
  EXPECT_FALSE(stayer.origin->ego_is_planning_problem);
  EXPECT_FALSE(stayer.origin->human_change.has_value());
}

TEST(CommonRoadImport, ARecordedTruckKeepsTheClearSpaceOfTheSafeDistances) {
  // The safe distances are stated centre to centre for the default car: as
  // the ego, the 12 m truck must keep the same clear space to every car, not
  // have its extra length eaten out of it.
  ImportSettings settings;
  settings.egos = EgoChoice::RecordedCars;
  settings.cars = {3};
  settings.right = true;
  const ImportReport report = import_text(two_lane_commonroad(), settings);
  ASSERT_EQ(report.scenes.size(), 1u);
  const Scenario& s = report.scenes[0].scene;
  EXPECT_DOUBLE_EQ(s.vehicle.length, 12.0);
  const Config defaults;
  ASSERT_GT(s.car_count(), 0u);
  for (CarIndex c = 0; c < s.car_count(); ++c) {
    for (const auto& [stated, used] :
         {std::pair{defaults.safety.leader, s.safe_distance.leader},
          std::pair{defaults.safety.follower, s.safe_distance.follower},
          std::pair{defaults.safety.target, s.safe_distance.target}}) {
      const double clear_space = s.bumper_gap(c, s.centre_safe_distance(c, used).standstill);
      EXPECT_NEAR(clear_space, stated.standstill - defaults.vehicle.length, 1e-9) << s.cars[c].id;
      EXPECT_DOUBLE_EQ(used.time_headway, stated.time_headway);
    }
  }
}

TEST(CommonRoadImport, ASideWithoutALaneIsSkippedAndCounted) {
  ImportSettings settings;
  settings.right = true;
  const ImportReport report = import_text(two_lane_commonroad(), settings);
  EXPECT_EQ(report.scenes.size(), 1u);
  ASSERT_EQ(report.skipped.size(), 1u);
  EXPECT_EQ(report.skipped.begin()->first, "no lane beside the ego's on the right");
  EXPECT_EQ(report.skipped.begin()->second, 1);
}

TEST(CommonRoadImport, AnImportedSceneReadsBackAsTheSameScene) {
  ImportSettings settings;
  settings.egos = EgoChoice::RecordedCars;
  settings.cars = {5};
  const Scenario s = import_text(two_lane_commonroad(), settings).scenes.at(0).scene;
  const Scenario back = scenario_from_json(scenario_to_json(s), Config{});
  EXPECT_EQ(scenario_to_json(back), scenario_to_json(s));
  ASSERT_TRUE(back.origin && back.origin->human_change);
  EXPECT_EQ(back.origin->human_change->ahead, "4");
}

TEST(CommonRoadImport, TheOriginFieldIsReadAsStrictlyAsTheRest) {
  const Scenario s = import_text(two_lane_commonroad()).scenes.at(0).scene;
  auto j = scenario_to_json(s);
  j["origin"]["human_change"] = {{"after", 1.0}, {"behind", nullptr}, {"ahead", "4"}};
  try {
    (void)scenario_from_json(j, Config{});
    ADD_FAILURE() << "a planning problem with a human lane change was read";
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "origin.human_change");
  }
  j = scenario_to_json(s);
  j["origin"]["driver"] = "x";
  try {
    (void)scenario_from_json(j, Config{});
    ADD_FAILURE() << "an unknown key was read";
  } catch (const InputError& e) {
    EXPECT_EQ(e.field(), "origin.driver");
  }
}

TEST(CommonRoadImport, TheCliWritesTheScenesAndLeavesTheFolderAloneOnABadFile) {
  const lanechange::testing::TempDir dir;
  const std::string good = dir.file("two.xml");
  const std::string bad = dir.file("bad.xml");
  lanechange::testing::write_text(good, two_lane_commonroad());
  lanechange::testing::write_text(bad,
                                  "<commonRoad commonRoadVersion=\"2020a\" timeStepSize=\"0.1\">"
                                  "<lanelet id=\"1\"><leftBound/></lanelet></commonRoad>");
  const std::string out = dir.file("scenes");
  auto r =
      lanechange::testing::run_cli("import-commonroad " + good + " --ego recorded --out " + out);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("the driver changed into the target lane"), std::string::npos)
      << r.output;
  const std::string scene = out + "/TEST_Two-1_1_T-1_car5_t0_left.json";
  ASSERT_TRUE(std::filesystem::exists(scene));
  const std::string before = lanechange::testing::read_text(scene);

  r = lanechange::testing::run_cli("import-commonroad " + good + " " + bad + " --out " + out);
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("<lanelet id=1>/<leftBound>"), std::string::npos) << r.output;
  EXPECT_EQ(lanechange::testing::read_text(scene), before);
  EXPECT_FALSE(std::filesystem::exists(out + "/TEST_Two-1_1_T-1_problem100_left.json"));

  r = lanechange::testing::run_cli("import-commonroad " + good + " --ego 5,x --out " + out);
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("--ego"), std::string::npos) << r.output;
}

TEST(CommonRoadImport, EveryRecordedFileBesideTheRepositoryGivesValidScenes) {
  const std::filesystem::path dir = std::filesystem::path(LANECHANGE_COMMONROAD_DIR) / "recorded";
  if (!std::filesystem::exists(dir)) GTEST_SKIP() << dir << " is not there";
  ImportSettings settings;
  settings.egos = EgoChoice::RecordedCars;
  settings.right = true;
  int scenes = 0;
  int changes = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    const ImportReport report =
        import_scenes(read_recording(entry.path().string()), Config{}, settings);
    for (const ImportedScene& s : report.scenes) {
      EXPECT_NO_THROW(validate_scenario(s.scene)) << s.name;
      changes += s.scene.origin->human_change ? 1 : 0;
    }
    scenes += static_cast<int>(report.scenes.size());
  }
  EXPECT_GT(scenes, 100);
  EXPECT_GT(changes, 0);
}

}  // namespace
}  // namespace lanechange::commonroad
