#include "run/csv.hpp"

#include <cmath>
#include <sstream>

namespace lanechange::run {

std::string csv_field(const std::string& text) {
  if (text.find_first_of(",\"\r\n") == std::string::npos) return text;
  std::string quoted = "\"";
  for (char c : text) {
    // One record per line keeps the files countable with wc -l and readable
    // by line-based tools; a line break in a message carries no meaning.
    if (c == '\n' || c == '\r') c = ' ';
    quoted += c == '"' ? std::string("\"\"") : std::string(1, c);
  }
  return quoted + "\"";
}

std::string csv_number(double v, int significant_digits) {
  if (!std::isfinite(v)) return "";
  std::ostringstream out;
  out.precision(significant_digits);
  out << v;
  return out.str();
}

}  // namespace lanechange::run
