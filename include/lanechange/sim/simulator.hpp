#pragma once
// The closed loop (docs/closed_loop.md): a planner acts every dt against the
// real motion of the other cars. The ego moves by the exact unicycle, the
// others by their behavior (IDM reacting to the real ego), and one judge
// gives every planner's rollout its outcome.
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>
#include <vector>

#include "lanechange/config.hpp"
#include "lanechange/planner/planner.hpp"
#include "lanechange/scenario.hpp"
#include "lanechange/trajectory.hpp"

namespace lanechange::sim {

/// The judge's verdict on a realised path.
enum class Outcome {
  WellPosed,  ///< success: in the target lane, no reversal, heading under the limit
  IllPosed,   ///< in the target lane, but with a reversal or a final heading over the limit
  Failure,    ///< not in the target lane (having left its own), or a collision
  Aborted,    ///< stayed in its own lane, without collision: the planner chose not to change
};
[[nodiscard]] std::string_view to_string(Outcome outcome);
[[nodiscard]] Outcome outcome_from_string(std::string_view name);

struct SimOptions {
  double duration = 0.0;  ///< s; 0: the scene's horizon plus closed_loop.settle_time
};

/// One step of a rollout, as the planner and the simulator saw it.
struct StepRecord {
  double compute_ms = 0.0;
  planner::ActStatus status = planner::ActStatus::Planned;  ///< who acted
  /// What the planner decided: an overrun hands a take-over's step to the
  /// fallback, but the take-over was still made then.
  planner::ActStatus decided = planner::ActStatus::Planned;
  bool lane_keeping = false;  ///< the manoeuvre was over: the lane keeper drove
  bool clipped = false;       ///< the simulator clipped the control to the limits
  bool overrun = false;       ///< the planner took longer than its budget
  std::string reason;
};

/// What evaluate tabulates per rollout.
struct RolloutMetrics {
  double time_to_target_lane = -1.0;  ///< s until |y - w| <= labels.reach first; -1: never
  /// s until the ego's centre first crossed into the target lane (y >= w / 2),
  /// as a recorded driver's change is timed; -1: never
  double time_to_lane_line = -1.0;
  double min_gap = 0.0;  ///< m, bumper to bumper, to a car in a lane the ego's body touches
  double min_ttc = 0.0;  ///< s, to such a car while closing in; infinity if never closing
  double max_abs_accel = 0.0;
  double rms_jerk = 0.0;  ///< m/s^3, of the applied acceleration
  double max_abs_omega = 0.0;
  double median_step_ms = 0.0;
  double p99_step_ms = 0.0;
  double max_step_ms = 0.0;
  int takeovers = 0;
  double first_takeover_t = -1.0;  ///< s of the first take-over; -1: none
  int fallbacks = 0;
  int clipped = 0;
  int overruns = 0;
  int failures = 0;  ///< steps where the planner threw
  /// Where the ego ends against Eq. 1's gap, if its centre ends in the
  /// target lane: "follower_target_gap" (between the scene's follower and
  /// target), "ahead_of_target" or "behind_follower"; empty otherwise.
  std::string target_lane_slot;
  /// m/s^2: the hardest braking the ego forced on a car following it (0:
  /// none), and whether that exceeded closed_loop.unsafe_decel.
  double forced_decel = 0.0;
  bool unsafe_cut_in = false;
  double max_car_decel = 0.0;  ///< m/s^2: the hardest braking of any other car
  bool cars_collide = false;   ///< two other cars overlapped at some node
};

struct Rollout {
  Outcome outcome = Outcome::Failure;
  std::string reason;     ///< the judge's words
  Trajectory trajectory;  ///< formats.md; others = the real motion
  std::vector<StepRecord> steps;
  RolloutMetrics metrics;
  double manoeuvre_over_at = -1.0;  ///< s; -1 if the ego never settled in the target lane
  /// A collision the ego caused: anything but being run into from behind by
  /// a car of the lane its body has been wholly in for at least 1 s (a
  /// constant-speed or constant-acceleration car does not react to the ego).
  bool collision_at_fault = false;
  /// m/s^2: the hardest braking of a car whose step the ego ahead of it set.
  double forced_decel = 0.0;
};

/// Runs one rollout of `planner` from `scene` (its fields override `config`).
[[nodiscard]] Rollout simulate(const Scenario& scene, const planner::ClosedLoopPlanner& planner,
                               const Config& config, const SimOptions& options = {});

/// The judge, on a realised path: the labeller of the plans (NOTES.md) plus
/// "aborted" for a path that never left its lane, and failure for any
/// collision.
[[nodiscard]] Outcome judge(const Trajectory& path, const Config& config, std::string& reason);

/// The rollout as formats.md's trajectory JSON, with the outcome, the step
/// records and the metrics added.
[[nodiscard]] nlohmann::json rollout_to_json(const Rollout& rollout);
/// "-" writes to standard output; a file is written atomically.
void save_rollout(const Rollout& rollout, const std::string& path);

}  // namespace lanechange::sim
