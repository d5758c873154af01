#include <gtest/gtest.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <thread>

#include "lanechange/error.hpp"
#include "lanechange/run/quantile.hpp"
#include "lanechange/sampler.hpp"
#include "lanechange/scenario.hpp"
#include "lanechange/sim/evaluate.hpp"
#include "test_helpers.hpp"

namespace lanechange {
namespace {

std::vector<std::string> lines_of(const std::string& path) {
  std::ifstream in(path);
  std::vector<std::string> out;
  for (std::string line; std::getline(in, line);) out.push_back(line);
  return out;
}

// The columns that do not depend on timing: everything but the step times.
std::string without_times(const std::string& row) {
  std::vector<std::string> cells;
  std::stringstream in(row);
  for (std::string c; std::getline(in, c, ',');) cells.push_back(c);
  const auto columns = sim::rollout_columns();
  const auto at = [&columns](const char* name) {
    return static_cast<std::size_t>(std::find(columns.begin(), columns.end(), name) -
                                    columns.begin());
  };
  const std::size_t first = at("median_step_ms");
  const std::size_t last = at("max_step_ms");
  std::string out;
  for (std::size_t i = 0; i < cells.size(); ++i) {
    if (i >= first && i <= last) continue;  // the step times
    out += cells[i] + "|";
  }
  return out;
}

sim::EvaluateOptions small(const std::string& dir) {
  sim::EvaluateOptions o;
  o.count = 7;
  o.seed = 4;
  o.planners = {"keep-lane", "miqp"};
  o.out_dir = dir;
  o.shard_size = 3;
  o.duration = 2.0;
  o.config.expert.steps = 20;
  // An overrun hands a step to the fallback, so on a loaded machine the
  // budget makes rollouts differ between runs; a generous one does not bind.
  o.config.closed_loop.step_budget_ms = 1e6;
  return o;
}

TEST(Evaluate, WritesARowPerScenarioAndPlannerAndASummary) {
  testing::TempDir dir;
  const auto o = small(dir.file("ev"));
  const sim::EvaluateReport r = sim::evaluate(o, {2, nullptr, false});
  EXPECT_EQ(r.shards_total, 3);
  EXPECT_EQ(r.rollouts, 14);
  const auto rows = lines_of(dir.file("ev/rollouts.csv"));
  ASSERT_EQ(rows.size(), 15U);
  EXPECT_EQ(rows[0].rfind("index,behavior,planner,outcome", 0), 0U);
  const auto summary = lines_of(dir.file("ev/summary.csv"));
  // A header, then per planner "all" and each behavior present.
  ASSERT_GE(summary.size(), 3U);
  long long keep_lane_all = 0;
  for (const auto& line : summary) {
    if (line.rfind("keep-lane,all,7,0,", 0) == 0) ++keep_lane_all;  // never succeeds
  }
  EXPECT_EQ(keep_lane_all, 1);
}

TEST(Evaluate, AKilledRunResumesToTheSameRowsAndOtherParametersAreRefused) {
  testing::TempDir dir;
  const auto o = small(dir.file("ev"));
  (void)sim::evaluate(o, {2, nullptr, false});
  const auto full = lines_of(dir.file("ev/rollouts.csv"));
  // What a kill leaves: a shard missing and the manifest not complete.
  std::filesystem::remove(dir.file("ev/rollouts-00001.csv"));
  std::filesystem::remove(dir.file("ev/rollouts.csv"));
  auto manifest = nlohmann::json::parse(testing::read_text(dir.file("ev/evaluation.json")));
  manifest["status"] = "incomplete";
  testing::write_text(dir.file("ev/evaluation.json"), manifest.dump());
  const sim::EvaluateReport r = sim::evaluate(o, {1, nullptr, false});
  EXPECT_EQ(r.shards_skipped, 2);
  EXPECT_EQ(r.rollouts, 6);
  const auto resumed = lines_of(dir.file("ev/rollouts.csv"));
  ASSERT_EQ(resumed.size(), full.size());
  for (std::size_t i = 0; i < full.size(); ++i) {
    EXPECT_EQ(without_times(resumed[i]), without_times(full[i])) << i;
  }
  auto other = o;
  other.seed = 5;
  EXPECT_THROW((void)sim::evaluate(other, {1, nullptr, false}), InputError);
  EXPECT_EQ(lines_of(dir.file("ev/rollouts.csv")), resumed);  // untouched
}

TEST(Evaluate, RolloutsReadBackAsWrittenAndAForeignFileIsNamed) {
  testing::TempDir dir;
  const auto o = small(dir.file("ev"));
  (void)sim::evaluate(o, {2, nullptr, false});
  const auto rows = sim::read_rollouts(dir.file("ev/rollouts.csv"));
  ASSERT_EQ(rows.size() + 1, lines_of(dir.file("ev/rollouts.csv")).size());
  for (const auto& row : rows) {
    EXPECT_LE(row.median_step_ms, row.p99_step_ms);
    EXPECT_LE(row.p99_step_ms, row.max_step_ms);
    EXPECT_FALSE(row.reason.empty());
    if (row.planner == "keep-lane") {
      EXPECT_EQ(row.outcome, "aborted");
      EXPECT_EQ(row.target_lane_slot, "");  // never left its lane
    }
    // The expert's problem (Eq. 1) admits only the follower-target gap.
    if (row.planner == "miqp" && row.success()) {
      EXPECT_EQ(row.target_lane_slot, "follower_target_gap") << row.index;
      EXPECT_EQ(row.gap_behind, "follower") << row.index;
      EXPECT_EQ(row.gap_ahead, "target") << row.index;
    }
  }
  testing::write_text(dir.file("bad.csv"), "index,behavior\n1,idm\n");
  try {
    (void)sim::read_rollouts(dir.file("bad.csv"));
    ADD_FAILURE() << "a foreign file was read";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("bad.csv"), std::string::npos);
  }
  auto text = testing::read_text(dir.file("ev/rollouts.csv"));
  testing::write_text(dir.file("short.csv"), text + "7,idm,miqp\n");
  EXPECT_THROW((void)sim::read_rollouts(dir.file("short.csv")), InputError);
  // A first row whose target_lane_slot (the cell before the gap's two cars and
  // the reason) is foreign.
  const auto lines = lines_of(dir.file("ev/rollouts.csv"));
  std::size_t slot_start = 0;
  for (std::size_t commas = 0; commas < sim::rollout_columns().size() - 4; ++commas) {
    slot_start = lines[1].find(',', slot_start) + 1;
  }
  const std::string foreign =
      lines[1].substr(0, slot_start) + "sideways" + lines[1].substr(lines[1].find(',', slot_start));
  testing::write_text(dir.file("slot.csv"), lines[0] + "\n" + foreign + "\n");
  EXPECT_THROW((void)sim::read_rollouts(dir.file("slot.csv")), InputError);
}

TEST(NearestRank, IsAnElementOfTheFiniteValuesAtItsRank) {
  const std::vector<double> v = {5, NAN, 1, 4, INFINITY, 2, 3};
  EXPECT_EQ(run::nearest_rank(v, 0.5), 3);  // rank ceil(0.5 * 5) = 3 of 1..5
  EXPECT_EQ(run::nearest_rank(v, 1.0), 5);
  EXPECT_EQ(run::nearest_rank(v, 0.01), 1);
  EXPECT_EQ(run::nearest_rank(v, 0.99), 5);
  EXPECT_TRUE(std::isnan(run::nearest_rank({NAN}, 0.5)));
  EXPECT_TRUE(std::isnan(run::nearest_rank({}, 0.5)));
}

// The outcome of a row: every column but the step times and the overrun
// count, which measure the machine.
std::string outcome_columns(const std::string& row) {
  std::string kept = without_times(row);
  const auto columns = sim::rollout_columns();
  const auto overruns = static_cast<std::size_t>(
      std::find(columns.begin(), columns.end(), "overruns") - columns.begin());
  std::size_t start = 0;
  for (std::size_t i = 0; i < overruns; ++i) start = kept.find('|', start) + 1;
  return kept.erase(start, kept.find('|', start) + 1 - start);
}

// Under the deadline of work (the default) the expert stops at the same point
// however loaded the machine is: one job, and two jobs beside threads that
// keep every core busy, give the same outcomes. The budget is cut so that it
// binds in most re-plans; a run without it shows that it did.
TEST(Evaluate, UnderTheDeadlineOfWorkLoadAndJobsChangeNoOutcome) {
  testing::TempDir dir;
  auto options = [&dir](const std::string& name, bool budgets) {
    auto o = small(dir.file(name));
    o.count = 4;
    o.planners = {"miqp"};
    o.config.closed_loop.deadline = Deadline::Work;
    o.config.closed_loop.step_budget_ms = Config{}.closed_loop.step_budget_ms;
    o.config.closed_loop.step_qp_iterations = budgets ? 60 : 1000000;
    return o;
  };
  (void)sim::evaluate(options("one", true), {1, nullptr, false});
  std::atomic<bool> busy = true;
  std::vector<std::thread> load;
  for (unsigned t = 0; t < std::max(2U, std::thread::hardware_concurrency()); ++t) {
    load.emplace_back([&busy] {
      volatile double x = 1.0;
      while (busy.load(std::memory_order_relaxed)) x = x * 1.0000001 + 1e-9;
    });
  }
  (void)sim::evaluate(options("two", true), {2, nullptr, false});
  busy = false;
  for (std::thread& t : load) t.join();
  (void)sim::evaluate(options("unbounded", false), {2, nullptr, false});
  const auto one = lines_of(dir.file("one/rollouts.csv"));
  const auto two = lines_of(dir.file("two/rollouts.csv"));
  const auto unbounded = lines_of(dir.file("unbounded/rollouts.csv"));
  ASSERT_EQ(one.size(), 5U);
  ASSERT_EQ(two.size(), one.size());
  ASSERT_EQ(unbounded.size(), one.size());
  int moved_by_budgets = 0;
  for (std::size_t i = 1; i < one.size(); ++i) {
    EXPECT_EQ(outcome_columns(two[i]), outcome_columns(one[i])) << "row " << i;
    moved_by_budgets += outcome_columns(unbounded[i]) != outcome_columns(one[i]) ? 1 : 0;
  }
  EXPECT_GT(moved_by_budgets, 0) << "the budgets never bound: the test shows nothing";
}

TEST(Evaluate, MpiRanksWriteWhatThreadsWrite) {
#ifndef LANECHANGE_HAVE_MPI
  GTEST_SKIP() << "built without MPI";
#endif
  if (!testing::mpirun_available()) GTEST_SKIP() << "no mpirun";
  testing::TempDir dir;
  // A step budget that never binds: an overrun depends on the machine's load.
  const std::string run = "--config " + testing::untimed_config_file(dir) +
                          " evaluate --count 6 --seed 3 --shard-size 2 --planner keep-lane,miqp "
                          "--duration 3 --out ";
  ASSERT_EQ(testing::run_cli(run + dir.file("threads") + " --jobs 2").exit_code, 0);
  const auto ranks_run = testing::run_cli_on_ranks(2, run + dir.file("ranks") + " --jobs 1");
  ASSERT_EQ(ranks_run.exit_code, 0) << ranks_run.output;
  const auto threads = lines_of(dir.file("threads/rollouts.csv"));
  const auto ranks = lines_of(dir.file("ranks/rollouts.csv"));
  ASSERT_EQ(ranks.size(), threads.size());
  EXPECT_EQ(threads.size(), 13U);
  for (std::size_t i = 0; i < threads.size(); ++i) {
    EXPECT_EQ(without_times(ranks[i]), without_times(threads[i])) << i;
  }
  EXPECT_NE(testing::read_text(dir.file("ranks/evaluation.json")).find("complete"),
            std::string::npos);
}

// The sampled scenes written as files and rolled out from the folder give
// the sampled evaluation's rows; scenes.csv names each index's file, and a
// resume with a changed file is refused.
TEST(Evaluate, AFolderOfScenesRollsOutLikeTheSampledScenes) {
  testing::TempDir dir;
  const auto sampled = small(dir.file("sampled"));
  (void)sim::evaluate(sampled, {2, nullptr, false});
  std::filesystem::create_directories(dir.file("scenes"));
  const ScenarioSampler sampler(sampled.config, sampled.seed);
  for (int i = 0; i < sampled.count; ++i) {
    save_scenario(sampler.sample(static_cast<std::uint64_t>(i)),
                  dir.file("scenes/scene_" + std::to_string(i) + ".json"));
  }
  testing::write_text(dir.file("scenes/notes.txt"), "not a scene");
  auto from_files = small(dir.file("files"));
  from_files.count = 0;
  from_files.scenarios_dir = dir.file("scenes");
  const sim::EvaluateReport r = sim::evaluate(from_files, {2, nullptr, false});
  EXPECT_EQ(r.rollouts, 2 * sampled.count);
  const auto expected = lines_of(dir.file("sampled/rollouts.csv"));
  const auto got = lines_of(dir.file("files/rollouts.csv"));
  ASSERT_EQ(got.size(), expected.size());
  for (std::size_t i = 0; i < got.size(); ++i) {
    EXPECT_EQ(without_times(got[i]), without_times(expected[i])) << i;
  }
  const auto index = lines_of(dir.file("files/scenes.csv"));
  ASSERT_EQ(index.size(), 1U + static_cast<std::size_t>(sampled.count));
  EXPECT_EQ(index[1], "0,scene_0.json");

  testing::write_text(dir.file("scenes/scene_3.json"), scenario_to_json(sampler.sample(99)).dump());
  EXPECT_THROW((void)sim::evaluate(from_files, {1, nullptr, false}), InputError);
}

TEST(Evaluate, CliRefusesABadSceneFolderAndWritesNothing) {
  testing::TempDir dir;
  std::filesystem::create_directories(dir.file("scenes"));
  const auto empty = testing::run_cli("evaluate --scenarios " + dir.file("scenes") +
                                      " --planner keep-lane --out " + dir.file("a"));
  EXPECT_EQ(empty.exit_code, 2) << empty.output;
  testing::write_text(dir.file("scenes/broken.json"), "{\"format\": \"lanechange.scenario/1\"");
  const auto broken = testing::run_cli("evaluate --scenarios " + dir.file("scenes") +
                                       " --planner keep-lane --out " + dir.file("b"));
  EXPECT_EQ(broken.exit_code, 2) << broken.output;
  EXPECT_NE(broken.output.find("broken.json"), std::string::npos) << broken.output;
  EXPECT_FALSE(std::filesystem::exists(dir.file("b")));
  const auto both = testing::run_cli("evaluate --scenarios " + dir.file("scenes") +
                                     " --count 3 --seed 1 --out " + dir.file("c"));
  EXPECT_EQ(both.exit_code, 2) << both.output;
  const auto neither = testing::run_cli("evaluate --planner keep-lane --out " + dir.file("d"));
  EXPECT_EQ(neither.exit_code, 2) << neither.output;
}

TEST(Evaluate, CliRefusesBadInputWithTwo) {
  testing::TempDir dir;
  EXPECT_EQ(testing::run_cli("evaluate --count 2 --seed 1 --planner nobody --out " + dir.file("a"))
                .exit_code,
            2);
  EXPECT_EQ(testing::run_cli("evaluate --count 0 --seed 1 --out " + dir.file("b")).exit_code, 2);
  EXPECT_EQ(testing::run_cli("evaluate --count 2 --seed 1 --behavior fast --out " + dir.file("c"))
                .exit_code,
            2);
}

}  // namespace
}  // namespace lanechange
