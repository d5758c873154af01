// rollouts.csv from the shards, and summary.csv from it.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

#include "common/json_fields.hpp"
#include "lanechange/error.hpp"
#include "lanechange/run/quantile.hpp"
#include "lanechange/sim/evaluate.hpp"
#include "run/csv.hpp"
#include "sim/evaluation_files.hpp"

namespace lanechange::sim {

namespace fs = std::filesystem;

namespace {

double cell_number(const std::string& cell) { return cell.empty() ? NAN : std::stod(cell); }

RolloutRow parse(const std::string& line) {
  std::vector<std::string> f;
  std::stringstream in(line);
  // The reason is last and may hold commas (quoted): split only the columns before it.
  const std::size_t before_reason = rollout_columns().size() - 1;
  for (std::string cell; f.size() < before_reason && std::getline(in, cell, ',');) {
    f.push_back(cell);
  }
  if (f.size() < before_reason) throw std::invalid_argument("too few columns");
  std::string reason;
  std::getline(in, reason);
  if (reason.size() >= 2 && reason.front() == '"') {
    std::string unquoted;
    for (std::size_t i = 1; i + 1 < reason.size(); ++i) {
      unquoted += reason[i];
      if (reason[i] == '"') ++i;  // "" stands for one quote
    }
    reason = unquoted;
  }
  RolloutRow r;
  r.index = std::stoll(f[0]);
  r.behavior = f[1];
  r.planner = f[2];
  r.outcome = f[3];
  r.collision = f[4] == "1";
  r.at_fault = f[5] == "1";
  r.unsafe_cut_in = f[6] == "1";
  r.cars_collide = f[7] == "1";
  r.target_lane_slot = f[before_reason - 3];
  r.gap_behind = f[before_reason - 2];
  r.gap_ahead = f[before_reason - 1];
  if (!r.target_lane_slot.empty() && r.target_lane_slot != "follower_target_gap" &&
      r.target_lane_slot != "ahead_of_target" && r.target_lane_slot != "behind_follower") {
    throw std::invalid_argument("unknown target_lane_slot \"" + r.target_lane_slot + "\"");
  }
  double* numbers[] = {&r.takeovers,    &r.fallbacks,     &r.overruns,
                       &r.failures,     &r.clipped,       &r.time_to_target_lane,
                       &r.min_gap,      &r.min_ttc,       &r.max_abs_accel,
                       &r.rms_jerk,     &r.max_abs_omega, &r.median_step_ms,
                       &r.p99_step_ms,  &r.max_step_ms,   &r.first_takeover_t,
                       &r.forced_decel, &r.max_car_decel, &r.time_to_lane_line};
  std::size_t column = 8;
  for (double* value : numbers) *value = cell_number(f[column++]);
  r.reason = reason;
  return r;
}

using Row = RolloutRow;

constexpr int kSummaryDigits = 6;

std::string summary_row(const std::string& planner, const std::string& behavior,
                        const std::vector<const Row*>& rows) {
  const auto n = static_cast<double>(rows.size());
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
  const RolloutRates rates = rates_of(rows);
  const std::vector<double> cells = {n,
                                     rates.success,
                                     rates.ill_posed,
                                     rates.failure,
                                     rates.aborted,
                                     rates.collision,
                                     rates.at_fault,
                                     rates.unsafe_cut_in,
                                     rates.cars_collide,
                                     rates.takeovers,
                                     rates.fallbacks,
                                     rates.overruns,
                                     run::nearest_rank(values(&Row::median_step_ms), 0.5),
                                     run::nearest_rank(values(&Row::max_step_ms), 0.99),
                                     run::nearest_rank(values(&Row::max_step_ms), 1.0),
                                     run::nearest_rank(values(&Row::time_to_target_lane), 0.5),
                                     run::nearest_rank(values(&Row::min_ttc), 0.05),
                                     mean(&Row::rms_jerk),
                                     run::nearest_rank(values(&Row::max_abs_accel), 0.95)};
  std::string line = planner + "," + behavior;
  for (double c : cells) {
    line += ',';
    line += run::csv_number(c, kSummaryDigits);
  }
  return line + "\n";
}

}  // namespace

RolloutRates rates_of(std::span<const RolloutRow* const> rows) {
  RolloutRates out;
  out.rollouts = static_cast<long long>(rows.size());
  if (rows.empty()) return out;
  for (const RolloutRow* r : rows) {
    out.success += r->success() ? 1 : 0;
    out.ill_posed += r->outcome == "ill_posed" ? 1 : 0;
    out.failure += r->outcome == "failure" ? 1 : 0;
    out.aborted += r->outcome == "aborted" ? 1 : 0;
    out.collision += r->collision ? 1 : 0;
    out.at_fault += r->at_fault ? 1 : 0;
    out.unsafe_cut_in += r->unsafe_cut_in ? 1 : 0;
    out.cars_collide += r->cars_collide ? 1 : 0;
    out.takeovers += r->takeovers;
    out.fallbacks += r->fallbacks;
    out.overruns += r->overruns;
  }
  const auto n = static_cast<double>(rows.size());
  for (double* share :
       {&out.success, &out.ill_posed, &out.failure, &out.aborted, &out.collision, &out.at_fault,
        &out.unsafe_cut_in, &out.cars_collide, &out.takeovers, &out.fallbacks, &out.overruns}) {
    *share /= n;
  }
  return out;
}

std::vector<RolloutRow> read_rollouts(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InputError(path, "cannot open the rollouts file");
  std::string line;
  std::getline(in, line);
  if (line + "\n" != detail::csv_header(rollout_columns())) {
    throw InputError(path, "is not a rollouts file of this version (its header differs)");
  }
  std::vector<RolloutRow> rows;
  long long number = 1;
  while (std::getline(in, line)) {
    ++number;
    if (line.empty()) continue;
    try {
      rows.push_back(parse(line));
    } catch (const std::exception&) {
      throw InputError(path, "line " + std::to_string(number) + " is malformed");
    }
  }
  return rows;
}

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
          "unsafe_cut_in_rate",
          "cars_collide_rate",
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

std::string csv_header(const std::vector<std::string>& columns) {
  std::string line;
  for (const auto& c : columns) {
    if (!line.empty()) line += ',';
    line += c;
  }
  return line + "\n";
}

std::string shard_file(long long shard) {
  char name[40];
  std::snprintf(name, sizeof name, "rollouts-%05lld.csv", shard);
  return name;
}

void write_results(const std::string& dir, long long shards) {
  std::string all = detail::csv_header(rollout_columns());
  std::vector<Row> rows;
  for (long long s = 0; s < shards; ++s) {
    const std::string path = (fs::path(dir) / shard_file(s)).string();
    if (!fs::exists(path)) throw InputError("", shard_file(s) + " is missing in " + dir);
    std::ifstream in(path);
    std::string line;
    std::getline(in, line);
    while (std::getline(in, line)) {
      if (!line.empty()) all += line + "\n";
    }
    for (auto& row : read_rollouts(path)) rows.push_back(std::move(row));
  }
  lanechange::detail::write_file_atomically((fs::path(dir) / "rollouts.csv").string(), all);
  std::map<std::pair<std::string, std::string>, std::vector<const Row*>> groups;
  std::vector<std::string> order;
  for (const Row& r : rows) {
    if (std::find(order.begin(), order.end(), r.planner) == order.end()) order.push_back(r.planner);
    groups[{r.planner, r.behavior}].push_back(&r);
    groups[{r.planner, "all"}].push_back(&r);
  }
  std::string text = csv_header(summary_columns());
  for (const std::string& planner : order) {
    for (const auto& [key, members] : groups) {
      if (key.first == planner) text += summary_row(key.first, key.second, members);
    }
  }
  lanechange::detail::write_file_atomically((fs::path(dir) / "summary.csv").string(), text);
}

}  // namespace detail

}  // namespace lanechange::sim
