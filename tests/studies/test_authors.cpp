// The authors' reference records (reference/README.md): loading, their cost
// and prediction as we read them, and our `authors` preset against them.
//
// The records live outside the repository. They are looked for in
// <source>/../shared/reference/, then /work/shared/reference/; the tests that
// need them skip when none exists. The full comparison is the command
// `lanechange authors-study` (docs/authors_comparison.md).
#include <gtest/gtest.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <nlohmann/json.hpp>
#include <string>

#include "../foundation/test_helpers.hpp"
#include "lanechange/error.hpp"
#include "lanechange/studies/authors.hpp"

namespace lanechange::studies {
namespace {

std::string records_path() {
  for (const std::string& candidate :
       {std::string(LANECHANGE_SOURCE_DIR) + "/../shared/reference/authors_idm.jsonl",
        std::string("/work/shared/reference/authors_idm.jsonl")}) {
    if (std::filesystem::exists(candidate)) return candidate;
  }
  return {};
}

// Loaded once: parsing 1283 records takes a fraction of a second.
const std::vector<AuthorsRecord>& all_records() {
  static const std::vector<AuthorsRecord> records = [] {
    const std::string path = records_path();
    return path.empty() ? std::vector<AuthorsRecord>{}
                        : load_authors_records(path, make_preset("authors"));
  }();
  return records;
}

#define REQUIRE_RECORDS()                          \
  if (all_records().empty()) {                     \
    GTEST_SKIP() << "authors_idm.jsonl not found"; \
  }

// A small valid record: the scenario of record data2.mat{1}, and either no
// solution or a made-up one of the right sizes.
nlohmann::json synthetic_record(bool solved) {
  nlohmann::json r = {
      {"id", solved ? "synthetic{solved}" : "synthetic{none}"},
      {"scenario",
       {{"format", "lanechange.scenario/1"},
        {"lane_width", 3.75},
        {"behavior", "idm"},
        {"ego", {{"x", 0.0}, {"y", 0.0}, {"v", 8.034278}, {"theta", 0.0}, {"a", 0.0}}},
        {"leader", {{"x", 24.10283}, {"v", 8.276469}, {"a", 0.1088276}}},
        {"target", {{"x", 32.7549}, {"v", 9.496471}, {"a", -0.5093734}}},
        {"follower", {{"x", -13.27187}, {"v", 9.921866}, {"a", -0.3594054}}}}},
      {"status", solved ? "solved" : "no_solution"}};
  if (solved) {
    std::vector<double> nodes(51, 0.0), steps(50, 0.0);
    r["objective"] = 1.0;
    r["objective_terms"] = {0.25, 0.25, 0.25, 0.25};
    r["solution"] = {{"x", nodes},     {"y", nodes}, {"v", nodes},
                     {"theta", nodes}, {"a", steps}, {"omega", steps}};
    nlohmann::json car = {{"x", nodes}, {"v", nodes}};
    r["predicted_others"] = {{"leader", car}, {"target", car}, {"follower", car}};
  }
  return r;
}

class TempFile {
 public:
  explicit TempFile(const std::string& text) {
    path_ =
        (std::filesystem::temp_directory_path() /
         ("lanechange_authors_" +
          std::string(::testing::UnitTest::GetInstance()->current_test_info()->name()) + ".jsonl"))
            .string();
    std::ofstream(path_) << text;
  }
  ~TempFile() { std::filesystem::remove(path_); }
  TempFile(const TempFile&) = delete;
  TempFile& operator=(const TempFile&) = delete;
  [[nodiscard]] const std::string& path() const { return path_; }

 private:
  std::string path_;
};

// The message of the InputError that loading `text` throws.
std::string load_error(const std::string& text) {
  const TempFile file(text);
  try {
    (void)load_authors_records(file.path(), make_preset("authors"));
  } catch (const InputError& e) {
    return e.what();
  }
  return "no error";
}

TEST(AuthorsRecords, LoadsSyntheticRecordsAndSkipsBlankLines) {
  const TempFile file(synthetic_record(true).dump() + "\n\n" + synthetic_record(false).dump() +
                      "\n");
  const auto records = load_authors_records(file.path(), make_preset("authors"));
  ASSERT_EQ(records.size(), 2u);
  EXPECT_TRUE(records[0].solved);
  EXPECT_EQ(records[0].line, 1);
  EXPECT_EQ(records[0].solution.states.size(), 51u);
  EXPECT_EQ(records[0].solution.controls.size(), 50u);
  EXPECT_EQ(records[0].predicted_others.nodes(), 51);
  EXPECT_DOUBLE_EQ(records[0].objective, 1.0);
  EXPECT_FALSE(records[1].solved);
  EXPECT_EQ(records[1].line, 3);
  EXPECT_TRUE(records[1].solution.states.empty());
  EXPECT_EQ(records[1].scenario.behavior, Behavior::Idm);
  EXPECT_DOUBLE_EQ(records[1].scenario.follower().x, -13.27187);
}

TEST(AuthorsRecords, BadLinesNameTheLineAndTheField) {
  const std::string good = synthetic_record(false).dump() + "\n";
  EXPECT_NE(load_error(good + good + "{not json\n").find("line 3"), std::string::npos);

  auto negative_speed = synthetic_record(false);
  negative_speed["scenario"]["leader"]["v"] = -1.0;
  const std::string e1 = load_error(good + negative_speed.dump() + "\n");
  EXPECT_NE(e1.find("line 2"), std::string::npos) << e1;
  EXPECT_NE(e1.find("scenario.leader.v"), std::string::npos) << e1;

  auto short_solution = synthetic_record(true);
  short_solution["solution"]["y"].erase(0);
  const std::string e2 = load_error(short_solution.dump() + "\n");
  EXPECT_NE(e2.find("line 1"), std::string::npos) << e2;
  EXPECT_NE(e2.find("solution.y"), std::string::npos) << e2;

  auto unknown_status = synthetic_record(false);
  unknown_status["status"] = "maybe";
  EXPECT_NE(load_error(unknown_status.dump()).find("status"), std::string::npos);

  auto missing_objective = synthetic_record(true);
  missing_objective.erase("objective");
  EXPECT_NE(load_error(missing_objective.dump()).find("objective"), std::string::npos);

  auto text_number = synthetic_record(true);
  text_number["solution"]["a"][7] = "0.3";
  EXPECT_NE(load_error(text_number.dump()).find("solution.a[7]"), std::string::npos);

  auto extra_field = synthetic_record(false);
  extra_field["solutions"] = 1;
  EXPECT_NE(load_error(extra_field.dump()).find("solutions"), std::string::npos);

  EXPECT_THROW((void)load_authors_records("/nonexistent/authors.jsonl", make_preset("authors")),
               InputError);
}

TEST(AuthorsRecords, LoadsTheReferenceFile) {
  REQUIRE_RECORDS();
  const auto& records = all_records();
  ASSERT_EQ(records.size(), 1283u);
  int solved = 0;
  for (const AuthorsRecord& r : records) {
    if (!r.solved) continue;
    ++solved;
    ASSERT_EQ(r.solution.states.size(), 51u) << r.id;
    ASSERT_EQ(r.predicted_others.nodes(), 51) << r.id;
  }
  EXPECT_EQ(solved, 1224);
  EXPECT_EQ(records.front().id, "data2.mat{1}");
  EXPECT_EQ(records.front().line, 1);
  EXPECT_EQ(records.back().line, 1283);
}

TEST(AuthorsRecords, TheirCostIsTheReadmeCost) {
  // Our reading of the authors' cost, on their solution and with their
  // target's end position, gives their stored terms (7 significant digits).
  REQUIRE_RECORDS();
  const Config config = make_preset("authors");
  double worst = 0.0;
  for (const AuthorsRecord& r : all_records()) {
    if (!r.solved) continue;
    const AuthorsTerms t =
        authors_objective_terms(r.solution, config, r.scenario.lane_width,
                                r.predicted_others.car(car_of(Role::Target)).x.back());
    for (int i = 0; i < 4; ++i) {
      worst = std::max(worst, std::abs(t[i] - r.objective_terms[i]) / (1.0 + r.objective_terms[i]));
    }
    worst = std::max(worst, std::abs(sum_of(t) - r.objective) / (1.0 + r.objective));
  }
  EXPECT_LT(worst, 1e-5);
}

TEST(AuthorsRecords, OurPredictionAlongTheirPathIsClose) {
  // Their stored prediction comes from their last round, which reacted to
  // their second-to-last iterate, not to the stored solution: the follower
  // may differ a little. The free-road leader and target do not react.
  REQUIRE_RECORDS();
  const Config config = make_preset("authors");
  double leader = 0.0, target = 0.0;
  for (std::size_t i = 0; i < all_records().size() && i < 200; ++i) {
    const AuthorsRecord& r = all_records()[i];
    if (!r.solved) continue;
    const auto ego = [&] {
      std::vector<EgoFootprint> out;
      for (const expert::State& z : r.solution.states)
        out.push_back({z[expert::kX], z[expert::kY], z[expert::kV]});
      return out;
    }();
    const int lead = config.expert.prediction_lead_steps;
    const auto mine = predict_traffic(r.scenario, config, r.scenario.steps + lead, 0.1, &ego);
    for (int k = 0; k <= r.scenario.steps; ++k) {
      leader = std::max(leader, std::abs(mine.car(car_of(Role::Leader)).x[k + lead] -
                                         r.predicted_others.car(car_of(Role::Leader)).x[k]));
      target = std::max(target, std::abs(mine.car(car_of(Role::Target)).x[k + lead] -
                                         r.predicted_others.car(car_of(Role::Target)).x[k]));
    }
  }
  RecordProperty("leader_max_dx", std::to_string(leader));
  RecordProperty("target_max_dx", std::to_string(target));
  // See docs/authors_comparison.md: their Euler step moves x with the new
  // speed; with the same step these are ~1e-5 m.
  EXPECT_LT(leader, 0.5);
  EXPECT_LT(target, 0.5);
}

TEST(AuthorsComparison, FirstSolvedRecordsMostlyMatch) {
  // The first 8 solved records (data2.mat{1..5}, data3.mat{1..3}): a second
  // or two. On the full file 94% are at most 1% above theirs (the issue's
  // bar is 90%).
  REQUIRE_RECORDS();
  std::vector<AuthorsRecord> subset;
  for (const AuthorsRecord& r : all_records()) {
    if (r.solved && subset.size() < 8) subset.push_back(r);
  }
  AuthorsComparisonSettings settings;
  settings.diagnose = false;
  const auto results = compare_with_authors(subset, authors_planner(), settings);
  const AuthorsSummary summary = summarize(results, settings.tolerance);
  EXPECT_EQ(summary.theirs_solved, 8);
  EXPECT_EQ(summary.both_solved, 8) << to_markdown(summary);
  EXPECT_GE(summary.at_most_tolerance_above, 7) << to_markdown(summary);
  for (const AuthorsComparison& c : results) {
    EXPECT_LT(std::abs(c.relative_difference), 0.03) << c.id;
    EXPECT_LT(c.max_dy, 0.5) << c.id;
    EXPECT_LT(c.max_dx, 1.0) << c.id;
  }
}

TEST(AuthorsComparison, DiagnosesOneRecord) {
  REQUIRE_RECORDS();
  const AuthorsRecord& r = all_records().front();
  AuthorsComparisonSettings settings;
  settings.diagnose_agreeing = true;
  const AuthorsComparison c = compare_with_authors(r, authors_planner(), settings);
  ASSERT_TRUE(c.theirs_solved);
  // Their path, linearized about itself, meets its own dynamics up to their
  // last linearization error, and our rebuild of our last round is exact.
  EXPECT_LT(c.with_their_prediction.violation.dynamics, 0.02);
  EXPECT_NEAR(c.our_qp_rebuild_error, 0.0, 1e-6);
  // With their own prediction, their path meets their lane rules (7 digits)
  // and costs what they stored; the optimum there is about their objective.
  EXPECT_LT(c.with_their_prediction.violation.lanes, 1e-4);
  EXPECT_NEAR(c.with_their_prediction.their_objective, r.objective, 1e-4 * r.objective);
  EXPECT_EQ(c.with_their_prediction.status, MiqpStatus::Optimal);
  EXPECT_NEAR(c.with_their_prediction.optimum, r.objective, 2e-3 * r.objective);
  // The three parts add up to the relative difference.
  EXPECT_NEAR(c.their_gap + c.prediction_effect + c.fixpoint_effect, c.relative_difference, 1e-12);
  nlohmann::json j = c;
  EXPECT_EQ(j["id"], "data2.mat{1}");
}

TEST(AuthorsRecords, TheirPredictionOnOurGrid) {
  REQUIRE_RECORDS();
  const AuthorsRecord& r = all_records().front();
  const TrafficPrediction p = their_prediction_on_our_grid(r);
  ASSERT_EQ(p.nodes(), r.scenario.steps + 2);
  EXPECT_DOUBLE_EQ(p.car(car_of(Role::Leader)).x[0], r.scenario.leader().x);
  EXPECT_DOUBLE_EQ(p.car(car_of(Role::Target)).x[1],
                   r.predicted_others.car(car_of(Role::Target)).x[0]);
  EXPECT_DOUBLE_EQ(p.car(car_of(Role::Follower)).v.back(),
                   r.predicted_others.car(car_of(Role::Follower)).v.back());
}

// Their Euler step moves each car with its NEW speed and lets the speed go
// below zero (data7.mat{504}, {628}); ours moves with the old speed and stops
// at zero, which puts the free-road leader and target up to 0.28 m off theirs.
// Enable once the authors' scheme is ours (docs/authors_comparison.md).
TEST(AuthorsRecords, PredictionMatchesTheirsExactly) {
  REQUIRE_RECORDS();
  const Config config = make_preset("authors");
  const int lead = config.expert.prediction_lead_steps;
  double worst = 0.0;
  for (const AuthorsRecord& r : all_records()) {
    if (!r.solved) continue;
    std::vector<EgoFootprint> ego;
    for (const expert::State& z : r.solution.states)
      ego.push_back({z[expert::kX], z[expert::kY], z[expert::kV]});
    const auto mine = predict_traffic(r.scenario, config, r.scenario.steps + lead, 0.1, &ego);
    for (CarIndex car : {car_of(Role::Leader), car_of(Role::Target)}) {
      for (int k = 0; k <= r.scenario.steps; ++k) {
        worst =
            std::max(worst, std::abs(mine.car(car).x[k + lead] - r.predicted_others.car(car).x[k]));
      }
    }
  }
  EXPECT_LT(worst, 1e-4);
}

TEST(AuthorsComparison, QuantilesAreNearestRanks) {
  const auto q = quantiles({3.0, 1.0, 2.0, NAN, 4.0}, {0.0, 0.5, 1.0, 0.25});
  EXPECT_DOUBLE_EQ(q[0].value, 1.0);
  EXPECT_DOUBLE_EQ(q[1].value, 2.0);
  EXPECT_DOUBLE_EQ(q[2].value, 4.0);
  EXPECT_DOUBLE_EQ(q[3].value, 1.0);
  EXPECT_TRUE(std::isnan(quantiles({}, {0.5})[0].value));
}

// The study of `lanechange authors-study` on the first records: its three
// files, one comparison a line, and a summary that counts them.
TEST(AuthorsStudy, WritesEveryComparisonAndTheSummary) {
  REQUIRE_RECORDS();
  const auto dir = std::filesystem::temp_directory_path() / "lanechange_authors_study_test";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  {
    std::ifstream in(records_path());
    std::ofstream few(dir / "few.jsonl");
    std::string line;
    for (int i = 0; i < 3 && std::getline(in, line); ++i) few << line << "\n";
  }
  AuthorsStudyOptions o;
  o.records_path = (dir / "few.jsonl").string();
  o.out_dir = (dir / "out").string();
  const std::string md = run_authors_study(o);
  std::ifstream lines(dir / "out" / "comparisons.jsonl");
  int count = 0;
  for (std::string line; std::getline(lines, line);) {
    EXPECT_TRUE(nlohmann::json::parse(line).contains("agreement"));
    ++count;
  }
  EXPECT_EQ(count, 3);
  const auto summary = nlohmann::json::parse(std::ifstream(dir / "out" / "summary.json"));
  EXPECT_EQ(summary.at("records").get<int>(), 3);
  EXPECT_NE(md.find("Wall time"), std::string::npos);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace lanechange::studies
