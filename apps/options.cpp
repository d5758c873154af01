#include <cmath>
#include <sstream>
#include <stdexcept>

#include "commands.hpp"
#include "lanechange/baselines/baselines.hpp"
#include "lanechange/error.hpp"

namespace lanechange::app {

void add_behavior_option(CLI::App& cmd, std::string& behavior) {
  behavior = "all";
  cmd.add_option("--behavior", behavior,
                 "constant_speed, constant_accel, idm, or all (drawn per scene)")
      ->capture_default_str();
}

std::optional<Behavior> behavior_option(const std::string& behavior) {
  if (behavior == "all") return std::nullopt;
  const Behavior b = behavior_from_string(behavior, "--behavior");
  if (b == Behavior::Replay) {
    throw InputError("--behavior", "replay needs recorded cars (lanechange import-commonroad)");
  }
  return b;
}

void add_traffic_option(CLI::App& cmd, std::string& target_lane_cars) {
  cmd.add_option("--target-lane-cars", target_lane_cars,
                 "Dense traffic: N, or LO,HI drawn per scene, cars in the target lane with a "
                 "leader and a car behind in the ego lane (sampler.target_lane_cars; 0: the "
                 "paper's three cars)");
}

Config with_target_lane_cars(Config config, const std::string& option) {
  if (option.empty()) return config;
  const auto comma = option.find(',');
  const auto count = [&](const std::string& text) {
    std::size_t used = 0;
    double value = -1.0;
    try {
      value = std::stod(text, &used);
    } catch (const std::exception&) {
      used = 0;
    }
    if (used != text.size() || value < 0.0 || value > 100.0 || value != std::floor(value)) {
      throw InputError(
          "--target-lane-cars",
          "must be N or LO,HI, whole numbers of cars in [0, 100], not \"" + option + "\"");
    }
    return value;
  };
  const double lo = count(option.substr(0, comma));
  const double hi = comma == std::string::npos ? lo : count(option.substr(comma + 1));
  if (hi < lo) throw InputError("--target-lane-cars", "LO must not exceed HI");
  config.sampler.target_lane_cars = {lo, hi};
  return config;
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
