#pragma once
// An independent check of a plan or rollout against its scenario: it uses
// nothing of the planner that made it, only the ego model, the limits, the
// labeller and the collision check.
#include <string>
#include <vector>

#include "lanechange/config.hpp"
#include "lanechange/scenario.hpp"
#include "lanechange/trajectory.hpp"

namespace lanechange {

struct AuditTolerances {
  double dynamics = 1e-6;  ///< m, m/s, rad: states against the re-simulated controls
  double controls = 1e-6;  ///< on the bounds of a and omega
  /// On the bounds of v and y. A plan's states are its controls run through
  /// the nonlinear model, which the last linearization approximates to about
  /// a centimetre; the plan reports that as linearization_defect.
  double states = 0.05;
};

/// Everything wrong with the trajectory, one sentence each; empty if nothing.
[[nodiscard]] std::vector<std::string> audit_trajectory(const Trajectory& trajectory,
                                                        const Scenario& scenario,
                                                        const Config& config,
                                                        const AuditTolerances& tol = {});

}  // namespace lanechange
