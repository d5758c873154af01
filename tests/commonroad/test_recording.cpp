// Reading CommonRoad 2020a files: what the reader keeps, and how it refuses
// what it cannot take.
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "commonroad_fixture.hpp"
#include "lanechange/commonroad/recording.hpp"
#include "lanechange/error.hpp"

namespace lanechange::commonroad {
namespace {

using lanechange::testing::two_lane_commonroad;

std::string replaced(std::string text, const std::string& from, const std::string& to) {
  const auto at = text.find(from);
  EXPECT_NE(at, std::string::npos) << from;
  if (at != std::string::npos) text.replace(at, from.size(), to);
  return text;
}

// The message of the InputError that reading `xml` throws, or "" if none.
std::string refusal(const std::string& xml) {
  try {
    (void)recording_from_text(xml, "bad.xml");
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

TEST(CommonRoadRecording, KeepsLaneletsObstaclesAndPlanningProblems) {
  const Recording rec = recording_from_text(two_lane_commonroad(), "two.xml");
  EXPECT_EQ(rec.benchmark_id, "TEST_Two-1_1_T-1");
  EXPECT_DOUBLE_EQ(rec.time_step_size, 0.1);
  ASSERT_EQ(rec.lanelets.size(), 2u);
  const Lanelet* ego_lane = rec.lanelet(10);
  ASSERT_NE(ego_lane, nullptr);
  EXPECT_EQ(ego_lane->adjacent_left, 11);
  EXPECT_FALSE(ego_lane->adjacent_right.has_value());
  EXPECT_EQ(ego_lane->left.size(), ego_lane->right.size());
  EXPECT_DOUBLE_EQ(ego_lane->left.front().y, 1.75);
  ASSERT_EQ(rec.obstacles.size(), 4u);
  const Obstacle& truck = rec.obstacles[1];
  EXPECT_EQ(truck.id, 3);
  EXPECT_EQ(truck.type, "truck");
  EXPECT_DOUBLE_EQ(truck.length, 12.0);
  EXPECT_EQ(truck.states.size(), 61u);
  ASSERT_NE(truck.at(60), nullptr);
  EXPECT_NEAR(truck.at(60)->position.x, -60.0 + 9.0 * 6.0, 1e-9);
  EXPECT_EQ(truck.at(61), nullptr);
  ASSERT_EQ(rec.planning_problems.size(), 1u);
  EXPECT_EQ(rec.planning_problems[0].id, 100);
  EXPECT_DOUBLE_EQ(rec.planning_problems[0].initial.velocity, 10.0);
}

TEST(CommonRoadRecording, RefusesWhatItCannotTakeNamingTheElementAndLine) {
  const std::string good = two_lane_commonroad();
  const std::string not_xml = refusal(good.substr(0, good.size() / 2));
  EXPECT_NE(not_xml.find("bad.xml:"), std::string::npos) << not_xml;
  EXPECT_NE(not_xml.find("not well-formed XML"), std::string::npos) << not_xml;

  const std::string version = refusal(replaced(good, "\"2020a\"", "\"2018b\""));
  EXPECT_NE(version.find("2018b"), std::string::npos) << version;
  EXPECT_NE(version.find("bad.xml:2: <commonRoad>"), std::string::npos) << version;

  const std::string circle =
      refusal(replaced(good, "<rectangle><length>12</length><width>2.5</width></rectangle>",
                       "<circle><radius>6</radius></circle>"));
  EXPECT_NE(circle.find("<dynamicObstacle id=3>/<shape>"), std::string::npos) << circle;
  EXPECT_NE(circle.find("rectangle"), std::string::npos) << circle;

  const std::string number = refusal(replaced(good, "<x>-200</x>", "<x>west</x>"));
  EXPECT_NE(number.find("<lanelet id=10>/<leftBound>/<point>/<x>"), std::string::npos) << number;
  EXPECT_NE(number.find("\"west\" is not a finite number"), std::string::npos) << number;

  const std::string reference =
      refusal(replaced(good, "adjacentLeft ref=\"11\"", "adjacentLeft ref=\"99\""));
  EXPECT_NE(reference.find("lanelet 99"), std::string::npos) << reference;

  const std::string unpaired = refusal(replaced(good, "<point><x>400</x><y>-1.75</y></point>", ""));
  EXPECT_NE(unpaired.find("<lanelet id=10>"), std::string::npos) << unpaired;
  EXPECT_NE(unpaired.find("pair up"), std::string::npos) << unpaired;

  const std::string interval =
      refusal(replaced(good, "<velocity><exact>10</exact>",
                       "<velocity><intervalStart>9</intervalStart><intervalEnd>11</intervalEnd>"));
  EXPECT_NE(interval.find("<planningProblem id=100>/<initialState>/<velocity>"), std::string::npos)
      << interval;

  EXPECT_NE(refusal("<scenario/>").find("not a CommonRoad file"), std::string::npos);
}

TEST(CommonRoadRecording, ReadsEveryRecordedFileBesideTheRepository) {
  const std::filesystem::path dir = std::filesystem::path(LANECHANGE_COMMONROAD_DIR) / "recorded";
  if (!std::filesystem::exists(dir)) GTEST_SKIP() << dir << " is not there";
  int files = 0;
  for (const auto& entry : std::filesystem::directory_iterator(dir)) {
    const Recording rec = read_recording(entry.path().string());
    EXPECT_FALSE(rec.lanelets.empty()) << entry.path();
    EXPECT_FALSE(rec.obstacles.empty()) << entry.path();
    EXPECT_EQ(rec.planning_problems.size(), 1u) << entry.path();
    for (const Obstacle& o : rec.obstacles) {
      EXPECT_GT(o.length, 0.0);
      EXPECT_EQ(o.states.back().time_step - o.states.front().time_step + 1,
                static_cast<int>(o.states.size()));
    }
    ++files;
  }
  EXPECT_EQ(files, 5);
}

}  // namespace
}  // namespace lanechange::commonroad
