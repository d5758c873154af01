#include "lanechange/run/quantile.hpp"

#include <algorithm>
#include <cmath>
#include <cstddef>

namespace lanechange::run {

namespace {

std::size_t rank_index(std::size_t count, double q) {
  const double rank = std::ceil(std::clamp(q, 0.0, 1.0) * static_cast<double>(count));
  return static_cast<std::size_t>(std::max(1.0, rank)) - 1;
}

}  // namespace

double nearest_rank(std::vector<double> values, double q) {
  std::erase_if(values, [](double v) { return !std::isfinite(v); });
  if (values.empty()) return NAN;
  const auto at = values.begin() + static_cast<std::ptrdiff_t>(rank_index(values.size(), q));
  std::nth_element(values.begin(), at, values.end());
  return *at;
}

double nearest_rank_sorted(const std::vector<double>& sorted, double q) {
  if (sorted.empty()) return NAN;
  return sorted[rank_index(sorted.size(), q)];
}

}  // namespace lanechange::run
