#include <gtest/gtest.h>

#include <cmath>
#include <set>
#include <sstream>

#include "data/shard.hpp"
#include "data_helpers.hpp"
#include "lanechange/data/dataset.hpp"
#include "lanechange/error.hpp"
#include "lanechange/expert/formulation.hpp"
#include "lanechange/expert/lane_change_solver.hpp"
#include "lanechange/run/progress.hpp"
#include "lanechange/sampler.hpp"

namespace lanechange {
namespace {

using testing::TempDir;

data::GenerateOptions small_options(const std::filesystem::path& dir, long long count) {
  data::GenerateOptions o;
  o.count = count;
  o.seed = 11;
  o.out_dir = dir.string();
  o.shard_size = 4;
  o.config = make_preset("paper");
  o.config.expert.steps = 8;
  return o;
}

data::GenerateReport run(const data::GenerateOptions& o, int jobs,
                         std::shared_ptr<const expert::LaneChangeSolver> solver = nullptr) {
  data::RunOptions r;
  r.jobs = jobs;
  r.solver_override = std::move(solver);
  return data::generate(o, r);
}

TEST(Generate, OneAndTwoWorkersWriteTheSameFiles) {
  TempDir dir;
  const auto o1 = small_options(dir.path() / "one", 14);
  auto o2 = o1;
  o2.out_dir = (dir.path() / "two").string();
  run(o1, 1);
  run(o2, 2);
  const auto one = testing::deterministic_files(o1.out_dir);
  EXPECT_EQ(one.size(), 8U);  // 4 shards, two deterministic files each
  EXPECT_EQ(one, testing::deterministic_files(o2.out_dir));
  const auto m1 = testing::read_manifest(o1.out_dir);
  const auto m2 = testing::read_manifest(o2.out_dir);
  EXPECT_EQ(m1["status"], "complete");
  EXPECT_EQ(m1["shards"], m2["shards"]);
  EXPECT_EQ(m1["counts"], m2["counts"]);
}

TEST(Generate, EveryIndexOnceWithItsSubSeedAndBehavior) {
  TempDir dir;
  const auto o = small_options(dir.path(), 10);
  run(o, 2);
  const auto t = testing::read_all(dir.path(), "scenarios");
  ASSERT_EQ(t.rows.size(), 10U);
  const ScenarioSampler sampler(o.config, o.seed);
  std::set<std::string> behaviors;
  for (std::size_t i = 0; i < t.rows.size(); ++i) {
    const auto& row = t.rows[i];
    EXPECT_EQ(row[t.column("index")], std::to_string(i));
    EXPECT_EQ(row[t.column("sub_seed")], std::to_string(scenario_seed(o.seed, i)));
    // "all": each index keeps the behavior its own sub-seed draws.
    EXPECT_EQ(row[t.column("behavior")], to_string(sampler.sample(i).behavior));
    behaviors.insert(row[t.column("behavior")]);
  }
  EXPECT_GT(behaviors.size(), 1U);
}

TEST(Generate, FixedBehaviorAppliesToEveryScenario) {
  TempDir dir;
  auto o = small_options(dir.path(), 6);
  o.behavior = Behavior::Idm;
  run(o, 1);
  const auto t = testing::read_all(dir.path(), "scenarios");
  ASSERT_EQ(t.rows.size(), 6U);
  for (const auto& row : t.rows) EXPECT_EQ(row[t.column("behavior")], "idm");
}

TEST(Generate, SolvedScenariosGiveNPlusOneSamplesFromTheirInitialScene) {
  TempDir dir;
  const auto o = small_options(dir.path(), 8);
  run(o, 1);
  const auto scenarios = testing::read_all(dir.path(), "scenarios");
  const auto samples = testing::read_all(dir.path(), "samples");
  std::map<std::string, std::vector<const std::vector<std::string>*>> by_index;
  for (const auto& row : samples.rows) by_index[row[0]].push_back(&row);
  long long solved = 0;
  for (const auto& row : scenarios.rows) {
    const auto& mine = by_index[row[scenarios.column("index")]];
    EXPECT_EQ(std::to_string(mine.size()), row[scenarios.column("samples")]);
    if (mine.empty()) continue;
    ++solved;
    ASSERT_EQ(mine.size(), 9U);  // N + 1 with N = 8
    for (std::size_t k = 0; k < mine.size(); ++k) {
      const auto& s = *mine[k];
      EXPECT_EQ(s[samples.column("k")], std::to_string(k));
      EXPECT_EQ(s[samples.column("label")], row[scenarios.column("label")]);
      for (const char* c : {"ego_x0", "ego_v0", "leader_x0", "follower_v0", "target_a0"}) {
        EXPECT_EQ(s[samples.column(c)], row[scenarios.column(c)]) << c;
      }
    }
    // The current state at k = 0 is the initial one.
    EXPECT_EQ(std::stod((*mine[0])[samples.column("v")]),
              std::stod(row[scenarios.column("ego_v0")]));
  }
  EXPECT_GT(solved, 0);
}

// The traffic columns at node k are the cars as the plan saw them: at k = 0
// the initial scene; for constant speed in the paper's traffic, x0 + v0 t. The lane mode says where
// the body is (footprint rule): wholly in the ego lane (0) or the target lane (2).
TEST(Generate, SamplesCarryTheTrafficAndTheLaneModePerNode) {
  TempDir dir;
  auto o = small_options(dir.path(), 8);
  o.behavior = Behavior::ConstantSpeed;
  o.config.traffic = paper_traffic();
  run(o, 1);
  const auto samples = testing::read_all(dir.path(), "samples");
  ASSERT_FALSE(samples.rows.empty());
  std::set<std::string> modes_seen;
  const double half_width = o.config.vehicle.width / 2.0;
  const double line = o.config.lane_width / 2.0;
  for (const auto& s : samples.rows) {
    auto value = [&](const char* c) { return std::stod(s[samples.column(c)]); };
    const double t = value("t");
    for (const char* car : {"leader", "follower", "target"}) {
      const std::string name(car);
      EXPECT_NEAR(value((name + "_x").c_str()),
                  value((name + "_x0").c_str()) + value((name + "_v0").c_str()) * t, 1e-9);
      EXPECT_DOUBLE_EQ(value((name + "_v").c_str()), value((name + "_v0").c_str()));
    }
    const std::string mode = s[samples.column("lane_mode")];
    modes_seen.insert(mode);
    if (s[samples.column("k")] == "0") {
      EXPECT_EQ(mode, "");
    }
    // The mode is the planned (linearised) one; the re-simulated y may differ
    // from it by centimetres.
    if (mode == "0") {
      EXPECT_LT(value("y") + half_width, line + 0.05);
    }
    if (mode == "2") {
      EXPECT_GT(value("y") - half_width, line - 0.05);
    }
  }
  EXPECT_TRUE(modes_seen.count("0") > 0 || modes_seen.count("2") > 0);
}

// dataset-info's "on the lane line" count, recomputed here from the samples:
// the longest run of consecutive nodes with the centre within 0.3 m of the
// line, measured from its first node's time to its last's, above 1 s.
TEST(Generate, SummaryCountsPlansThatRideTheLaneLine) {
  TempDir dir;
  auto o = small_options(dir.path(), 16);
  o.config.expert.steps = 50;
  o.config.expert.lane_rule = LaneRule::EitherOr;  // the rule that rides the line
  run(o, 2);
  const auto samples = testing::read_all(dir.path(), "samples");
  std::map<std::string, std::pair<std::string, double>> longest;  // index -> label, seconds
  std::map<std::string, double> start;
  const double line = o.config.lane_width / 2.0;
  for (const auto& s : samples.rows) {
    const std::string index = s[samples.column("index")];
    const double t = std::stod(s[samples.column("t")]);
    auto& entry = longest[index];
    entry.first = s[samples.column("label")];
    if (std::abs(std::stod(s[samples.column("y")]) - line) > 0.3) {
      start.erase(index);
      continue;
    }
    if (!start.count(index)) start[index] = t;
    entry.second = std::max(entry.second, t - start[index]);
  }
  long long reached = 0;
  long long riding = 0;
  for (const auto& [index, entry] : longest) {
    if (entry.first == "failure") continue;
    ++reached;
    riding += entry.second > 1.0 ? 1 : 0;
  }
  const data::DatasetSummary summary = data::summarize_dataset(dir.path().string());
  EXPECT_EQ(summary.reached, reached);
  EXPECT_EQ(summary.riding_line, riding);
  auto count_of = [&summary](const char* label) {
    const auto it = summary.by_label.find(label);
    return it == summary.by_label.end() ? 0LL : it->second;
  };
  EXPECT_EQ(summary.reached, count_of("well_posed") + count_of("ill_posed"));
  EXPECT_GT(reached, 0);
}

// Throws for fast egos, so a run holds both kinds of rows.
class ThrowingSolver final : public expert::LaneChangeSolver {
 public:
  [[nodiscard]] std::string_view name() const override { return "throwing"; }
  [[nodiscard]] expert::LaneChangeSolution solve(const expert::LaneChangeQp& qp,
                                                 const expert::MiqpSettings& settings,
                                                 const expert::SolveHints& hints) const override {
    if (qp.initial_state[expert::kV] > 8.0) throw std::runtime_error("boom, with a comma");
    return fast_.solve(qp, settings, hints);
  }

 private:
  expert::FastLaneChangeSolver fast_;
};

TEST(Generate, AThrowingSolverGivesFailureRowsAndTheRunGoesOn) {
  TempDir dir;
  const auto o = small_options(dir.path(), 12);
  run(o, 2, std::make_shared<ThrowingSolver>());
  const auto t = testing::read_all(dir.path(), "scenarios");
  ASSERT_EQ(t.rows.size(), 12U);
  int thrown = 0;
  for (const auto& row : t.rows) {
    const bool fast = std::stod(row[t.column("ego_v0")]) > 8.0;
    EXPECT_EQ(row[t.column("status")] == "exception", fast);
    if (!fast) continue;
    ++thrown;
    EXPECT_EQ(row[t.column("label")], "failure");
    EXPECT_NE(row[t.column("reason")].find("boom, with a comma"), std::string::npos);
  }
  EXPECT_GT(thrown, 0);
  EXPECT_LT(thrown, 12);
  EXPECT_EQ(testing::read_manifest(dir.path())["counts"]["by_status"]["exception"], thrown);
}

TEST(Generate, MismatchedParametersAreRefusedAndNothingChanges) {
  TempDir dir;
  const auto o = small_options(dir.path(), 5);
  run(o, 1);
  const auto before = testing::all_files(dir.path());
  auto other_seed = o;
  other_seed.seed = 12;
  auto other_count = o;
  other_count.count = 6;
  auto other_config = o;
  other_config.config.expert.steps = 9;
  for (const auto& bad : {other_seed, other_count, other_config}) {
    EXPECT_THROW(run(bad, 1), InputError);
  }
  EXPECT_EQ(testing::all_files(dir.path()), before);
  // The same parameters find a complete data set and leave it alone.
  EXPECT_TRUE(run(o, 1).already_complete);
  EXPECT_EQ(testing::all_files(dir.path()), before);
}

// The data set names the only open gap and labels every gap around the ego
// on its own.
TEST(Generate, GapLabelsNameTheOnlyOpenGap) {
  const Scenario s = testing::only_the_gap_ahead_of_the_target();
  const expert::ExpertPlanner planner(Config{}, std::make_shared<expert::FastLaneChangeSolver>());
  data::PlanOutcome outcome = data::plan_outcome(planner, s, 60.0);
  ASSERT_EQ(outcome.label, Label::WellPosed) << outcome.reason;
  // Both cars are behind the ego: the gap beside it is the one ahead of the target.
  EXPECT_EQ(outcome.gap_slot, expert::kGapSlotBeside);
  EXPECT_EQ(outcome.gap_behind, s.cars[car_of(Role::Target)].id);
  EXPECT_EQ(outcome.gap_ahead, "");
  data::label_gaps(planner, s, 60.0, outcome);
  const auto& labels = outcome.slot_labels;
  EXPECT_EQ(labels[expert::kGapSlotBeside], Label::WellPosed);
  EXPECT_EQ(labels[expert::kGapSlotBeside - 1], Label::Failure);  // between the two
  EXPECT_EQ(labels[expert::kGapSlotBeside - 2], Label::Failure);  // behind the follower
  EXPECT_FALSE(labels[expert::kGapSlotBeside + 1].has_value());   // the lane has no more
  // The row carries the gap and the labels under their columns.
  const std::string row = data::scenario_rows(0, 1, s, outcome).scenarios;
  const auto columns = data::scenario_columns();
  const auto at = [&columns](const std::string& name) {
    return std::find(columns.begin(), columns.end(), name) - columns.begin();
  };
  std::vector<std::string> fields;
  std::stringstream line(row.substr(0, row.size() - 1));
  for (std::string f; std::getline(line, f, ',');) fields.push_back(f);
  fields.resize(columns.size());
  EXPECT_EQ(fields[at("gap_slot")], "0");  // the slot beside the ego
  EXPECT_EQ(fields[at("gap_0_label")], "well_posed");
  EXPECT_EQ(fields[at("gap_m1_label")], "failure");
  EXPECT_EQ(fields[at("gap_p1_label")], "");
  EXPECT_EQ(std::stod(fields[at("gap_0_behind_dx")]), s.target().x - s.ego.x);
}

// Each sample sees the plan's own gap from where the ego is at its node:
// the car behind it by the prediction, the open side far ahead, the leader.
TEST(Generate, SamplesSeeThePlansGapFromTheEgo) {
  const Scenario s = testing::only_the_gap_ahead_of_the_target();
  const expert::ExpertPlanner planner(Config{}, std::make_shared<expert::FastLaneChangeSolver>());
  const data::PlanOutcome outcome = data::plan_outcome(planner, s, 60.0);
  ASSERT_EQ(outcome.label, Label::WellPosed) << outcome.reason;
  const testing::Table samples = [&] {
    testing::Table t;
    t.header = data::sample_columns();
    std::stringstream lines(data::scenario_rows(0, 1, s, outcome).samples);
    for (std::string line; std::getline(lines, line);) {
      t.rows.push_back(testing::split_line(line, t.header.size()));
    }
    return t;
  }();
  const Trajectory& plan = outcome.trajectory;
  ASSERT_EQ(samples.rows.size(), static_cast<std::size_t>(plan.nodes()));
  const CarTrack& behind = plan.others.car(car_of(Role::Target));
  const CarTrack& leader = plan.others.car(car_of(Role::Leader));
  for (const std::size_t k : {std::size_t{0}, samples.rows.size() - 1}) {
    const auto& row = samples.rows[k];
    const auto value = [&](const char* name) { return std::stod(row[samples.column(name)]); };
    const EgoState& ego = plan.ego[k];
    EXPECT_DOUBLE_EQ(value("gap_behind_dx"), behind.x[k] - ego.x) << "node " << k;
    EXPECT_DOUBLE_EQ(value("gap_behind_dv"), behind.v[k] - ego.v) << "node " << k;
    EXPECT_EQ(value("gap_ahead_dx"), expert::kOpenGapDistance);
    EXPECT_DOUBLE_EQ(value("leader_dx"), leader.x[k] - ego.x) << "node " << k;
  }
}

TEST(Progress, LogLineHasCountsRateAndEta) {
  const std::string line = run::format_progress(50, 200, 10.0, false);
  EXPECT_NE(line.find("50/200"), std::string::npos) << line;
  EXPECT_NE(line.find("5.0/s"), std::string::npos) << line;
  EXPECT_NE(line.find("ETA 0:00:30"), std::string::npos) << line;
  EXPECT_EQ(line.find('['), std::string::npos) << line;
}

TEST(Progress, TerminalBarFillsWithTheFraction) {
  const std::string line = run::format_progress(100, 200, 4.0, true);
  EXPECT_EQ(std::count(line.begin(), line.end(), '#'), 15) << line;
  EXPECT_NE(line.find("25.0/s"), std::string::npos) << line;
}

TEST(Progress, LogGetsPlainLinesAndAFinalOne) {
  std::ostringstream out;
  run::Progress p(&out, false, 3, 0.0);
  for (int i = 0; i < 3; ++i) p.add(1);
  p.finish();
  const std::string text = out.str();
  EXPECT_EQ(std::count(text.begin(), text.end(), '\n'), 4) << text;
  EXPECT_EQ(text.find('\r'), std::string::npos);
  EXPECT_NE(text.find("3/3 scenarios"), std::string::npos) << text;
}

}  // namespace
}  // namespace lanechange
