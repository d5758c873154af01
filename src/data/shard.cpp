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
      out.gap_slot = expert::gap_slots(scenario).slot_of(result.gap);
      const auto id = [&scenario](std::optional<CarIndex> c) {
        return c ? scenario.cars[*c].id : std::string();
      };
      out.gap_behind = id(result.gap.car_behind());
      out.gap_ahead = id(result.gap.car_ahead());
      out.gap_frame = expert::frame_of(result.gap);
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

namespace {

int rank(Label label) { return label == Label::WellPosed ? 2 : label == Label::IllPosed ? 1 : 0; }

}  // namespace

void label_gaps(const expert::ExpertPlanner& planner, const Scenario& scenario, double time_limit_s,
                PlanOutcome& outcome) {
  const expert::GapSlots slots = expert::gap_slots(scenario);
  for (int slot = 0; slot < expert::kGapSlots; ++slot) {
    const auto& gap = slots.gaps[static_cast<std::size_t>(slot)];
    auto& label = outcome.slot_labels[static_cast<std::size_t>(slot)];
    label.reset();
    if (!gap) continue;
    expert::PlanHints through;
    through.gap = &*gap;
    label = plan_outcome(planner, scenario, time_limit_s, through).label;
    // Successive linearization from another start can end worse: the plan
    // over every gap is also a plan through the gap it took.
    if (slot == outcome.gap_slot && rank(outcome.label) > rank(*label)) label = outcome.label;
  }
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
