#include "data/shard.hpp"

#include <cstdio>
#include <filesystem>
#include <fstream>

#include "lanechange/data/dataset.hpp"

namespace lanechange::data {

namespace {

std::string shard_name(const char* kind, long long shard) {
  char name[64];
  std::snprintf(name, sizeof name, "%s-%05lld.csv", kind, shard);
  return name;
}

}  // namespace

std::string scenarios_file(long long shard) { return shard_name("scenarios", shard); }
std::string samples_file(long long shard) { return shard_name("samples", shard); }
std::string timing_file(long long shard) { return shard_name("timing", shard); }

}  // namespace lanechange::data

namespace lanechange::data {

long long shard_count(long long count, long long shard_size) {
  return (count + shard_size - 1) / shard_size;
}

ShardRange shard_range(long long shard, long long count, long long shard_size) {
  const long long first = shard * shard_size;
  return {shard, first, std::min(shard_size, count - first)};
}

PlanOutcome plan_outcome(const expert::ExpertPlanner& planner, const Scenario& scenario,
                         double time_limit_s, const expert::PlanHints& hints) {
  PlanOutcome out;
  try {
    const expert::ExpertResult result = planner.plan(scenario, {time_limit_s}, hints);
    Trajectory trajectory = planner.to_trajectory(result, scenario);
    out.status = std::string(expert::to_string(result.status));
    out.label = trajectory.label;
    out.reason = trajectory.reason;
    out.collision = trajectory.collision;
    out.objective = result.objective;
    out.iterations = result.iterations();
    out.solve_ms = result.total_ms;
    // A plan without a solution has no samples to learn from.
    if (!result.path.states.empty()) {
      out.trajectory = std::move(trajectory);
      for (const auto& lanes : result.occupancy) {
        out.lane_modes.push_back(lanes ? static_cast<int>(*lanes) : -1);
      }
    }
  } catch (const std::exception& e) {
    // One bad scenario must not end a run of thousands: it becomes a
    // failure row that says what happened.
    out = PlanOutcome{};
    out.status = "exception";
    out.reason = std::string("the planner threw: ") + e.what();
    out.objective = expert::kInfinity;
  }
  return out;
}

ShardFiles::ShardFiles(const std::string& dir, long long shard)
    : scenarios_((std::filesystem::path(dir) / scenarios_file(shard)).string()),
      samples_((std::filesystem::path(dir) / samples_file(shard)).string()),
      timing_((std::filesystem::path(dir) / timing_file(shard)).string()) {
  write(header_rows());
}

void ShardFiles::write(const ScenarioRows& rows) {
  scenarios_.write(rows.scenarios);
  samples_.write(rows.samples);
  timing_.write(rows.timing);
}

void ShardFiles::commit() {
  timing_.commit();
  samples_.commit();
  scenarios_.commit();
}

long long count_rows(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return -1;
  long long lines = 0;
  std::string line;
  while (std::getline(in, line)) ++lines;
  return lines - 1;
}

bool shard_finished(const ShardRange& range, const std::string& dir) {
  const std::filesystem::path d(dir);
  return count_rows((d / scenarios_file(range.shard)).string()) == range.count &&
         count_rows((d / timing_file(range.shard)).string()) == range.count &&
         count_rows((d / samples_file(range.shard)).string()) >= 0;
}

}  // namespace lanechange::data
