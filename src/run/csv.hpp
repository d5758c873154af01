#pragma once
#include <string>

namespace lanechange::run {

/// `text` as one CSV field: quoted (RFC 4180) where it holds a comma, a quote
/// or a line break, which becomes a space so that each record is one line.
[[nodiscard]] std::string csv_field(const std::string& text);

/// `v` as a CSV number of `significant_digits`; empty where it is not finite
/// (a quantity the row does not have, such as a time never reached).
[[nodiscard]] std::string csv_number(double v, int significant_digits);

}  // namespace lanechange::run
