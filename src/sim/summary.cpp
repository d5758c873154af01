// rollouts.csv from the shards, and summary.csv from it.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include "common/json_fields.hpp"
#include "lanechange/error.hpp"
#include "lanechange/sim/evaluate.hpp"
#include "sim/evaluation_files.hpp"

namespace lanechange::sim {

namespace fs = std::filesystem;

namespace {

struct Row {
  std::string behavior, planner, outcome;
  bool collision = false;
  bool at_fault = false;
  double takeovers = 0, fallbacks = 0, overruns = 0;
  double time_to_target_lane = NAN, min_ttc = NAN, max_abs_accel = 0, rms_jerk = 0;
  double median_step_ms = 0, max_step_ms = 0;
};

double field(const std::vector<std::string>& f, std::size_t i) {
  return i < f.size() && !f[i].empty() ? std::stod(f[i]) : NAN;
}

Row parse(const std::string& line) {
  std::vector<std::string> f;
  std::stringstream in(line);
  // The reason is last and may hold commas: split only the columns before it.
  for (std::string cell; f.size() + 1 < rollout_columns().size() && std::getline(in, cell, ',');) {
    f.push_back(cell);
  }
  Row r;
  r.behavior = f.at(1);
  r.planner = f.at(2);
  r.outcome = f.at(3);
  r.collision = f.at(4) == "1";
  r.at_fault = f.at(5) == "1";
  r.takeovers = field(f, 6);
  r.fallbacks = field(f, 7);
  r.overruns = field(f, 8);
  r.time_to_target_lane = field(f, 11);
  r.min_ttc = field(f, 13);
  r.max_abs_accel = field(f, 14);
  r.rms_jerk = field(f, 15);
  r.median_step_ms = field(f, 17);
  r.max_step_ms = field(f, 18);
  return r;
}

// Nearest-rank percentile of the finite values; NaN without any.
double percentile(std::vector<double> v, double q) {
  v.erase(std::remove_if(v.begin(), v.end(), [](double x) { return !std::isfinite(x); }), v.end());
  if (v.empty()) return NAN;
  std::sort(v.begin(), v.end());
  const auto rank = static_cast<std::size_t>(std::ceil(q * static_cast<double>(v.size())));
  return v[std::max<std::size_t>(rank, 1) - 1];
}

std::string number(double v) {
  if (!std::isfinite(v)) return "";
  std::ostringstream out;
  out.precision(6);
  out << v;
  return out.str();
}

std::string summary_row(const std::string& planner, const std::string& behavior,
                        const std::vector<const Row*>& rows) {
  const auto n = static_cast<double>(rows.size());
  auto rate = [&](auto predicate) {
    return static_cast<double>(std::count_if(rows.begin(), rows.end(), predicate)) / n;
  };
  auto values = [&](double Row::*member) {
    std::vector<double> v;
    v.reserve(rows.size());
    for (const Row* r : rows) v.push_back(r->*member);
    return v;
  };
  auto mean = [&](double Row::*member) {
    double sum = 0;
    for (const Row* r : rows) sum += r->*member;
    return sum / n;
  };
  const std::vector<double> cells = {
      n,
      rate([](const Row* r) { return r->outcome == "well_posed" && !r->collision; }),
      rate([](const Row* r) { return r->outcome == "ill_posed"; }),
      rate([](const Row* r) { return r->outcome == "failure"; }),
      rate([](const Row* r) { return r->outcome == "aborted"; }),
      rate([](const Row* r) { return r->collision; }),
      rate([](const Row* r) { return r->at_fault; }),
      mean(&Row::takeovers),
      mean(&Row::fallbacks),
      mean(&Row::overruns),
      percentile(values(&Row::median_step_ms), 0.5),
      percentile(values(&Row::max_step_ms), 0.99),
      percentile(values(&Row::max_step_ms), 1.0),
      percentile(values(&Row::time_to_target_lane), 0.5),
      percentile(values(&Row::min_ttc), 0.05),
      mean(&Row::rms_jerk),
      percentile(values(&Row::max_abs_accel), 0.95)};
  std::string line = planner + "," + behavior;
  for (double c : cells) {
    line += ',';
    line += number(c);
  }
  return line + "\n";
}

}  // namespace

std::vector<std::string> summary_columns() {
  return {"planner",
          "behavior",
          "rollouts",
          "success_rate",
          "ill_posed_rate",
          "failure_rate",
          "aborted_rate",
          "collision_rate",
          "at_fault_collision_rate",
          "takeovers_per_rollout",
          "fallback_steps_per_rollout",
          "overruns_per_rollout",
          "step_ms_p50",
          "max_step_ms_p99",
          "max_step_ms_max",
          "time_to_target_lane_p50",
          "min_ttc_p5",
          "rms_jerk_mean",
          "max_abs_accel_p95"};
}

namespace detail {

std::string shard_file(long long shard) {
  char name[40];
  std::snprintf(name, sizeof name, "rollouts-%05lld.csv", shard);
  return name;
}

void write_results(const std::string& dir, long long shards) {
  std::string all;
  std::vector<Row> rows;
  for (long long s = 0; s < shards; ++s) {
    const std::string name = shard_file(s);
    std::ifstream in(fs::path(dir) / name);
    if (!in) throw InputError("", name + " is missing in " + dir);
    std::string line;
    std::getline(in, line);
    if (s == 0) all += line + "\n";
    while (std::getline(in, line)) {
      if (line.empty()) continue;
      all += line + "\n";
      rows.push_back(parse(line));
    }
  }
  lanechange::detail::write_file_atomically((fs::path(dir) / "rollouts.csv").string(), all);
  std::map<std::pair<std::string, std::string>, std::vector<const Row*>> groups;
  std::vector<std::string> order;
  for (const Row& r : rows) {
    if (std::find(order.begin(), order.end(), r.planner) == order.end()) order.push_back(r.planner);
    groups[{r.planner, r.behavior}].push_back(&r);
    groups[{r.planner, "all"}].push_back(&r);
  }
  std::string text;
  for (const auto& c : summary_columns()) {
    if (!text.empty()) text += ',';
    text += c;
  }
  text += "\n";
  for (const std::string& planner : order) {
    for (const auto& [key, members] : groups) {
      if (key.first == planner) text += summary_row(key.first, key.second, members);
    }
  }
  lanechange::detail::write_file_atomically((fs::path(dir) / "summary.csv").string(), text);
}

}  // namespace detail

}  // namespace lanechange::sim
