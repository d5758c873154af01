// The convex part of a round once the lane modes are fixed: one structured QP,
// the same node solve the exact search uses for its leaves.
#include <chrono>

#include "expert/fast_solver_internal.hpp"
#include "lanechange/expert/lane_change_solver.hpp"

namespace lanechange::expert {

namespace {

// Why `modes` cannot be the integer part of `qp` ("" when they can).
std::string unfit_modes(const LaneChangeQp& qp, const std::vector<int>* modes) {
  if (modes == nullptr) return "no lane modes were given";
  if (static_cast<int>(modes->size()) != qp.steps + 1) {
    std::string what = "the lane modes cover ";
    what += std::to_string(modes->size());
    what += " nodes, not ";
    what += std::to_string(qp.steps + 1);
    return what;
  }
  for (int k = 1; k <= qp.steps; ++k) {
    const int m = (*modes)[static_cast<std::size_t>(k)];
    const auto count = static_cast<int>(qp.node_modes[static_cast<std::size_t>(k)].size());
    if (count > 0 && (m < 0 || m >= count)) {
      std::string what = "node ";
      what += std::to_string(k);
      what += " has no lane mode ";
      what += std::to_string(m);
      return what;
    }
  }
  return "";
}

}  // namespace

bool lane_modes_can_hold(const LaneChangeQp& qp, const std::vector<int>& modes) {
  return unfit_modes(qp, &modes).empty() && detail::initial_state_allowed(qp) &&
         detail::modes_can_hold(qp, modes);
}

std::unique_ptr<LaneChangeWorkspace> FixedModeLaneChangeSolver::make_workspace() const {
  return std::make_unique<detail::FastWorkspace>();
}

LaneChangeSolution FixedModeLaneChangeSolver::solve(const LaneChangeQp& qp,
                                                    const MiqpSettings& settings,
                                                    const SolveHints& hints) const {
  LaneChangeSolution out;
  solve_into(qp, settings, hints, out);
  return out;
}

void FixedModeLaneChangeSolver::solve_into(const LaneChangeQp& qp, const MiqpSettings& settings,
                                           const SolveHints& hints, LaneChangeSolution& out) const {
  const auto start = std::chrono::steady_clock::now();
  out.clear();
  out.status = MiqpStatus::Infeasible;
  out.message = unfit_modes(qp, hints.modes);
  if (out.message.empty() && !detail::initial_state_allowed(qp)) {
    out.message = "the initial state breaks the lane rules";
  }
  if (out.message.empty() && !detail::modes_can_hold(qp, *hints.modes)) {
    out.message = "no reachable state meets the lane modes";
  }
  if (!out.message.empty()) return;
  // A caller's budget already spent (a step's, shared with other solves).
  if (settings.qp_iteration_limit <= 0 || settings.time_limit_s <= 0.0) {
    out.status = settings.qp_iteration_limit <= 0 ? MiqpStatus::WorkLimit : MiqpStatus::TimeLimit;
    out.message = "the budget is spent";
    return;
  }
  std::unique_ptr<LaneChangeWorkspace> owned;
  detail::FastWorkspace& ws = detail::workspace_for(hints, owned);
  // With the modes fixed, a plan's rounds (and a screen's candidates) solve
  // near-identical QPs: the state bounds one of them needed, the next will
  // too, and carrying them saves solving it twice. An extra bound that does
  // not bind changes nothing but the row count.
  const unsigned bounds_needed_before = ws.needed_bounds;
  detail::prepare_round(qp, hints, ws);
  ws.needed_bounds = bounds_needed_before;
  // A plan's next round solves nearly the same QP: its interior-point
  // method starts from the last one's multipliers where the rows match.
  ws.warm_start_qp = true;
  ws.rough_tolerance = settings_.rough_tolerance;
  // Node 0's mode is not a choice (its state is given), so it stays free.
  std::vector<int>& modes = ws.fixed_modes;
  modes.assign(hints.modes->begin(), hints.modes->end());
  modes[0] = detail::kFreeMode;
  detail::NodeOutcome node = detail::solve_node(
      qp, modes, ws, settings.objective_cutoff,
      settings_.rough ? detail::NodePrecision::Rough : detail::NodePrecision::Exact);
  out.nodes = 1;
  out.qp_iterations = ws.iterations;
  out.solve_ms =
      std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
  if (node.cut_off) {
    ws.recycle(node.path);
    out.status = MiqpStatus::Cutoff;
    out.objective = node.objective;
    out.message = "no point is cheaper than the cutoff";
    return;
  }
  if (!node.feasible) {
    ws.recycle(node.path);
    out.status = node.numerical_failure ? MiqpStatus::NumericalError : MiqpStatus::Infeasible;
    out.message =
        node.numerical_failure ? "the QP failed" : "the lane modes leave no feasible path";
    return;
  }
  out.status = MiqpStatus::Optimal;
  std::swap(out.path, node.path);
  ws.recycle(node.path);
  out.objective = node.objective;
  out.modes.assign(hints.modes->begin(), hints.modes->end());
}

}  // namespace lanechange::expert
