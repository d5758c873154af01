#pragma once
// A lane-change scenario (spec/formats.md, "lanechange.scenario/1"): the ego,
// the leader in its lane, and the follower and target (leader) in the lane to
// its left. x is along the road, y across it; x and y locate a car's centre.
#include <array>
#include <nlohmann/json_fwd.hpp>
#include <optional>
#include <string>
#include <string_view>

#include "lanechange/config.hpp"

namespace lanechange {

inline constexpr std::string_view kScenarioFormat = "lanechange.scenario/1";

enum class Behavior { ConstantSpeed, ConstantAccel, Idm };

[[nodiscard]] std::string_view to_string(Behavior behavior);
/// Throws InputError naming `field` for an unknown name.
[[nodiscard]] Behavior behavior_from_string(std::string_view name,
                                            const std::string& field = "behavior");

struct EgoState {
  double x = 0.0;
  double y = 0.0;
  double v = 0.0;
  double theta = 0.0;
  double a = 0.0;
};

/// A car that stays in its lane.
struct CarState {
  double x = 0.0;
  double v = 0.0;
  double a = 0.0;
};

enum class Car { Leader, Follower, Target };
inline constexpr Car kAllCars[] = {Car::Leader, Car::Follower, Car::Target};
[[nodiscard]] std::string_view to_string(Car car);

struct Scenario {
  double lane_width = 3.75;
  Behavior behavior = Behavior::ConstantSpeed;
  EgoState ego;
  CarState leader;
  CarState follower;
  CarState target;
  // The optional fields of the format, filled from the config when absent.
  double horizon = 5.0;
  int steps = 50;
  VehicleSize vehicle;
  IdmParameters idm;
  SafetyMargins safe_distance;
  Limits limits;
  /// A car's own body where the scene gives one (recorded traffic: trucks,
  /// vans); absent, the car has `vehicle`'s, as the ego does.
  std::array<std::optional<VehicleSize>, 3> car_size;

  [[nodiscard]] const CarState& car(Car which) const;
  [[nodiscard]] VehicleSize size_of(Car which) const;
  /// Bumper to bumper between the ego and a car whose centre is dx ahead
  /// (negative: behind) of the ego's.
  [[nodiscard]] double bumper_gap(Car which, double dx) const;
  /// Eq. 1's distances, centre to centre. `safe_distance` is set for a car
  /// of the ego's length; a longer car's centre sits further from its
  /// bumper, so its standstill distance grows by half the difference.
  [[nodiscard]] SafetyMargins centre_safe_distances() const;
  /// One of Eq. 1's distances, `base`, centre to centre to `which`, as above.
  [[nodiscard]] SafeDistance centre_safe_distance(Car which, SafeDistance base) const;
  [[nodiscard]] CarState& car(Car which);
  /// Lane centre of a car: 0 for the leader, lane_width for the others.
  [[nodiscard]] double lane_center(Car which) const;
  /// The ego's speed bounds at time t of a plan. An ego that starts outside
  /// limits.v (recorded traffic) meets them from the first moment full
  /// braking or acceleration can reach them; inside them, limits.v.
  [[nodiscard]] Interval speed_bounds_at(double t) const;
};

/// A scenario with every optional field taken from `defaults`.
[[nodiscard]] Scenario default_scenario(const Config& defaults);

/// Parses and validates. Throws InputError naming the field for every bad
/// input of formats.md: a missing field, an unknown behavior, a non-finite
/// number, a negative speed or lane width, or cars that overlap at t = 0.
[[nodiscard]] Scenario scenario_from_json(const nlohmann::json& in, const Config& defaults);
[[nodiscard]] Scenario scenario_from_text(const std::string& text, const Config& defaults);
[[nodiscard]] Scenario load_scenario(const std::string& path, const Config& defaults);

/// Writes every field, the optional ones included.
[[nodiscard]] nlohmann::json scenario_to_json(const Scenario& scenario);
void save_scenario(const Scenario& scenario, const std::string& path);

/// Physical checks that do not depend on the JSON: speeds, geometry, overlap.
void validate_scenario(const Scenario& scenario);

/// The config with the scenario's own lane width, horizon, vehicle, IDM,
/// safety and limits in place of the defaults.
[[nodiscard]] Config effective_config(const Config& base, const Scenario& scenario);

}  // namespace lanechange
