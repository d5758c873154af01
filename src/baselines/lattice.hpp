#pragma once
// The Frenet lattice planner of Werling et al. 2010, as Apollo's lattice
// planner and TUM's Frenetix follow it (docs/baselines.md,
// "lattice"): on the straight road s = x and d = y. Every step, quintic
// lateral and quartic (speed keeping) or quintic (following) longitudinal
// polynomials are sampled from the current state, priced, and checked in
// order of cost; the cheapest valid one is followed for one step.
#include <memory>
#include <string>
#include <vector>

#include "baselines/polynomial.hpp"
#include "lanechange/planner/planner.hpp"
#include "lanechange/traffic.hpp"

namespace lanechange::baselines {

/// One candidate of the lattice: both axes over the same duration.
struct FrenetCandidate {
  Polynomial lateral;       ///< d(t)
  Polynomial longitudinal;  ///< s(t), s(0) = the ego's x
  double cost = 0.0;
};

/// The ego's state on both axes, its last yaw rate giving the accelerations.
[[nodiscard]] AxisState lateral_start(const EgoState& ego, double last_omega);
[[nodiscard]] AxisState longitudinal_start(const EgoState& ego, double last_omega);

/// The candidates from the ego's state, priced, cheapest first.
[[nodiscard]] std::vector<FrenetCandidate> lattice_candidates(const planner::Observation& o,
                                                              double last_omega,
                                                              const TrafficPrediction& cars,
                                                              const Config& config);

/// The candidate as unicycle poses at the nodes of dt, from t = 0 to `steps`.
[[nodiscard]] std::vector<EgoState> candidate_path(const FrenetCandidate& c, int steps, double dt);

/// Empty when the path keeps the speed, acceleration, yaw-rate, curvature and
/// heading limits, stays on the road and clear of the predicted cars;
/// otherwise what it breaks first.
[[nodiscard]] std::string candidate_problem(const std::vector<EgoState>& path,
                                            const TrafficPrediction& cars, const Scenario& scene,
                                            const LatticeSettings& settings);

/// The unicycle control that takes the ego from its state now to the path's
/// next node in one step: a from the speeds, omega from the headings.
[[nodiscard]] EgoControl first_control(const std::vector<EgoState>& path, double dt);

class LatticePlanner final : public planner::ClosedLoopPlanner {
 public:
  explicit LatticePlanner(Config config) : config_(std::move(config)) {}
  [[nodiscard]] std::string_view name() const override { return "lattice"; }
  [[nodiscard]] std::unique_ptr<planner::PlannerSession> start(
      const Scenario& scene) const override;

 private:
  Config config_;
};

[[nodiscard]] std::shared_ptr<const planner::ClosedLoopPlanner> make_lattice_planner(
    const Config& config);

}  // namespace lanechange::baselines
