#pragma once
// The files of an evaluation directory (docs/closed_loop.md), shared by the
// run (evaluate.cpp) and its tables (summary.cpp).
#include <string>
#include <vector>

#include "lanechange/sim/evaluate.hpp"

namespace lanechange::sim::detail {

/// rollouts-SSSSS.csv: the rows of shard s.
[[nodiscard]] std::string shard_file(long long shard);

/// The columns joined by commas, with the line's end.
[[nodiscard]] std::string csv_header(const std::vector<std::string>& columns);

/// rollouts.csv (the shards in order) and summary.csv, from the shard files.
void write_results(const std::string& dir, long long shards);
/// human.csv in `dir`: one row per planner (docs/recorded.md).
void write_human_comparison(const std::string& dir, const std::vector<HumanComparison>& rows);

}  // namespace lanechange::sim::detail
