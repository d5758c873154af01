#pragma once
// The one quantile definition of every table and report: the nearest rank
// (the smallest value with at least a share q of the values at or below it),
// so that a reported p99 is a value that was measured.
#include <vector>

namespace lanechange::run {

/// The q-quantile (q in [0, 1]) of the finite values, by nearest rank; NaN
/// where none is finite. q = 0 gives the smallest, q = 1 the largest.
[[nodiscard]] double nearest_rank(std::vector<double> values, double q);

/// The same of values already sorted ascending and all finite (no copy).
[[nodiscard]] double nearest_rank_sorted(const std::vector<double>& sorted, double q);

}  // namespace lanechange::run
