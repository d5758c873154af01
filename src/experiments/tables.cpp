#include "experiments/tables.hpp"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <sstream>

#include "lanechange/error.hpp"
#include "lanechange/run/quantile.hpp"
#include "lanechange/sampler.hpp"

namespace lanechange::experiments {

namespace fs = std::filesystem;

namespace {

// The paper's numbers (spec/paper.tex, Tables I-III and Sec. V-C).
const std::map<std::string, double> kPaperAccuracy = {{"decision_tree", 86.8},
                                                      {"naive_bayes", 78.2},
                                                      {"svm", 93.1},
                                                      {"knn", 84.4},
                                                      {"ensemble", 91.9}};
const std::map<std::string, std::string> kPaperComparison = {
    {"mlp-miqp", "85.171% / 6 ms"}, {"mpc", "65.905% / 230 ms"}, {"dwa", "57.897% / 489 ms"}};
const std::map<std::string, std::string> kPaperBehavior = {
    {"constant_speed", "88.75%"}, {"constant_accel", "85.17%"}, {"idm", "91.95%"}};
constexpr double kPaperGeneralization = 22.0;

std::string fixed(double value, int digits) {
  if (!std::isfinite(value)) return "–";
  std::ostringstream out;
  out.setf(std::ios::fixed);
  out.precision(digits);
  out << value;
  return out.str();
}

// Step times span five decades (microseconds for a network, a second for a
// stalled solve): three significant digits for each.
std::string significant(double value) {
  if (!std::isfinite(value)) return "–";
  std::ostringstream out;
  out.precision(3);
  out << value;
  return out.str();
}

std::vector<const sim::RolloutRow*> of_planner(const std::vector<sim::RolloutRow>& rows,
                                               const std::string& planner,
                                               const std::string& behavior = "") {
  std::vector<const sim::RolloutRow*> out;
  for (const auto& r : rows) {
    if (r.planner == planner && (behavior.empty() || r.behavior == behavior)) out.push_back(&r);
  }
  return out;
}

template <class Predicate>
long long count(const std::vector<const sim::RolloutRow*>& rows, Predicate predicate) {
  return std::count_if(rows.begin(), rows.end(), predicate);
}

std::vector<double> column(const std::vector<const sim::RolloutRow*>& rows,
                           double sim::RolloutRow::*member) {
  std::vector<double> values;
  values.reserve(rows.size());
  for (const auto* r : rows) values.push_back(r->*member);
  return values;
}

double mean(const std::vector<double>& values) {
  double sum = 0.0;
  for (double v : values) sum += v;
  return values.empty() ? NAN : sum / static_cast<double>(values.size());
}

double success_share(const std::vector<const sim::RolloutRow*>& rows) {
  if (rows.empty()) return NAN;
  return static_cast<double>(count(rows, [](const auto* r) { return r->success(); })) /
         static_cast<double>(rows.size());
}

// The scenes (behavior, index) where `planner` succeeds.
std::map<std::pair<std::string, long long>, bool> successes_of(
    const std::vector<sim::RolloutRow>& rows, const std::string& planner) {
  std::map<std::pair<std::string, long long>, bool> out;
  for (const auto& r : rows) {
    if (r.planner == planner) out[{r.behavior, r.index}] = r.success();
  }
  return out;
}

std::string success_where_miqp_succeeds(const std::vector<sim::RolloutRow>& rows,
                                        const std::string& planner) {
  const auto miqp = successes_of(rows, "miqp");
  long long both = 0;
  long long base = 0;
  for (const auto& r : rows) {
    if (r.planner != planner) continue;
    const auto it = miqp.find({r.behavior, r.index});
    if (it == miqp.end() || !it->second) continue;
    ++base;
    both += r.success() ? 1 : 0;
  }
  return percent(both, base);
}

}  // namespace

std::string percent(long long part, long long whole) {
  if (whole <= 0) return "–";
  return fixed(100.0 * static_cast<double>(part) / static_cast<double>(whole), 1) + "%";
}

Table dagger_table(const dagger::DaggerReport& report) {
  Table t{{"round", "planner", "rollouts", "success", "take-overs per rollout", "collisions",
           "at-fault collisions", "network drives", "taken over at the start", "taken over later",
           "new well-posed labels", "DAgger samples so far"},
          {}};
  std::vector<dagger::RoundRow> rows = report.rounds;
  rows.push_back(report.expert);
  for (const auto& r : rows) {
    const auto network = [&r](long long n) { return r.round < 0 ? "-" : std::to_string(n); };
    t.rows.push_back({r.round < 0 ? "-" : std::to_string(r.round), r.planner,
                      std::to_string(r.rollouts), fixed(100.0 * r.success_rate, 1) + "%",
                      fixed(r.takeovers_per_rollout, 2), fixed(100.0 * r.collision_rate, 1) + "%",
                      fixed(100.0 * r.at_fault_collision_rate, 1) + "%", network(r.driven),
                      network(r.taken_over_at_start), network(r.taken_over_later),
                      std::to_string(r.labels), std::to_string(r.dagger_samples)});
  }
  return t;
}

std::vector<std::string> dagger_verdicts(const dagger::DaggerReport& report) {
  const auto& rounds = report.rounds;
  if (rounds.size() < 2) return {"No DAgger round ran."};
  int falling = 0;
  int falling_later = 0;
  for (std::size_t r = 1; r < rounds.size(); ++r) {
    falling += rounds[r].takeovers_per_rollout < rounds[r - 1].takeovers_per_rollout ? 1 : 0;
    falling_later += rounds[r].taken_over_later < rounds[r - 1].taken_over_later ? 1 : 0;
  }
  const int steps = static_cast<int>(rounds.size()) - 1;
  const double gap = 100.0 * (report.expert.success_rate - rounds.back().success_rate);
  return {
      std::string(falling == steps ? "Met" : "Not met") +
          ": fewer take-overs per rollout with every round (" + std::to_string(falling) + " of " +
          std::to_string(steps) + " rounds lower than the round before).",
      "Of those, the take-overs from states the network drove to (after its first step; "
      "DAgger's own case) fell in " +
          std::to_string(falling_later) + " of " + std::to_string(steps) + " rounds (" +
          std::to_string(rounds.front().taken_over_later) + " before DAgger, " +
          std::to_string(rounds.back().taken_over_later) + " after round " + std::to_string(steps) +
          ").",
      std::string(gap <= 2.0 ? "Met" : "Not met") +
          ": mlp-miqp within 2 points of miqp after DAgger (" + fixed(std::abs(gap), 1) +
          (gap >= 0.0 ? " points below" : " points above") + " miqp after round " +
          std::to_string(steps) + ").",
  };
}

ExpertLabels read_expert_labels(const std::vector<std::string>& dataset_dirs) {
  ExpertLabels labels;
  for (const auto& dir : dataset_dirs) {
    for (const auto& entry : fs::directory_iterator(dir)) {
      const std::string name = entry.path().filename().string();
      if (name.rfind("scenarios-", 0) != 0) continue;
      std::ifstream in(entry.path());
      std::string line;
      std::getline(in, line);
      std::vector<std::string> header;
      std::stringstream head(line);
      for (std::string cell; std::getline(head, cell, ',');) header.push_back(cell);
      const auto label_at = std::find(header.begin(), header.end(), "label") - header.begin();
      if (header.size() < 3 || header[0] != "index" || header[2] != "behavior" ||
          label_at == static_cast<long>(header.size())) {
        throw InputError(entry.path().string(), "is not a scenarios file of a data set");
      }
      while (std::getline(in, line)) {
        std::vector<std::string> cells;
        std::stringstream row(line);
        for (std::string cell;
             cells.size() <= static_cast<std::size_t>(label_at) && std::getline(row, cell, ',');) {
          cells.push_back(cell);
        }
        if (cells.size() <= static_cast<std::size_t>(label_at)) {
          throw InputError(entry.path().string(), "has a row with too few columns");
        }
        labels[{cells[2], std::stoll(cells[0])}] = cells[static_cast<std::size_t>(label_at)];
      }
    }
  }
  return labels;
}

Table classifier_table(const nlohmann::json& metrics) {
  // Models trained on data without gap features have no gap classifiers.
  const bool gaps = metrics.contains("gap_classifiers");
  // Without every gap labelled, the one gap known to be completable is the
  // expert's own, and the second column would repeat the first.
  const bool labelled = gaps && metrics.value("gap_labels", false);
  Table t{{"classifier", "accuracy (13 features)", "with behavior", "paper"}, {}};
  if (gaps) t.header.emplace_back("gap named");
  if (labelled) t.header.emplace_back("gap completable");
  for (const auto& [name, paper] : kPaperAccuracy) {
    const auto plain = metrics.at("classifiers").at(name).at("test_accuracy").get<double>();
    const auto with =
        metrics.at("classifiers_with_behavior").at(name).at("test_accuracy").get<double>();
    t.rows.push_back(
        {name, fixed(100 * plain, 1) + "%", fixed(100 * with, 1) + "%", fixed(paper, 1) + "%"});
    if (!gaps) continue;
    const nlohmann::json& g = metrics.at("gap_classifiers").at(name);
    t.rows.back().push_back(fixed(100 * g.at("test_accuracy").get<double>(), 1) + "%");
    if (labelled) {
      t.rows.back().push_back(fixed(100 * g.at("completable_share").get<double>(), 1) + "%");
    }
  }
  const auto majority = metrics.at("majority_class").at("test_accuracy").get<double>();
  t.rows.push_back(
      {"majority class (" + metrics.at("majority_class").at("class").get<std::string>() + ")",
       fixed(100 * majority, 1) + "%", "", "–"});
  t.rows.back().resize(t.header.size());
  return t;
}

Table svm_confusion_table(const nlohmann::json& metrics) {
  static const std::vector<std::string> kClasses = {"well_posed", "ill_posed", "failure"};
  Table t{{"true \\ predicted", kClasses[0], kClasses[1], kClasses[2]}, {}};
  const auto& m = metrics.at("classifiers").at("svm").at("confusion_row_normalised");
  for (std::size_t i = 0; i < kClasses.size(); ++i) {
    std::vector<std::string> row = {kClasses[i]};
    for (std::size_t j = 0; j < kClasses.size(); ++j) {
      row.push_back(fixed(m.at(i).at(j).get<double>(), 3));
    }
    t.rows.push_back(std::move(row));
  }
  return t;
}

Table comparison_table(const std::vector<sim::RolloutRow>& rows,
                       const std::vector<std::string>& planners) {
  Table t{{"planner", "scenes", "success", "success where miqp succeeds", "collision (at fault)",
           "unsafe cut-in", "aborted", "take-overs / rollout", "step ms p50", "step ms p99",
           "step ms max", "RMS jerk", "max abs(a) p95", "paper: success / time"},
          {}};
  for (const auto& planner : planners) {
    const auto mine = of_planner(rows, planner);
    const auto n = static_cast<long long>(mine.size());
    const auto paper = kPaperComparison.find(planner);
    t.rows.push_back(
        {planner, std::to_string(n),
         percent(count(mine, [](const auto* r) { return r->success(); }), n),
         success_where_miqp_succeeds(rows, planner),
         percent(count(mine, [](const auto* r) { return r->collision; }), n) + " (" +
             percent(count(mine, [](const auto* r) { return r->at_fault; }), n) + ")",
         percent(count(mine, [](const auto* r) { return r->unsafe_cut_in; }), n),
         percent(count(mine, [](const auto* r) { return r->outcome == "aborted"; }), n),
         fixed(mean(column(mine, &sim::RolloutRow::takeovers)), 2),
         significant(run::nearest_rank(column(mine, &sim::RolloutRow::median_step_ms), 0.5)),
         significant(run::nearest_rank(column(mine, &sim::RolloutRow::p99_step_ms), 0.99)),
         significant(run::nearest_rank(column(mine, &sim::RolloutRow::max_step_ms), 1.0)),
         fixed(mean(column(mine, &sim::RolloutRow::rms_jerk)), 2),
         fixed(run::nearest_rank(column(mine, &sim::RolloutRow::max_abs_accel), 0.95), 2),
         paper == kPaperComparison.end() ? "–" : paper->second});
  }
  return t;
}

std::string traffic_check(const std::vector<sim::RolloutRow>& rows, std::optional<double> limit) {
  long long overlaps = 0;
  double hardest = 0.0;
  for (const auto& r : rows) {
    overlaps += r.cars_collide ? 1 : 0;
    hardest = std::max(hardest, r.max_car_decel);
  }
  return std::to_string(overlaps) + " of " + std::to_string(rows.size()) +
         " rollouts show two other cars overlapping; the hardest braking of any car is " +
         fixed(hardest, 2) + " m/s^2" +
         (limit ? " (limit `traffic.max_decel`: " + fixed(*limit, 2) + ")" : " (no limit set)");
}

Table behavior_table(const std::vector<sim::RolloutRow>& rows,
                     const std::vector<std::string>& planners) {
  Table t{{"behavior of the other cars"}, {}};
  for (const auto& planner : planners) t.header.push_back(planner);
  t.header.emplace_back("paper (MLP-MIQP)");
  for (const Behavior sampled : kSampledBehaviors) {
    const std::string behavior(to_string(sampled));
    std::vector<std::string> row = {behavior};
    for (const auto& planner : planners) {
      const auto mine = of_planner(rows, planner, behavior);
      row.push_back(percent(count(mine, [](const auto* r) { return r->success(); }),
                            static_cast<long long>(mine.size())));
    }
    row.push_back(kPaperBehavior.at(behavior));
    t.rows.push_back(std::move(row));
  }
  return t;
}

GeneralizationResult generalization_table(const std::vector<sim::RolloutRow>& rows,
                                          const ExpertLabels& labels,
                                          const std::vector<std::string>& planners) {
  GeneralizationResult out;
  for (const auto& [key, label] : labels) out.ill_posed += label == "ill_posed" ? 1 : 0;
  out.table = {{"planner", "ill-posed scenes run", "ends well-posed", "paper (MLP-MIQP)"}, {}};
  for (const auto& planner : planners) {
    long long run = 0;
    long long well = 0;
    for (const auto& r : rows) {
      if (r.planner != planner) continue;
      const auto it = labels.find({r.behavior, r.index});
      if (it == labels.end() || it->second != "ill_posed") continue;
      ++run;
      well += r.success() ? 1 : 0;
    }
    out.table.rows.push_back({planner, std::to_string(run), percent(well, run),
                              planner == "mlp-miqp" ? fixed(kPaperGeneralization, 0) + "%" : "–"});
  }
  return out;
}

std::vector<std::string> where_others_beat_ours(const std::vector<sim::RolloutRow>& rows,
                                                const std::vector<std::string>& planners) {
  std::vector<std::string> out;
  const auto ours = of_planner(rows, "mlp-miqp");
  if (ours.empty()) return out;
  const double our_success = success_share(ours);
  const auto share = [](const std::vector<const sim::RolloutRow*>& set, auto predicate) {
    return percent(count(set, predicate), static_cast<long long>(set.size()));
  };
  const auto ahead_of_target = [](const std::vector<const sim::RolloutRow*>& set) {
    const long long successes = count(set, [](const auto* r) { return r->success(); });
    return percent(count(set,
                         [](const auto* r) {
                           return r->success() && r->target_lane_slot == "ahead_of_target";
                         }),
                   successes);
  };
  for (const auto& planner : planners) {
    if (planner == "mlp-miqp") continue;
    const auto theirs = of_planner(rows, planner);
    const double their_success = success_share(theirs);
    if (!(their_success > our_success)) continue;
    std::string s = "**" + planner;
    s += "** succeeds more often than mlp-miqp (";
    s += fixed(100 * their_success, 1) + "% against " + fixed(100 * our_success, 1) + "%). ";
    s += "Measured why: mlp-miqp aborts in ";
    s += share(ours, [](const auto* r) { return r->outcome == "aborted"; });
    s += " of the scenes (its classifier predicted failure, or its check handed the scene to the "
         "fallback) against ";
    s += share(theirs, [](const auto* r) { return r->outcome == "aborted"; });
    s += "; it ends ill-posed in ";
    s += share(ours, [](const auto* r) { return r->outcome == "ill_posed"; });
    s += " against ";
    s += share(theirs, [](const auto* r) { return r->outcome == "ill_posed"; });
    s += "; it collides in ";
    s += share(ours, [](const auto* r) { return r->collision; });
    s += " against ";
    s += share(theirs, [](const auto* r) { return r->collision; });
    s += ". Of its successes, ";
    s += ahead_of_target(theirs);
    s += " end ahead of the target, outside Eq. 1's gap (mlp-miqp: ";
    s += ahead_of_target(ours);
    s += ").";
    out.push_back(std::move(s));
  }
  return out;
}

}  // namespace lanechange::experiments
