#pragma once
// A lane-change scenario (docs/scenarios.md): the ego and any number of other
// cars on a two-lane road, the ego lane centred at y = 0 and the target lane
// to its left at y = lane_width. x is along the road, y across it; x and y
// locate a car's centre. Format 1 holds the paper's three cars; format 2 any.
#include <array>
#include <cstddef>
#include <nlohmann/json_fwd.hpp>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "lanechange/config.hpp"

namespace lanechange {

inline constexpr std::string_view kScenarioFormat = "lanechange.scenario/1";
inline constexpr std::string_view kScenarioFormatCars = "lanechange.scenario/2";

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

enum class Lane { Ego, Target };
[[nodiscard]] std::string_view to_string(Lane lane);

/// Where the target lane lies as the ego drives: to its left (y > 0) or right.
enum class Side { Left, Right };
[[nodiscard]] std::string_view to_string(Side side);
/// -1 for a right-hand change, whose files hold the mirror image of the scene
/// every stage plans (y, theta and omega negated), else 1.
[[nodiscard]] inline double mirror_sign(Side side) { return side == Side::Right ? -1.0 : 1.0; }

/// The paper's three cars: the car ahead of the ego in its lane, and the two
/// that frame Eq. 1's gap in the target lane. A scene of any size may give
/// each role to one of its cars.
enum class Role { Leader, Follower, Target };
inline constexpr Role kRoles[] = {Role::Leader, Role::Follower, Role::Target};
[[nodiscard]] std::string_view to_string(Role role);

/// A car's place in Scenario::cars, and in every list of cars made from a
/// scene (observations, predictions, trajectories).
using CarIndex = std::size_t;

/// A car's recorded motion along its lane from the scene's start: x and v at
/// times k * dt. A replayed car moves by it, and past its end on at its last
/// speed.
struct RecordedTrack {
  double dt = 0.1;
  std::vector<double> x;
  std::vector<double> v;
  /// The state at time t >= 0, linearly interpolated between samples; `a` is
  /// the slope of v there.
  [[nodiscard]] CarState at(double t) const;
};

/// Another car: it keeps to its lane and moves by its behavior.
struct OtherCar {
  std::string id;
  Lane lane = Lane::Target;
  CarState state;
  Behavior behavior = Behavior::ConstantSpeed;
  /// Its own body where the scene gives one (recorded traffic: trucks,
  /// vans); absent, the car has the scene's `vehicle`, as the ego does.
  std::optional<VehicleSize> size;
  /// A replayed car's record (Behavior::Replay); none for any other car.
  std::optional<RecordedTrack> record;
};

/// The recorded driver's own change into the target lane, in a scene cut
/// from recorded traffic.
struct HumanLaneChange {
  double after = 0.0;  ///< s from the scene's start until its centre entered the target lane
  /// The ids of the target-lane cars nearest behind and ahead of it then;
  /// none where that side of the lane was empty.
  std::optional<std::string> behind;
  std::optional<std::string> ahead;
};

/// Where a scene cut from a recording comes from (docs/recorded.md).
struct SceneOrigin {
  std::string recording;  ///< the recording's benchmark id
  double time = 0.0;      ///< the scene's t = 0 in the recording, s
  std::string ego;        ///< the id of the recorded car or planning problem that is the ego
  bool ego_is_planning_problem = false;
  /// A recorded ego's own change into the target lane; none where it stayed
  /// out of that lane to the recording's end. Always none for a planning problem.
  std::optional<HumanLaneChange> human_change;
};

struct Scenario {
  double lane_width = 3.75;
  /// Inside, the target lane is always to the left; a file with the target
  /// lane to the right is read and written as the mirror image.
  Side target_side = Side::Left;
  /// The scene's behavior: every car's in format 1, the default of a car
  /// that names none in format 2, and the class the tables group by.
  Behavior behavior = Behavior::ConstantSpeed;
  EgoState ego;
  std::vector<OtherCar> cars;
  /// Which car plays each role (Role order); none where no car does.
  std::array<std::optional<CarIndex>, 3> roles;
  // The optional fields of the format, filled from the config when absent.
  double horizon = 5.0;
  int steps = 50;
  VehicleSize vehicle;
  IdmParameters idm;
  SafetyMargins safe_distance;
  Limits limits;
  /// Set for a scene cut from a recording.
  std::optional<SceneOrigin> origin;

  [[nodiscard]] std::size_t car_count() const { return cars.size(); }
  /// The scene's behavior, given to every car.
  void set_behavior(Behavior b);
  [[nodiscard]] const CarState& car(CarIndex which) const { return cars.at(which).state; }
  [[nodiscard]] CarState& car(CarIndex which) { return cars.at(which).state; }
  [[nodiscard]] bool has(Role role) const { return roles[index(role)].has_value(); }
  /// A leader, a follower and a target: what the paper's parts read.
  [[nodiscard]] bool has_every_role() const {
    return has(Role::Leader) && has(Role::Follower) && has(Role::Target);
  }
  /// The car of a role; throws std::logic_error where no car has it.
  [[nodiscard]] CarIndex index_of(Role role) const;
  [[nodiscard]] const CarState& car(Role role) const { return car(index_of(role)); }
  [[nodiscard]] CarState& car(Role role) { return car(index_of(role)); }
  [[nodiscard]] const CarState& leader() const { return car(Role::Leader); }
  [[nodiscard]] const CarState& follower() const { return car(Role::Follower); }
  [[nodiscard]] const CarState& target() const { return car(Role::Target); }
  [[nodiscard]] CarState& leader() { return car(Role::Leader); }
  [[nodiscard]] CarState& follower() { return car(Role::Follower); }
  [[nodiscard]] CarState& target() { return car(Role::Target); }
  [[nodiscard]] VehicleSize size_of(CarIndex which) const;
  [[nodiscard]] VehicleSize size_of(Role role) const { return size_of(index_of(role)); }
  /// Bumper to bumper between the ego and a car whose centre is dx ahead
  /// (negative: behind) of the ego's.
  [[nodiscard]] double bumper_gap(CarIndex which, double dx) const;
  /// One of Eq. 1's distances, `base`, centre to centre to `which`.
  /// `safe_distance` is set for a car of the ego's length; a longer car's
  /// centre sits further from its bumper, so its standstill distance grows by
  /// half the difference.
  [[nodiscard]] SafeDistance centre_safe_distance(CarIndex which, SafeDistance base) const;
  /// Eq. 1's distances to the cars of the three roles, as above; a role no
  /// car has keeps `safe_distance`'s.
  [[nodiscard]] SafetyMargins centre_safe_distances() const;
  /// Lane centre: 0 for the ego lane, lane_width for the target lane.
  [[nodiscard]] double lane_center(Lane lane) const;
  [[nodiscard]] double lane_center(CarIndex which) const {
    return lane_center(cars.at(which).lane);
  }
  /// The index of a car with this id, if any.
  [[nodiscard]] std::optional<CarIndex> find(std::string_view id) const;
  /// The ego's speed bounds at time t of a plan. An ego that starts outside
  /// limits.v (recorded traffic) meets them from the first moment full
  /// braking or acceleration can reach them; inside them, limits.v.
  [[nodiscard]] Interval speed_bounds_at(double t) const;

 private:
  static constexpr std::size_t index(Role role) { return static_cast<std::size_t>(role); }
};

/// A scenario with every optional field taken from `defaults`, and no cars.
[[nodiscard]] Scenario default_scenario(const Config& defaults);
/// default_scenario plus the paper's three cars (ids "leader", "follower",
/// "target", in Role order and with those roles), all at x = 0: the shape of
/// a format-1 scene, for the caller to place.
[[nodiscard]] Scenario three_car_scenario(const Config& defaults);

/// The car of `lane` nearest the position x, ahead of it (x_car > x) or at
/// or behind it, with the cars where `now` puts them (one state per car of
/// `scene`, in its order); none where that side of the lane is empty.
[[nodiscard]] std::optional<CarIndex> nearest_in_lane(const Scenario& scene,
                                                      std::span<const CarState> now, Lane lane,
                                                      double x, bool ahead);

/// The car that plays `role` by the cars' places at t = 0: the nearest car
/// ahead of the ego in its lane (leader), and the cars of the target lane
/// nearest behind (follower) and ahead of (target) the ego's centre.
[[nodiscard]] std::optional<CarIndex> nearest_in_role(const Scenario& scene, Role role);

/// Parses and validates either format. Throws InputError naming the field
/// for every bad input of docs/scenarios.md: a missing or unknown field, an
/// unknown behavior, a non-finite number, a negative speed or lane width, or
/// cars that overlap at t = 0.
[[nodiscard]] Scenario scenario_from_json(const nlohmann::json& in, const Config& defaults);
[[nodiscard]] Scenario scenario_from_text(const std::string& text, const Config& defaults);
[[nodiscard]] Scenario load_scenario(const std::string& path, const Config& defaults);

/// Writes every field, the optional ones included: format 1 for a scene that
/// format 1 can hold (the three cars of three_car_scenario, all of the
/// scene's behavior), else format 2.
[[nodiscard]] nlohmann::json scenario_to_json(const Scenario& scenario);
void save_scenario(const Scenario& scenario, const std::string& path);

/// Physical checks that do not depend on the JSON: speeds, geometry, overlap,
/// unique ids, and roles that fit their cars' lanes and places.
void validate_scenario(const Scenario& scenario);

/// The config with the scenario's own lane width, horizon, vehicle, IDM,
/// safety and limits in place of the defaults.
[[nodiscard]] Config effective_config(const Config& base, const Scenario& scenario);

}  // namespace lanechange
