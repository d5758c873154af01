#pragma once
// The --planner(s) option of evaluate and experiments: one spelling for both.
#include <sstream>
#include <string>
#include <vector>

namespace lanechange::app {

/// "a,b,,c" -> {a, b, c}: an empty name (a doubled or trailing comma) is
/// skipped; unknown names are left for the planner registry to name.
[[nodiscard]] inline std::vector<std::string> planner_list(const std::string& comma_separated) {
  std::vector<std::string> names;
  std::stringstream in(comma_separated);
  for (std::string name; std::getline(in, name, ',');) {
    if (!name.empty()) names.push_back(name);
  }
  return names;
}

}  // namespace lanechange::app
