#pragma once
// One shard: a contiguous range of scenario indices, planned and written as
// three files. Rows are streamed to temporary files as they are made, so a
// worker holds one scenario's rows at a time whatever the shard size. The
// scenarios file is renamed into place last: its presence means the shard is
// finished.
#include <cstdint>
#include <optional>
#include <string>

#include "common/json_fields.hpp"
#include "data/rows.hpp"
#include "lanechange/expert/planner.hpp"
#include "lanechange/sampler.hpp"

namespace lanechange::data {

struct ShardRange {
  long long shard = 0;
  long long first = 0;  ///< first scenario index
  long long count = 0;
};

[[nodiscard]] long long shard_count(long long count, long long shard_size);
[[nodiscard]] ShardRange shard_range(long long shard, long long count, long long shard_size);

/// Plans one scenario; a solver that fails or throws gives a failure row.
[[nodiscard]] PlanOutcome plan_outcome(const expert::ExpertPlanner& planner,
                                       const Scenario& scenario, double time_limit_s,
                                       const expert::PlanHints& hints = {});
/// Fills outcome.slot_labels: the scene planned again through each slot's
/// gap alone, and labelled (a plan that fails or throws is a failure). The
/// slot of the gap `outcome` took keeps the better of that and its label.
void label_gaps(const expert::ExpertPlanner& planner, const Scenario& scenario, double time_limit_s,
                PlanOutcome& outcome);

/// Everything a worker needs to make shards; shared read-only by all threads.
struct ShardMaker {
  const ScenarioSampler& sampler;
  const expert::ExpertPlanner& planner;
  std::optional<Behavior> behavior;
  std::uint64_t seed = 0;
  double time_limit_s = 60.0;
  bool gap_labels = false;  ///< label every gap slot (label_gaps)
};

/// The three files of a shard being written.
class ShardFiles {
 public:
  ShardFiles(const std::string& dir, long long shard);
  void write(const ScenarioRows& rows);
  /// Publishes the files, the scenarios file last.
  void commit();

 private:
  lanechange::detail::AtomicFile scenarios_;
  lanechange::detail::AtomicFile samples_;
  lanechange::detail::AtomicFile timing_;
};

/// Plans the shard's scenarios (calling `planned` after each) and writes its
/// files atomically into dir.
template <class Tick>
void make_shard(const ShardMaker& maker, const ShardRange& range, const std::string& dir,
                Tick&& planned) {
  ShardFiles files(dir, range.shard);
  for (long long i = range.first; i < range.first + range.count; ++i) {
    const auto index = static_cast<std::uint64_t>(i);
    const Scenario scenario = maker.sampler.sample(index, maker.behavior);
    PlanOutcome outcome = plan_outcome(maker.planner, scenario, maker.time_limit_s);
    if (maker.gap_labels) label_gaps(maker.planner, scenario, maker.time_limit_s, outcome);
    files.write(scenario_rows(index, scenario_seed(maker.seed, index), scenario, outcome));
    planned();
  }
  files.commit();
}

/// Whether the shard's files are all there with the expected row count.
[[nodiscard]] bool shard_finished(const ShardRange& range, const std::string& dir);

/// Data lines (all but the header) of a file; -1 if it cannot be read.
[[nodiscard]] long long count_rows(const std::string& path);

}  // namespace lanechange::data
