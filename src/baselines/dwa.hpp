#pragma once
// The dynamic window approach (Fox, Burgard and Thrun 1997) for the unicycle
// (docs/baselines.md, "dwa"): every step, sample (a, omega) in the
// window reachable from the last control within one step, roll each out at
// constant control against the predicted cars, keep the admissible ones and
// apply the best scored.
#include <memory>
#include <vector>

#include "lanechange/planner/planner.hpp"

namespace lanechange::baselines {

/// The controls reachable within one step of dt from `last`, under the
/// assumed jerk and yaw acceleration, within the limits of a and omega.
struct DynamicWindow {
  Interval a;
  Interval omega;
};
[[nodiscard]] DynamicWindow dynamic_window(EgoControl last, const Limits& limits,
                                           const DwaSettings& settings, double dt);

/// `steps` steps of dt at the constant control `u` (the planner's model,
/// step_trapezoidal), saturated at the limits as the simulator clips;
/// steps + 1 states, the first being `from`.
[[nodiscard]] std::vector<EgoState> constant_control_rollout(const EgoState& from, EgoControl u,
                                                             int steps, double dt,
                                                             const Limits& limits);

class DwaPlanner final : public planner::ClosedLoopPlanner {
 public:
  explicit DwaPlanner(Config config) : config_(std::move(config)) {}
  [[nodiscard]] std::string_view name() const override { return "dwa"; }
  [[nodiscard]] std::unique_ptr<planner::PlannerSession> start(
      const Scenario& scene) const override;

 private:
  Config config_;
};

[[nodiscard]] std::shared_ptr<const planner::ClosedLoopPlanner> make_dwa_planner(
    const Config& config);

}  // namespace lanechange::baselines
