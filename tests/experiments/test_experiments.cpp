// The experiments command at a tiny scale: every table and figure is made
// from the run's own files, a rerun reuses the finished stages, and a
// changed input runs its stage again.
#include <gtest/gtest.h>

#include <filesystem>
#include <nlohmann/json.hpp>

#include "lanechange/baselines/baselines.hpp"
#include "lanechange/dagger/dagger.hpp"
#include "lanechange/error.hpp"
#include "lanechange/experiments/experiments.hpp"
#include "test_helpers.hpp"

namespace lanechange {
namespace {

namespace fs = std::filesystem;

experiments::ExperimentOptions tiny(const std::string& dir) {
  experiments::ExperimentOptions o;
  o.out_dir = dir;
  o.scale = experiments::Scale::Tiny;
  o.eval_count = 1;
  o.jobs = 2;
  o.config = testing::untimed_config();
  return o;
}

bool reused(const experiments::ExperimentReport& r, const std::string& stage) {
  for (const auto& s : r.stages) {
    if (s.name == stage) return s.reused;
  }
  ADD_FAILURE() << "no stage " << stage;
  return false;
}

TEST(Experiments, ATinyRunWritesEveryTableAndFigureAndARerunReusesItsStages) {
  testing::TempDir dir;
  const auto o = tiny(dir.file("run"));
  const auto first = experiments::run_experiments(o);
  const std::string md = testing::read_text(first.report_md);
  for (const char* section :
       {"Table I", "Table II: planners in closed loop (footprint", "Table III", "Generalization",
        "either_or lane rule", "Table II: planners in closed loop (the paper's formulation)",
        "Table II: planners in closed loop (dense traffic)", "rollouts show two other cars",
        "Example rollouts", "85.171%", "93.1%", "DAgger for the action network",
        "fewer take-overs per rollout with every round",
        "the take-overs from states the network drove to", "taken over at the start",
        "SUMO traffic", "Table II: planners in closed loop (SUMO, highway_15)",
        "Table II: planners in closed loop (SUMO, highway_40)"}) {
    EXPECT_NE(md.find(section), std::string::npos) << section;
  }
  // Every planner has a row in each Table II (the default, the paper's and
  // the dense one), and every row has a number of scenes; but the oracle, a
  // diagnostic an exact plan per look-ahead step slows.
  for (const auto& planner : baselines::planner_names()) {
    if (planner == "mlp-miqp-oracle") continue;
    const std::string row = "| " + planner + " | 3 |";
    int tables = 0;
    for (auto at = md.find(row); at != std::string::npos; at = md.find(row, at + 1)) ++tables;
    EXPECT_GE(tables, 3) << planner;
  }
  // The dense scenes were drawn with a platoon in the target lane, and the
  // paper's with its own formulation.
  const auto parameters = [&](const std::string& run) {
    return nlohmann::json::parse(
               testing::read_text(o.out_dir + "/eval/" + run + "/idm/evaluation.json"))
        .at("parameters")
        .at("config");
  };
  EXPECT_EQ(parameters("dense")["sampler"]["target_lane_cars"], nlohmann::json({4.0, 10.0}));
  EXPECT_EQ(parameters("footprint")["sampler"]["target_lane_cars"], nlohmann::json({0.0, 0.0}));
  EXPECT_EQ(parameters("paper")["expert"]["gap"], "fixed");
  EXPECT_EQ(parameters("paper")["traffic"]["followers_react"], false);
  // Every picture the report names exists, and the HTML embeds it. (No
  // std::regex: GCC 12 warns inside it under the sanitizers.)
  int pictures = 0;
  for (auto at = md.find("](figures/"); at != std::string::npos;
       at = md.find("](figures/", at + 1)) {
    const auto end = md.find(')', at);
    const std::string path = md.substr(at + 2, end - at - 2);
    EXPECT_TRUE(fs::exists(fs::path(o.out_dir) / path)) << path;
    ++pictures;
  }
  EXPECT_GE(pictures, 5);  // confusion matrix, success bars, step times, DAgger, an example
  // DAgger's round 0 is the experiments' model with an ensemble whose first
  // network is the model's one, and its round 1 a data set of labels.
  EXPECT_TRUE(fs::exists(fs::path(o.out_dir) / "figures/dagger.png"));
  EXPECT_TRUE(fs::exists(fs::path(o.out_dir) / "dagger/rounds/model-1/model.json"));
  const std::string round0 = o.out_dir + "/dagger/rounds/model-0";
  const auto json_in = [](const std::string& path) {
    return nlohmann::json::parse(testing::read_text(path));
  };
  EXPECT_EQ(json_in(round0 + "/model.json")["classifiers"],
            json_in(o.out_dir + "/model/model.json")["classifiers"]);
  const auto base_scores = json_in(o.out_dir + "/model/metrics.json")["classifiers"];
  for (const auto& [name, scores] : json_in(round0 + "/metrics.json")["classifiers"].items()) {
    EXPECT_EQ(scores["confusion_counts"], base_scores[name]["confusion_counts"]) << name;
  }
  EXPECT_EQ(testing::read_text(round0 + "/strategy.json"),
            testing::read_text(o.out_dir + "/model/strategy.json"));
  const auto members = json_in(round0 + "/policy.json")["average_of"];
  ASSERT_EQ(members.size(), 3U);
  EXPECT_EQ(members[0], json_in(o.out_dir + "/model/policy.json"));
  // Round 1's policy is the mean of both rounds' ensembles: round 0's
  // networks first, then its own three.
  const auto round1 = json_in(o.out_dir + "/dagger/rounds/model-1/policy.json")["average_of"];
  ASSERT_EQ(round1.size(), 6U);
  for (std::size_t k = 0; k < members.size(); ++k) EXPECT_EQ(round1[k], members[k]) << k;
  EXPECT_NE(round1[3], members[0]);
  const auto rows = dagger::read_report(o.out_dir + "/dagger/rounds");
  ASSERT_EQ(rows.rounds.size(), 2U);
  EXPECT_EQ(rows.rounds[1].round, 1);
  EXPECT_EQ(rows.expert.planner, "miqp");
  EXPECT_EQ(rows.expert.rollouts, 3);
  const std::string html = testing::read_text(first.report_html);
  EXPECT_EQ(html.find("missing picture"), std::string::npos);
  EXPECT_NE(html.find("data:image/png;base64,iVBORw0KGgo"), std::string::npos);
  for (const auto& s : first.stages) EXPECT_FALSE(s.reused) << s.name;

  const auto again = experiments::run_experiments(o);
  for (const auto& s : again.stages) EXPECT_TRUE(s.reused) << s.name;
  EXPECT_EQ(testing::read_text(again.report_md).substr(0, 200), md.substr(0, 200));

  // Another evaluation size keeps the data and the models, and evaluates again.
  auto more = o;
  more.eval_count = 2;
  more.planners = {"miqp", "keep-lane"};
  const auto third = experiments::run_experiments(more);
  EXPECT_TRUE(reused(third, "data"));
  EXPECT_TRUE(reused(third, "models"));
  EXPECT_FALSE(reused(third, "evaluate-footprint"));
  EXPECT_NE(testing::read_text(third.report_md).find("| miqp | 6 |"), std::string::npos);
}

TEST(Experiments, MpiRanksShareTheDataAndEvaluationStages) {
#ifndef LANECHANGE_HAVE_MPI
  GTEST_SKIP() << "built without MPI";
#endif
  if (!testing::mpirun_available()) GTEST_SKIP() << "no mpirun";
  testing::TempDir dir;
  const auto run = testing::run_cli_on_ranks(
      2, "--config " + testing::untimed_config_file(dir) +
             " experiments --scale tiny --eval-count 1 --planner miqp,keep-lane --no-figures "
             "--jobs 1 --out " +
             dir.file("run"));
  ASSERT_EQ(run.exit_code, 0) << run.output;
  const std::string md = testing::read_text(dir.file("run/report.md"));
  EXPECT_NE(md.find("| miqp | 3 |"), std::string::npos);
  // The data set's manifest says two ranks made it.
  const auto manifest =
      nlohmann::json::parse(testing::read_text(dir.file("run/data/idm/manifest.json")));
  EXPECT_EQ(manifest["run"]["ranks"], 2);
}

TEST(Experiments, BadOptionsAreRefusedBeforeAnythingIsWritten) {
  testing::TempDir dir;
  auto o = tiny(dir.file("run"));
  o.planners = {"miqp", "nobody"};
  EXPECT_THROW((void)experiments::run_experiments(o), InputError);
  EXPECT_FALSE(fs::exists(o.out_dir));
  EXPECT_THROW((void)experiments::scale_from_string("huge", "--scale"), InputError);
  EXPECT_EQ(testing::run_cli("experiments --scale huge --out " + dir.file("x")).exit_code, 2);
  EXPECT_FALSE(fs::exists(dir.file("x")));
}

}  // namespace
}  // namespace lanechange
