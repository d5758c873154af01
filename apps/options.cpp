#include <sstream>

#include "commands.hpp"
#include "lanechange/baselines/baselines.hpp"

namespace lanechange::app {

void add_behavior_option(CLI::App& cmd, std::string& behavior) {
  behavior = "all";
  cmd.add_option("--behavior", behavior,
                 "constant_speed, constant_accel, idm, or all (drawn per scene)")
      ->capture_default_str();
}

std::optional<Behavior> behavior_option(const std::string& behavior) {
  if (behavior == "all") return std::nullopt;
  return behavior_from_string(behavior, "--behavior");
}

void add_planner_option(CLI::App& cmd, std::string& planners, const std::string& what) {
  std::string names;
  for (const auto& name : baselines::planner_names()) {
    if (!names.empty()) names += ", ";
    names += name;
  }
  cmd.add_option("--planner", planners, what + ": " + names)->capture_default_str();
}

std::vector<std::string> planner_list(const std::string& comma_separated) {
  std::vector<std::string> names;
  std::stringstream in(comma_separated);
  for (std::string name; std::getline(in, name, ',');) {
    if (!name.empty()) names.push_back(name);
  }
  return names;
}

}  // namespace lanechange::app
