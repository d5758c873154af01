#include "lanechange/expert/crosscheck.hpp"

#include <cmath>

#include "lanechange/error.hpp"
#include "lanechange/expert/planner.hpp"

namespace lanechange::expert {

namespace {

LaneChangeQp first_round_problem(const Scenario& scenario, const Config& base,
                                 const Gap* aimed_at) {
  const Config config = effective_config(base, scenario);
  const int steps = scenario.steps;
  const double dt = scenario.horizon / steps;
  const int predicted = steps + config.expert.prediction_lead_steps;
  const TrafficPrediction prediction = predict_traffic(scenario, config, predicted, dt);
  const Iterate point = aimed_at != nullptr ? warm_start(scenario, config, prediction, *aimed_at)
                                            : warm_start(scenario, config, prediction);
  return build_lane_change_qp(scenario, config, point,
                              prediction_along(scenario, config, predicted, dt, point),
                              aimed_at != nullptr ? *aimed_at : paper_gap(scenario));
}

}  // namespace

LaneChangeQp first_round_problem(const Scenario& scenario, const Config& config) {
  return first_round_problem(scenario, config, nullptr);
}

LaneChangeQp first_round_problem(const Scenario& scenario, const Config& config, const Gap& gap) {
  return first_round_problem(scenario, config, &gap);
}

CrossCheckCase compare_with_reference(const LaneChangeSolution& f, const StoredReference& r,
                                      double tolerance) {
  CrossCheckCase c;
  c.fast_status = f.status;
  c.reference_status = r.status;
  c.fast_objective = f.objective;
  c.reference_objective = r.objective;
  c.fast_ms = f.solve_ms;
  c.reference_ms = r.ms;
  c.fast_nodes = f.nodes;
  c.reference_nodes = r.nodes;
  const bool both_solved = f.status == MiqpStatus::Optimal && r.status == MiqpStatus::Optimal;
  const bool both_infeasible =
      f.status == MiqpStatus::Infeasible && r.status == MiqpStatus::Infeasible;
  if (both_solved) {
    c.relative_difference =
        std::abs(f.objective - r.objective) / std::max(1.0, std::abs(r.objective));
  }
  c.agree = both_infeasible || (both_solved && c.relative_difference <= tolerance);
  return c;
}

MiqpStatus parse_miqp_status(std::string_view text) {
  for (MiqpStatus s :
       {MiqpStatus::Optimal, MiqpStatus::Infeasible, MiqpStatus::TimeLimit, MiqpStatus::NodeLimit,
        MiqpStatus::NumericalError, MiqpStatus::InvalidProblem}) {
    if (to_string(s) == text) return s;
  }
  throw InputError("reference_status", "unknown solver status \"" + std::string(text) + "\"");
}

CrossCheckCase cross_check(const LaneChangeQp& qp, const LaneChangeSolver& fast,
                           const LaneChangeSolver& reference, const MiqpSettings& settings,
                           double tolerance) {
  const LaneChangeSolution f = fast.solve(qp, settings);
  const LaneChangeSolution r = reference.solve(qp, settings);
  return compare_with_reference(f, {r.status, r.objective, r.solve_ms, r.nodes}, tolerance);
}

}  // namespace lanechange::expert
