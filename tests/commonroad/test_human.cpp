// Planners beside the recorded drivers (evaluate's human.csv).
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include "commonroad_fixture.hpp"
#include "lanechange/commonroad/import.hpp"
#include "lanechange/sim/evaluate.hpp"
#include "test_helpers.hpp"

namespace lanechange::sim {
namespace {

RolloutRow row(long long index, const std::string& planner, double time_to_lane_line,
               const std::string& behind, const std::string& ahead) {
  RolloutRow r;
  r.index = index;
  r.planner = planner;
  r.outcome = std::isfinite(time_to_lane_line) ? "well_posed" : "aborted";
  r.time_to_lane_line = time_to_lane_line;
  r.gap_behind = behind;
  r.gap_ahead = ahead;
  return r;
}

TEST(HumanComparison, CountsChangesSameGapsAndTheTimeAgainstTheDriver) {
  std::vector<Scenario> scenes(3);
  scenes[0].origin = SceneOrigin{"rec", 0.0, "5", false, HumanLaneChange{3.0, "a", "b"}};
  scenes[1].origin = SceneOrigin{"rec", 2.0, "5", false, HumanLaneChange{1.0, std::nullopt, "c"}};
  scenes[2].origin = SceneOrigin{"rec", 4.0, "6", false, std::nullopt};  // the driver stayed
  const std::vector<RolloutRow> rows = {row(0, "p", 2.0, "a", "b"), row(1, "p", 4.0, "d", "c"),
                                        row(2, "p", 1.0, "", ""), row(0, "q", NAN, "", ""),
                                        row(1, "q", 1.5, "", "c")};
  const auto c = compare_with_humans(scenes, rows, {"p", "q"});
  ASSERT_EQ(c.size(), 2u);
  EXPECT_EQ(c[0].scenes, 2);
  EXPECT_EQ(c[0].changed, 2);
  EXPECT_EQ(c[0].same_gap, 1);
  EXPECT_EQ(c[0].succeeded, 2);
  // Differences -1 and +3: the lower median.
  EXPECT_DOUBLE_EQ(c[0].time_difference_p50, -1.0);
  EXPECT_EQ(c[1].scenes, 2);
  EXPECT_EQ(c[1].changed, 1);
  EXPECT_EQ(c[1].same_gap, 1);
  EXPECT_DOUBLE_EQ(c[1].time_difference_p50, 0.5);
}

TEST(HumanComparison, EvaluateWritesItForImportedScenes) {
  const lanechange::testing::TempDir dir;
  const std::string xml = dir.file("two.xml");
  lanechange::testing::write_text(xml, lanechange::testing::two_lane_commonroad());
  const std::string scenes = dir.file("scenes");
  auto r = lanechange::testing::run_cli("import-commonroad " + xml + " --ego 5 --out " + scenes);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const std::string out = dir.file("eval");
  r = lanechange::testing::run_cli("evaluate --scenarios " + scenes +
                                   " --planner keep-lane --jobs 1 --out " + out);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const std::string text = lanechange::testing::read_text(out + "/human.csv");
  EXPECT_EQ(text.substr(0, text.find('\n')),
            "planner,human_changes,changed,changed_rate,same_gap,same_gap_rate,success_rate,"
            "time_difference_p50");
  EXPECT_EQ(text.substr(text.find('\n') + 1, 15), "keep-lane,1,0,0");
}

}  // namespace
}  // namespace lanechange::sim
