#pragma once
#include <string>

namespace lanechange::run {

/// `text` as one CSV field: quoted (RFC 4180) where it holds a comma, a quote
/// or a line break, which becomes a space so that each record is one line.
[[nodiscard]] std::string csv_field(const std::string& text);

}  // namespace lanechange::run
