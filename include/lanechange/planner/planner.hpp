#pragma once
// Closed-loop planners (docs/closed_loop.md). A planner is const and shared by
// every thread; each rollout gets its own session, which holds what the
// planner remembers between steps (the last plan, the classifier's verdict).
// Every step the session sees an observation, never the other cars' future,
// and answers with a control and a status.
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "lanechange/config.hpp"
#include "lanechange/ego.hpp"
#include "lanechange/scenario.hpp"

namespace lanechange::planner {

/// What a planner sees at step k: the initial scene, the time, and the
/// current state of every car.
struct Observation {
  const Scenario* scene = nullptr;  ///< the initial scene (t = 0)
  int step = 0;
  double t = 0.0;  ///< s since the start
  EgoState ego;    ///< ego.a is the acceleration applied in the last step
  /// Every car of the scene, in its order; a is the acceleration it drives
  /// by (TrafficModel::observed).
  std::vector<CarState> cars;
  [[nodiscard]] const CarState& car(CarIndex which) const { return cars[which]; }
  [[nodiscard]] const CarState& car(Role role) const { return cars[scene->index_of(role)]; }
};

/// Who produced a step's control.
enum class ActStatus {
  Planned,   ///< the planner's own method (the expert's plan, the network)
  TookOver,  ///< the hierarchical planner's check overruled its network: the expert acts
  Fallback,  ///< no lane change (any more): the lane keeper in the ego lane acts
  Failed,    ///< the planner could not act (it threw or overran); the simulator falls back
};
[[nodiscard]] std::string_view to_string(ActStatus status);

struct Decision {
  EgoControl control;
  ActStatus status = ActStatus::Planned;
  std::string reason;  ///< why a take-over or fallback happened; empty otherwise
};

/// One rollout's state.
class PlannerSession {
 public:
  virtual ~PlannerSession() = default;
  [[nodiscard]] virtual Decision act(const Observation& observation) = 0;
};

class ClosedLoopPlanner {
 public:
  virtual ~ClosedLoopPlanner() = default;
  [[nodiscard]] virtual std::string_view name() const = 0;
  /// A fresh session for a rollout of `scene` (the scene's own fields
  /// override the planner's config, as for a plan).
  [[nodiscard]] virtual std::unique_ptr<PlannerSession> start(const Scenario& scene) const = 0;
};

/// A car of the lane keeper's lane, with its length for the bumper gap.
struct LaneCar {
  CarIndex car = 0;
  CarState state;
  double length = 0.0;
};

/// The lane keeper: follows the car ahead in its lane by IDM, keeps up with a
/// faster car closing in from behind (closed_loop.keeper_rear_horizon), and
/// steers to the lane centre. It is the fallback of every planner (in the
/// ego lane, behind the leader) and drives on once a lane change is over (in
/// the target lane, behind the target). Pure and const.
class LaneKeeper {
 public:
  explicit LaneKeeper(const Config& config) : config_(config) {}
  /// The control that keeps `lane_center`, behind `ahead` (none: free road)
  /// and ahead of `behind` (none: no car behind).
  [[nodiscard]] EgoControl control(const EgoState& ego, double lane_center,
                                   const std::optional<LaneCar>& ahead,
                                   const std::optional<LaneCar>& behind = std::nullopt) const;
  /// The yaw rate of a cut-in backed out of: the keeper's steering with
  /// closed_loop.keeper_backout_heading as its largest heading.
  [[nodiscard]] double back_out(const EgoState& ego, double lane_center) const;

  static constexpr double kCalmHeading = 0.15;  ///< rad: keeping a lane, never a swerve

 private:
  /// The yaw rate that closes the offset to `lane_center` along a heading of
  /// at most `max_heading`.
  [[nodiscard]] double steer(const EgoState& ego, double lane_center, double max_heading) const;
  [[nodiscard]] double keep_up(double ego_x, double speed, double gap_ahead, double ahead_speed,
                               const LaneCar& behind) const;
  Config config_;
};

/// The nearest car ahead of the ego in a lane (the target lane, or the ego
/// lane), none on a free road.
[[nodiscard]] std::optional<LaneCar> car_ahead(const Observation& observation, bool target_lane);

/// The nearest car behind the ego in a lane, none where no car is.
[[nodiscard]] std::optional<LaneCar> car_behind(const Observation& observation, bool target_lane);

/// Whether the fallback keeps to the target lane: once the ego's centre is
/// over the line (turning back from there is the riskier move), unless the
/// target lane breaks the expert's safe distances around the ego more than
/// the ego lane does (a cut-in gone wrong: back out of it).
[[nodiscard]] bool fallback_in_target_lane(const Observation& observation);

/// The fallback's control: the lane keeper in the lane fallback_in_target_lane
/// chooses.
[[nodiscard]] EgoControl fallback_control(const LaneKeeper& keeper, const Observation& observation);

/// True when the ego's body (centre y) stays within the outer edges of the two
/// lanes: the road, not the expert's planning margin.
[[nodiscard]] bool body_on_road(double y, const Scenario& scene);

/// Clips a control to the ego's limits, also keeping the speed within its
/// bounds over the next step. Returns true when it had to.
bool clip_to_limits(EgoControl& control, const EgoState& ego, const Limits& limits, double dt);

/// The planners by name: "miqp" (the exact expert, re-planning), "mlp-miqp", and the fallback
/// (the lane keeper alone: never changes lanes; named "keep-lane"). Throws InputError for an
/// unknown name.
/// "mlp-miqp" (Algorithm 1) and "strategy-qp" (docs/strategy.md) load their models from
/// `model_dir`.
[[nodiscard]] std::shared_ptr<const ClosedLoopPlanner> make_planner(
    std::string_view name, const Config& config, const std::string& model_dir = "");
[[nodiscard]] std::vector<std::string> planner_names();

}  // namespace lanechange::planner
