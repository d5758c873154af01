#pragma once
#include <cmath>
#include <nlohmann/json.hpp>

namespace lanechange::run {

/// JSON has no infinity or NaN: such a value is written as null, which every
/// reader of our files takes as "no value".
[[nodiscard]] inline nlohmann::json number_or_null(double value) {
  return std::isfinite(value) ? nlohmann::json(value) : nlohmann::json(nullptr);
}

}  // namespace lanechange::run
