#pragma once
// A plan or a rollout in the "lanechange.trajectory/1" format (formats.md).
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>
#include <vector>

#include "lanechange/checks.hpp"
#include "lanechange/ego.hpp"
#include "lanechange/traffic.hpp"

namespace lanechange {

inline constexpr std::string_view kTrajectoryFormat = "lanechange.trajectory/2";
/// The earlier format, read still: the paper's three cars, keyed by role.
inline constexpr std::string_view kTrajectoryFormatThreeCars = "lanechange.trajectory/1";

/// Who a track of Trajectory::others is.
struct TrackedCar {
  std::string id;
  Lane lane = Lane::Target;
  VehicleSize size;
};

/// The scene's cars as a trajectory names them.
[[nodiscard]] std::vector<TrackedCar> tracked_cars(const Scenario& scenario);

struct Trajectory {
  std::string planner;
  Label label = Label::Failure;
  std::string reason;  ///< why the label; empty for well-posed
  double dt = 0.0;
  std::vector<double> t;
  std::vector<EgoState> ego;         ///< one per node; ego[k].a is applied from t[k]
  std::vector<EgoControl> controls;  ///< one per node; the last repeats the one before
  TrafficPrediction others;          ///< predicted (plan) or simulated (rollout)
  std::vector<TrackedCar> cars;      ///< who each track of `others` is
  bool collision = false;
  double compute_total_ms = 0.0;
  double compute_max_step_ms = 0.0;
  double lane_width = 0.0;
  /// As the scene's: a right-hand change is written as the mirror image of
  /// what is held here (y, theta and omega negated) and read back the same way.
  Side target_side = Side::Left;
  /// Planner-specific extra fields (objective, iterations, ...), written at top level.
  nlohmann::json details = nlohmann::json::object();

  [[nodiscard]] int nodes() const { return static_cast<int>(t.size()); }
  [[nodiscard]] std::vector<double> ys() const;
};

/// A failed plan: label failure, the reason, the initial state only.
[[nodiscard]] Trajectory failed_trajectory(std::string planner, const Scenario& scenario,
                                           std::string reason);

[[nodiscard]] nlohmann::json trajectory_to_json(const Trajectory& trajectory);
/// Throws InputError naming the field on a malformed file.
[[nodiscard]] Trajectory trajectory_from_json(const nlohmann::json& in);
[[nodiscard]] Trajectory load_trajectory(const std::string& path);
/// "-" writes to standard output; a file is written atomically.
void save_trajectory(const Trajectory& trajectory, const std::string& path);

}  // namespace lanechange
