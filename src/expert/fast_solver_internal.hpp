#pragma once
// The fast solver's node solve, shared with the fixed-mode solver: both solve
// structured QPs of one round with some lane modes fixed, and one workspace
// type serves both, so a caller may hand either back-end the other's.
#include <array>
#include <utility>
#include <vector>

#include "lanechange/expert/lane_change_solver.hpp"
#include "lanechange/expert/structured_qp.hpp"

namespace lanechange::expert::detail {

inline constexpr int kFreeMode = -1;            ///< a node of a search whose mode is not fixed
inline constexpr double kModeTolerance = 1e-6;  ///< m: a lane row may be this far off and hold
/// Relative widening of a row, and of a box, in the bound tightening of
/// `modes_can_hold`: far above the QP's own tolerance, far below a lane.
inline constexpr double kBoxMargin = 1e-5;

/// A node of the search waiting to be solved: its lane modes, and a lower
/// bound on its optimum that its parent proved (a child's QP only adds rows).
struct OpenNode {
  std::vector<int> modes;
  double bound = -kInfinity;
};

struct FastWorkspace final : LaneChangeWorkspace {
  StructuredQp base;  // dynamics, costs and bounds of the round
  StructuredQp node;  // the base plus the lane rows of one search node
  QpWorkspace qp_workspace;
  std::vector<OpenNode> stack;  // waiting to be solved
  // Mode lists of nodes the search is done with, for the next children: a
  // search allocates none once the stack has been as deep before.
  std::vector<std::vector<int>> spare_modes;
  std::vector<std::pair<double, int>> child_order;  // push_children's, kept for its memory
  // The rest of a solve's mode lists, kept for their memory: the root's (all
  // free), the incumbent search's starts and moves, the fixed-mode solve's.
  std::vector<int> root_modes, switch_modes, switch_trial, fixed_modes;
  std::array<std::vector<int>, 2> start_modes;
  // Paths of node solutions the search is done with, for the next nodes'.
  std::vector<Iterate> spare_paths;
  // Gives a node's path back for the next node to fill.
  void recycle(Iterate& path) {
    if (path.states.capacity() > 0) spare_paths.push_back(std::move(path));
    path = Iterate{};
  }
  std::vector<Control> start_controls;
  long iterations = 0;         // of the interior-point method, for the solution's statistics
  unsigned needed_bounds = 0;  // state components whose bounds this round's QPs carry
  bool warm_start_qp = false;  // start a node QP from the last one's multipliers (fixed modes)
  RiccatiForm riccati = RiccatiForm::Schur;  // of the node QPs (bench_expert compares the forms)
  bool kinematic_sparsity = true;  // of the node QPs (bench_expert compares with dense steps)
  double rough_tolerance = 1e-3;   // where a NodePrecision::Rough QP may stop
  // Per node, bit m set when lane mode m can hold there at all: the states
  // the round's dynamics, bounds and controls can reach leave the others out.
  std::vector<unsigned> possible_modes;
  std::vector<State> reach_lower, reach_upper;  // per node, the box of reachable states
  void advance(int nodes) override { qp_workspace.advance(nodes); }
  [[nodiscard]] bool possible(int node, int mode) const {
    return ((possible_modes[static_cast<std::size_t>(node)] >> mode) & 1U) != 0;
  }
};

struct NodeOutcome {
  bool feasible = false;
  bool coarse = false;  // a point good enough to branch on, not a solution
  bool numerical_failure = false;
  bool cut_off = false;  // its lower bound passed the cutoff: objective holds that bound
  int iterations = 0;
  double objective = kInfinity;
  /// Proven for the node's QP: its objective once solved exactly; for a
  /// coarse point, the dual bound seen on the way (-infinity if none).
  double lower_bound = -kInfinity;
  Iterate path;
};

/// The workspace `hints` names if it is a FastWorkspace, else one made in `owned`.
FastWorkspace& workspace_for(const SolveHints& hints, std::unique_ptr<LaneChangeWorkspace>& owned);

/// True when some mode of node 0 holds at the initial state (or none applies).
[[nodiscard]] bool initial_state_allowed(const LaneChangeQp& qp);

/// False when the lane modes (a mode per node; -1 or kFreeMode: no rows)
/// can hold at no state the round can reach: boxes of the states carried
/// through the linear dynamics with every control in its box and cut to the
/// state bounds and to each node's mode rows. Bound tightening, so it never
/// refuses modes the QP could meet; it catches a gap the ego cannot reach
/// without the 60 iterations an interior-point method takes to give up.
[[nodiscard]] bool modes_can_hold(const LaneChangeQp& qp, const std::vector<int>& modes);

/// Readies `ws` for the QPs of one round: the base problem without lane rows,
/// the starting controls (the hint's, strictly inside the bounds) and, with
/// `reachable_modes`, the modes each node can reach (else every mode).
void prepare_round(const LaneChangeQp& qp, const SolveHints& hints, FastWorkspace& ws,
                   bool reachable_modes = true);

/// How far solve_node takes a QP.
enum class NodePrecision {
  Exact,
  /// A node well below the cutoff may come back as a rough point: a branch
  /// and bound only needs to see where to branch.
  RoughBelowCutoff,
  /// Any node may: enough to rank fixed-mode candidates, not to follow one.
  Rough,
};

/// The QP of `modes` (kFreeMode where a node is free); see fast_solver.cpp.
/// A node whose optimum is proven to be at least `cutoff` comes back infeasible.
NodeOutcome solve_node(const LaneChangeQp& qp, const std::vector<int>& modes, FastWorkspace& ws,
                       double cutoff = kInfinity, NodePrecision precision = NodePrecision::Exact);

}  // namespace lanechange::expert::detail
