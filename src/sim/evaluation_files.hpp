#pragma once
// The files of an evaluation directory (docs/closed_loop.md), shared by the
// run (evaluate.cpp) and its tables (summary.cpp).
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>
#include <vector>

#include "lanechange/sim/evaluate.hpp"
#include "lanechange/sim/simulator.hpp"

namespace lanechange::sim::detail {

/// rollouts-SSSSS.csv: the rows of shard s.
[[nodiscard]] std::string shard_file(long long shard);

/// The columns joined by commas, with the line's end.
[[nodiscard]] std::string csv_header(const std::vector<std::string>& columns);

/// Creates the evaluation directory and its manifest, or checks that the
/// manifest there is of an evaluation with these very parameters (InputError
/// naming --out otherwise). Returns true when that evaluation is complete.
[[nodiscard]] bool prepare_directory(const std::string& out_dir, const nlohmann::json& parameters);
/// Marks the manifest complete.
void mark_complete(const std::string& out_dir, const nlohmann::json& parameters);

/// One line of rollouts.csv; `group` fills the behavior column (a behavior,
/// or the traffic of a co-simulation).
[[nodiscard]] std::string rollout_row(long long index, std::string_view group,
                                      const std::string& planner, const Rollout& rollout);

/// rollouts.csv (the shards in order) and summary.csv, from the shard files.
void write_results(const std::string& dir, long long shards);
/// human.csv in `dir`: one row per planner (docs/recorded.md).
void write_human_comparison(const std::string& dir, const std::vector<HumanComparison>& rows);

}  // namespace lanechange::sim::detail
