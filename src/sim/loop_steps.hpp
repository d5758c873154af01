#pragma once
// The parts of a closed loop that do not depend on what moves the other cars
// (our traffic model, or a co-simulated traffic simulator): asking the
// planner, handing over to the lane keeper, and judging the rollout.
#include "lanechange/planner/planner.hpp"
#include "lanechange/sim/simulator.hpp"

namespace lanechange::sim::detail {

/// The planner's answer, timed into `record`; a throw, or an overrun under a
/// wall-clock deadline, hands the step to the fallback.
[[nodiscard]] EgoControl ask_planner(planner::PlannerSession& session,
                                     const planner::Observation& observation, const Config& config,
                                     const planner::LaneKeeper& keeper, StepRecord& record);

/// The lane keeper's control in the ego lane, or the target lane, behind
/// the car ahead there and ahead of the car behind.
[[nodiscard]] EgoControl keep_lane(const planner::LaneKeeper& keeper,
                                   const planner::Observation& observation, bool target_lane);

/// Whether the manoeuvre is over: the ego settled on the target lane's
/// centre, after which the lane keeper drives it there.
class SettleCheck {
 public:
  SettleCheck(const Config& config, double lane_width) : config_(config), lane_width_(lane_width) {}
  /// Takes the ego's state after a step; true from the step it settles on.
  bool settled(const EgoState& ego);

 private:
  const Config& config_;
  double lane_width_;
  bool over_ = false;
  double peak_y_ = -INFINITY;
};

/// Judges a recorded rollout (its trajectory, steps and forced_decel, with
/// `scene` naming every track of the trajectory) and fills in its outcome,
/// reason, collision, gap and metrics.
void finish_rollout(Rollout& rollout, const Scenario& scene, const Config& config);

}  // namespace lanechange::sim::detail
