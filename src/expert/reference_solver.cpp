#include "lanechange/error.hpp"
#include "lanechange/expert/bonmin_solver.hpp"
#include "lanechange/expert/lane_change_solver.hpp"

namespace lanechange::expert {

LaneChangeSolution ReferenceLaneChangeSolver::solve(const LaneChangeQp& qp,
                                                    const MiqpSettings& settings,
                                                    const SolveHints& /*hints*/) const {
  MiqpLayout layout;
  const MiqpProblem problem = to_miqp(qp, big_m_, layout);
  const MiqpResult result = BonminSolver(BonminAlgorithm::BranchAndBound).solve(problem, settings);
  LaneChangeSolution out;
  out.status = result.status;
  out.best_bound = result.best_bound;
  out.nodes = result.nodes;
  out.solve_ms = result.solve_ms;
  out.message = result.message;
  if (!result.has_solution()) return out;
  out.path = iterate_from_miqp(result.x, layout);
  out.objective = qp.objective(out.path);
  out.modes.assign(qp.steps + 1, -1);
  for (int k = 0; k <= qp.steps; ++k) {
    const int count = static_cast<int>(qp.node_modes[k].size());
    for (int m = 0; m < count; ++m) {
      if (result.x[layout.mode(k, m)] > 0.5) out.modes[k] = m;
    }
  }
  return out;
}

void LaneChangeSolution::clear() {
  status = MiqpStatus::NumericalError;
  path.states.clear();
  path.controls.clear();
  modes.clear();
  objective = kInfinity;
  best_bound = -kInfinity;
  nodes = 0;
  qp_iterations = 0;
  incumbent_qps = 0;
  solve_ms = 0.0;
  message.clear();
}

std::shared_ptr<const LaneChangeSolver> make_lane_change_solver(std::string_view name,
                                                                double big_m) {
  if (name == "reference") return std::make_shared<ReferenceLaneChangeSolver>(big_m);
  if (name == "fast") return std::make_shared<FastLaneChangeSolver>();
  throw InputError("--solver",
                   "unknown solver \"" + std::string(name) + "\" (expected fast or reference)");
}

}  // namespace lanechange::expert
