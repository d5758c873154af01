// Our exact solver for the lane-change MIQP. A node of the search fixes the
// lane mode of some nodes of the horizon and leaves the rest free (no lane
// rows there): its QP is a relaxation of every completion, so its optimum is
// a lower bound for them. Branching picks the earliest free node whose relaxed
// state clearly violates all its modes, and makes one child per mode. The search
// is depth first, best child first, and starts from the hinted modes (the
// previous round's) as an incumbent, so most of the tree is pruned at once.
// Nothing here assumes a monotone lane sequence: the search is exact for any.
#include <algorithm>
#include <array>
#include <bit>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <functional>
#include <string>
#include <utility>

#include "expert/fast_solver_internal.hpp"

namespace lanechange::expert {

namespace detail {

namespace {

constexpr int kFree = kFreeMode;
constexpr double kCoarseViolation = 1e-3;  // m: clearly broken even at a rough point

void add_row(QpStage& stage, const Eigen::Vector4d& g_state, double d, bool soft) {
  QpRow row;
  row.g.head<4>() = g_state;
  row.d = d;
  row.soft = soft;
  stage.rows.push_back(row);
}

void add_control_bound(QpStage& stage, int component, double lo, double hi) {
  QpRow upper;
  upper.g[kQpStates + component] = 1.0;
  upper.d = hi;
  QpRow lower;
  lower.g[kQpStates + component] = -1.0;
  lower.d = -lo;
  stage.rows.push_back(upper);
  stage.rows.push_back(lower);
}

// |omega| <= kappa v: two rows on the stage's speed and yaw rate.
void add_turn_rows(QpStage& stage, double kappa) {
  for (const double sign : {1.0, -1.0}) {
    QpRow row;
    row.g[kV] = -kappa;
    row.g[kQpStates + kOmega] = sign;
    stage.rows.push_back(row);
  }
}

// The round's QP without lane rows, in the solver's stage form.
void build_base(const LaneChangeQp& qp, StructuredQp& out) {
  const int n = qp.steps;
  out.stages.resize(n + 1);
  out.initial_state.head<4>() = qp.initial_state;
  out.initial_state[4] = 0.0;
  out.has_terminal_equality = qp.terminal_lateral_fixed;
  out.terminal_g.setZero();
  out.terminal_g[kY] = 1.0;
  out.terminal_d = qp.lateral_reference;
  for (int k = 0; k <= n; ++k) {
    QpStage& st = out.stages[k];
    st.rows.clear();
    st.A.setZero();
    st.B.setZero();
    st.c.setZero();
    st.H.setZero();
    st.h.setZero();
    st.control_curvature.setZero();
    if (k < n) {
      st.A.topLeftCorner<4, 4>() = qp.dynamics[k].A;
      st.B.topRows<4>() = qp.dynamics[k].B;
      st.B(4, kA) = 1.0;  // the next stage remembers this acceleration for the jerk
      st.c.head<4>() = qp.dynamics[k].c;
      st.H(5, 5) += 2.0 * qp.accel_weight;
      st.H(6, 6) += 2.0 * qp.yaw_rate_weight;
      st.control_curvature << 2.0 * qp.accel_weight, 2.0 * qp.yaw_rate_weight;
      if (k >= 1) {
        const double w = 2.0 * qp.jerk_weight;
        st.H(5, 5) += w;
        st.H(4, 4) += w;
        st.H(4, 5) -= w;
        st.H(5, 4) -= w;
      }
      add_control_bound(st, kA, qp.control_lower[kA], qp.control_upper[kA]);
      add_control_bound(st, kOmega, qp.control_lower[kOmega], qp.control_upper[kOmega]);
      if (qp.yaw_rate_per_speed > 0.0) add_turn_rows(st, qp.yaw_rate_per_speed);
    }
    const double wy = qp.lateral_weight[k];
    st.H(kY, kY) += 2.0 * wy;
    st.h[kY] -= 2.0 * wy * qp.lateral_reference;
    if (k == n && qp.terminal_x_weight > 0.0) {
      st.H(kX, kX) += 2.0 * qp.terminal_x_weight;
      st.h[kX] -= 2.0 * qp.terminal_x_weight * qp.terminal_x_reference;
    }
    // The state bounds rarely bind (x and theta never: they are far from
    // anything the controls can reach), so the search leaves them out: a
    // relaxation, still a valid bound, with fewer rows in every pass of the
    // interior-point method. A solution that breaks one is solved again with
    // them (see solve_node).
  }
}

double mode_violation(const LaneMode& mode, const State& z) {
  double worst = 0.0;
  for (const HalfSpace& h : mode.rows) worst = std::max(worst, h.g.dot(z) - h.upper);
  return worst;
}

// An interval of y that holds every point of a mode, from its rows on y and
// the heading alone (the heading at its least helpful within `heading`).
std::pair<double, double> lateral_range(const LaneMode& mode, double lo, double hi,
                                        const Interval& heading) {
  for (const HalfSpace& h : mode.rows) {
    if (h.g[kX] != 0.0 || h.g[kV] != 0.0 || h.g[kY] == 0.0) continue;
    const double by_heading = std::min(h.g[kTheta] * heading.lo, h.g[kTheta] * heading.hi);
    // A row without the heading must not meet an infinite heading bound (0 * inf).
    const double upper = h.g[kTheta] == 0.0 ? h.upper : h.upper - by_heading;
    if (!std::isfinite(upper)) continue;
    if (h.g[kY] > 0.0) hi = std::min(hi, upper / h.g[kY]);
    if (h.g[kY] < 0.0) lo = std::max(lo, upper / h.g[kY]);
  }
  return {lo, hi};
}

// The tightest limit a mode puts on g'z for the row direction g, or +inf.
double limit_along(const LaneMode& mode, const Eigen::Vector4d& g) {
  double limit = kInfinity;
  for (const HalfSpace& h : mode.rows) {
    if ((h.g - g).cwiseAbs().maxCoeff() == 0.0) limit = std::min(limit, h.upper);
  }
  return limit;
}

// A free node still lies in the union of its modes. Where the lowest and the
// highest mode (in y) both bound x + h v from above, with the same h, the
// union lies below the line through their corners, a ramp in y: an
// inequality that every mode implies, which tightens the relaxation a lot
// (the ego cannot be far ahead of its leader while still low in its lane).
bool ramp_row(const LaneChangeQp& qp, const FastWorkspace& ws, int k, HalfSpace& out) {
  const auto& all_modes = qp.node_modes[k];
  // The modes the node can reach, in order of y (lane_modes lists them so).
  std::array<const LaneMode*, 3> modes{};
  std::size_t count = 0;
  for (std::size_t m = 0; m < all_modes.size() && count < modes.size(); ++m) {
    if (ws.possible(k, static_cast<int>(m))) modes[count++] = &all_modes[m];
  }
  if (count < 2) return false;
  const double ylo = qp.state_lower[k][kY];
  const double yhi = qp.state_upper[k][kY];
  const Interval heading{std::max(qp.state_lower[k][kTheta], ws.reach_lower[k][kTheta]),
                         std::min(qp.state_upper[k][kTheta], ws.reach_upper[k][kTheta])};
  const LaneMode& low = *modes[0];
  const LaneMode& high = *modes[count - 1];
  const auto [low_lo, low_hi] = lateral_range(low, ylo, yhi, heading);
  const auto [high_lo, high_hi] = lateral_range(high, ylo, yhi, heading);
  // The corners exist only where both modes reach into the node's y bounds; a
  // narrow box (the expert's trust region) can leave one out, and a line
  // anchored on it would cut off the other.
  if (low_lo > low_hi || high_lo > high_hi) return false;
  for (const HalfSpace& h : low.rows) {
    if (h.g[kX] != 1.0 || h.g[kY] != 0.0) continue;
    const double u_low = limit_along(low, h.g);
    const double u_high = limit_along(high, h.g);
    if (!std::isfinite(u_low) || !std::isfinite(u_high)) continue;
    // The ramp lies between the two limits over the node's y, and a middle
    // mode may reach anywhere in it: it must allow no more than the smaller.
    const double u_min = std::min(u_low, u_high);
    bool middle_ok = true;
    for (std::size_t m = 1; m + 1 < count; ++m) {
      middle_ok = middle_ok && limit_along(*modes[m], h.g) <= u_min;
    }
    if (!middle_ok) continue;
    // A mode that reaches the far end of the node's y leaves no line between
    // the corners (the heading rule's rows, at large headings).
    if ((u_high > u_low && high_lo <= ylo) || (u_high < u_low && low_hi >= yhi)) continue;
    double slope = 0.0;  // of the limit in y
    if (u_high > u_low) slope = (u_high - u_low) / (high_lo - ylo);
    if (u_high < u_low) slope = (u_high - u_low) / (yhi - low_hi);
    const double anchor_y = u_high >= u_low ? ylo : yhi;
    const double anchor_u = u_high >= u_low ? u_low : u_high;
    // g'z <= anchor_u + slope (y - anchor_y)  <=>  g'z - slope y <= anchor_u - slope anchor_y
    out.g = h.g;
    out.g[kY] -= slope;
    out.upper = anchor_u - slope * anchor_y;
    return true;
  }
  return false;
}

// The smallest value of g'z over the box [lo, hi].
double least_over_box(const Eigen::Vector4d& g, const State& lo, const State& hi) {
  double least = 0.0;
  for (int i = 0; i < 4; ++i) {
    if (g[i] != 0.0) least += g[i] * (g[i] > 0.0 ? lo[i] : hi[i]);  // 0 * inf is no bound
  }
  return least;
}

// The base with the bounds of the state components in `bounds` (bit i for
// component i) and the lane rows of `modes`; free nodes get their ramp.
void build_node(const LaneChangeQp& qp, const std::vector<int>& modes, unsigned bounds,
                FastWorkspace& ws) {
  for (int k = 0; k <= qp.steps; ++k) {
    QpStage& st = ws.node.stages[k];
    st.rows.assign(ws.base.stages[k].rows.begin(), ws.base.stages[k].rows.end());
    for (int i = 0; i < 4 && k >= 1; ++i) {
      if ((bounds >> i) & 1U) {
        Eigen::Vector4d e = Eigen::Vector4d::Unit(i);
        add_row(st, e, qp.state_upper[k][i], true);
        add_row(st, -e, -qp.state_lower[k][i], true);
      }
    }
    if (k == 0 || qp.node_modes[k].empty()) continue;  // the initial state is fixed: checked apart
    // A node whose mode is fixed, or the only one it can reach, is in that
    // mode: its rows are no choice, and those that every reachable state
    // meets need not be written.
    const unsigned possible = ws.possible_modes[k];
    const int fixed = modes[k] != kFree              ? modes[k]
                      : std::popcount(possible) == 1 ? std::countr_zero(possible)
                                                     : kFree;
    if (fixed != kFree) {
      for (const HalfSpace& h : qp.node_modes[k][fixed].rows) {
        if (-least_over_box(-h.g, ws.reach_lower[k], ws.reach_upper[k]) > h.upper) {
          add_row(st, h.g, h.upper, true);
        }
      }
      continue;
    }
    HalfSpace ramp;
    if (ramp_row(qp, ws, k, ramp)) add_row(st, ramp.g, ramp.upper, true);
  }
}

// The node's solution, in a path the search is done with where there is one.
Iterate path_of(const QpWorkspace& qp_ws, int steps, FastWorkspace& ws) {
  Iterate path;
  if (!ws.spare_paths.empty()) {
    path = std::move(ws.spare_paths.back());
    ws.spare_paths.pop_back();
  }
  path.states.clear();
  path.controls.clear();
  path.states.reserve(steps + 1);
  path.controls.reserve(steps);
  const auto& w = qp_ws.solution();
  for (int k = 0; k <= steps; ++k) {
    path.states.emplace_back(w[k].head<4>());
    if (k < steps) path.controls.emplace_back(w[k].tail<2>());
  }
  return path;
}

// The state components (bit i for component i) whose bounds the path breaks.
unsigned broken_bounds(const LaneChangeQp& qp, const Iterate& path) {
  unsigned broken = 0;
  for (int k = 1; k <= qp.steps; ++k) {
    for (int i = 0; i < 4; ++i) {
      const double z = path.states[k][i];
      if (z > qp.state_upper[k][i] + kModeTolerance || z < qp.state_lower[k][i] - kModeTolerance) {
        broken |= 1U << i;
      }
    }
  }
  return broken;
}

NodeOutcome solve_node_with(const LaneChangeQp& qp, const std::vector<int>& modes, unsigned bounds,
                            double cutoff, NodePrecision precision, FastWorkspace& ws) {
  build_node(qp, modes, bounds, ws);
  ws.qp_workspace.setup(ws.node);
  ws.qp_workspace.set_initial_controls(ws.start_controls);
  QpSettings settings;
  settings.warm_start = ws.warm_start_qp && precision == NodePrecision::Exact;
  settings.riccati = ws.riccati;
  settings.kinematic_sparsity = ws.kinematic_sparsity;
  // The QP's objective leaves out LaneChangeQp::objective's constant.
  const double qp_cutoff = cutoff - qp.objective_constant();
  // A hair above the cutoff: a node this close is decided by its converged objective.
  settings.objective_cutoff = qp_cutoff + 1e-9 * (1.0 + std::abs(cutoff));
  if (precision == NodePrecision::RoughBelowCutoff) {
    // Clearly below the cutoff: this node will be branched on, and a rough
    // point tells where as well as the optimum does.
    settings.coarse_below = qp_cutoff - 1e-2 * (1.0 + std::abs(cutoff));
  }
  if (precision == NodePrecision::Rough) {
    settings.coarse_below = kInfinity;
    settings.coarse_tolerance = ws.rough_tolerance;
  }
  const QpResult r = solve_structured_qp(ws.node, ws.qp_workspace, settings);
  NodeOutcome out;
  out.iterations = r.iterations;
  if (r.status == QpStatus::Cutoff) {
    out.cut_off = true;
    out.objective = r.lower_bound + qp.objective_constant();
    return out;
  }
  if (r.status == QpStatus::NumericalError || r.status == QpStatus::IterationLimit) {
    out.numerical_failure = true;
    return out;
  }
  if (r.status != QpStatus::Optimal && r.status != QpStatus::Coarse) return out;
  out.feasible = true;
  out.coarse = r.status == QpStatus::Coarse;
  out.path = path_of(ws.qp_workspace, qp.steps, ws);
  // The next node is most often a child or sibling of this one: start there.
  ws.start_controls = out.path.controls;
  out.objective = qp.objective(out.path);
  // A rough point's objective may lie on either side of the optimum; only
  // the dual bound is proven there.
  out.lower_bound = out.coarse ? r.lower_bound + qp.objective_constant() : out.objective;
  return out;
}

}  // namespace

// The node's QP, with the bounds of only those state components that this
// round's solutions have broken so far: solved again, with more, while its
// solution breaks one.
NodeOutcome solve_node(const LaneChangeQp& qp, const std::vector<int>& modes, FastWorkspace& ws,
                       double cutoff, NodePrecision precision) {
  int iterations = 0;
  NodeOutcome out;
  // Bound tightening refuses most infeasible nodes in microseconds, where the
  // interior-point method takes its whole iteration limit to give up.
  if (!modes_can_hold(qp, modes)) return out;
  for (;;) {
    ws.recycle(out.path);
    out = solve_node_with(qp, modes, ws.needed_bounds, cutoff, precision, ws);
    iterations += out.iterations;
    const unsigned broken = out.feasible ? broken_bounds(qp, out.path) & ~ws.needed_bounds : 0U;
    if (broken == 0) break;
    ws.needed_bounds |= broken;
  }
  out.iterations = iterations;
  ws.iterations += iterations;
  return out;
}

FastWorkspace& workspace_for(const SolveHints& hints, std::unique_ptr<LaneChangeWorkspace>& owned) {
  auto* ws = dynamic_cast<FastWorkspace*>(hints.workspace);
  if (ws != nullptr) return *ws;
  owned = std::make_unique<FastWorkspace>();
  return static_cast<FastWorkspace&>(*owned);
}

bool initial_state_allowed(const LaneChangeQp& qp) {
  if (qp.node_modes[0].empty()) return true;
  bool holds = false;
  for (const LaneMode& m : qp.node_modes[0])
    holds = holds || mode_violation(m, qp.initial_state) <= kModeTolerance;
  return holds;
}

namespace {

// Cuts the box [lo, hi] to the row g'z <= upper: each component's bound
// given the least the others can contribute. The row is widened by a margin
// that keeps any point the QP would accept (its rows hold to about 1e-6).
void cut_to_row(const HalfSpace& h, State& lo, State& hi) {
  const double upper = h.upper + kBoxMargin * (1.0 + std::abs(h.upper));
  for (int j = 0; j < 4; ++j) {
    const double g = h.g[j];
    if (g == 0.0) continue;
    double rest = 0.0;
    for (int i = 0; i < 4; ++i) {
      if (i != j && h.g[i] != 0.0) rest += h.g[i] * (h.g[i] > 0.0 ? lo[i] : hi[i]);
    }
    if (!std::isfinite(rest)) continue;
    if (g > 0.0) hi[j] = std::min(hi[j], (upper - rest) / g);
    if (g < 0.0) lo[j] = std::max(lo[j], (upper - rest) / g);
  }
}

// Empty beyond the margin that keeps any point the QP would accept.
bool empty_box(const State& lo, const State& hi) {
  const State slack = kBoxMargin * (State::Ones() + lo.cwiseAbs());
  return (lo.array() > (hi + slack).array()).any();
}

// Bit m for each lane mode of node k that some state of the box [lo, hi]
// could satisfy: the box cut to the mode's rows, each row's bound given the
// others' at their best, stays non-empty. A gap shorter than its two safe
// distances shows here, where no row alone misses the box.
unsigned modes_meeting_box(const LaneChangeQp& qp, int k, const State& lo, const State& hi) {
  unsigned possible = 0;
  const auto& modes = qp.node_modes[k];
  for (std::size_t m = 0; m < modes.size(); ++m) {
    State mode_lo = lo;
    State mode_hi = hi;
    // Twice: a row cut by a later one may cut again.
    for (int pass = 0; pass < 2; ++pass) {
      for (const HalfSpace& h : modes[m].rows) cut_to_row(h, mode_lo, mode_hi);
    }
    if (!empty_box(mode_lo, mode_hi)) possible |= 1U << m;
  }
  return possible;
}

// Which modes each node can reach. Boxes of the states are carried through
// the round's (linear) dynamics from the fixed initial state with every
// control in its box, and cut to the state bounds at each node: every
// feasible point of the round lies in them, so a mode that no state of its
// node's box satisfies is no choice there. This is bound tightening, not a
// heuristic: the search stays exact. A node with one mode left is fixed from
// the root on, and the ramp of a node is drawn between its reachable modes.
// The box of node k + 1's states, from node k's box [lo, hi] through the
// round's linear dynamics with every control in its box, cut to the state
// bounds (and the fixed terminal y). Empty (some lo > hi) when no state holds.
void next_box(const LaneChangeQp& qp, int k, State& lo, State& hi) {
  const StageDynamics& d = qp.dynamics[k];
  State next_lo = d.c;
  State next_hi = d.c;
  for (int i = 0; i < 4; ++i) {
    for (int j = 0; j < 4; ++j) {
      const double a = d.A(i, j);
      next_lo[i] += a * (a > 0.0 ? lo[j] : hi[j]);
      next_hi[i] += a * (a > 0.0 ? hi[j] : lo[j]);
    }
    for (int j = 0; j < 2; ++j) {
      const double b = d.B(i, j);
      next_lo[i] += b * (b > 0.0 ? qp.control_lower[j] : qp.control_upper[j]);
      next_hi[i] += b * (b > 0.0 ? qp.control_upper[j] : qp.control_lower[j]);
    }
  }
  lo = next_lo.cwiseMax(qp.state_lower[k + 1]);
  hi = next_hi.cwiseMin(qp.state_upper[k + 1]);
  if (k + 1 == qp.steps && qp.terminal_lateral_fixed) {
    lo[kY] = std::max(lo[kY], qp.lateral_reference);
    hi[kY] = std::min(hi[kY], qp.lateral_reference);
  }
}

void find_possible_modes(const LaneChangeQp& qp, FastWorkspace& ws) {
  const int n = qp.steps;
  State lo = qp.initial_state;
  State hi = qp.initial_state;
  for (int k = 0; k < n; ++k) {
    next_box(qp, k, lo, hi);
    // An empty box means the round has no feasible point; let the QPs show it.
    if ((lo.array() > hi.array()).any()) return;
    ws.reach_lower[k + 1] = lo;
    ws.reach_upper[k + 1] = hi;
    if (!qp.node_modes[k + 1].empty())
      ws.possible_modes[k + 1] = modes_meeting_box(qp, k + 1, lo, hi);
  }
}

}  // namespace

bool modes_can_hold(const LaneChangeQp& qp, const std::vector<int>& modes) {
  State lo = qp.initial_state;
  State hi = qp.initial_state;
  for (int k = 0; k < qp.steps; ++k) {
    next_box(qp, k, lo, hi);
    const auto& choices = qp.node_modes[static_cast<std::size_t>(k) + 1];
    const int m = modes[static_cast<std::size_t>(k) + 1];
    if (m >= 0 && static_cast<std::size_t>(m) < choices.size()) {
      // Twice: a row cut by a later one may cut again.
      for (int pass = 0; pass < 2; ++pass) {
        for (const HalfSpace& h : choices[static_cast<std::size_t>(m)].rows) cut_to_row(h, lo, hi);
      }
    }
    if (empty_box(lo, hi)) return false;
    hi = hi.cwiseMax(lo);  // within the margin: a point, not an empty box
  }
  return true;
}

namespace {

// Room for every node QP of the round, made before it starts: the most rows
// a node can carry (the base's, both bounds of every state component, and its
// busiest mode's rows or its ramp), and node paths.
void reserve_for_node_qps(const LaneChangeQp& qp, FastWorkspace& ws) {
  const int n = qp.steps;
  constexpr std::size_t kStateBoundRows = 8;  // both bounds of x, y, v and theta
  std::size_t rows = 0;
  for (int k = 0; k <= n; ++k) {
    std::size_t lane = 1;  // a ramp
    for (const LaneMode& m : qp.node_modes[k]) lane = std::max(lane, m.rows.size());
    const std::size_t stage_rows = ws.base.stages[k].rows.size() + kStateBoundRows + lane;
    ws.node.stages[k].rows.reserve(stage_rows);
    rows += stage_rows;
  }
  ws.qp_workspace.reserve(rows);
  ws.fixed_modes.reserve(static_cast<std::size_t>(n) + 1);
  constexpr std::size_t kPaths = 8;  // more than a search holds at once
  ws.spare_paths.reserve(2 * kPaths);
  while (ws.spare_paths.size() < kPaths) {
    Iterate& path = ws.spare_paths.emplace_back();
    path.states.reserve(static_cast<std::size_t>(n) + 1);
    path.controls.reserve(static_cast<std::size_t>(n));
  }
}

}  // namespace

void prepare_round(const LaneChangeQp& qp, const SolveHints& hints, FastWorkspace& ws,
                   bool reachable_modes) {
  const int n = qp.steps;
  ws.iterations = 0;
  build_base(qp, ws.base);
  ws.needed_bounds = 0;
  ws.node = ws.base;
  ws.start_controls.assign(n, Control::Zero());
  if (hints.controls != nullptr && static_cast<int>(hints.controls->size()) == n) {
    ws.start_controls = *hints.controls;
  }
  // Strictly inside the control bounds. The turn rows (min_turn_radius) are hard
  // too but tie the yaw rate to a speed the start does not know; the method
  // starts from any point, and they may start broken.
  const Control margin = 1e-3 * (qp.control_upper - qp.control_lower);
  for (Control& u : ws.start_controls) {
    u = u.cwiseMax(qp.control_lower + margin).cwiseMin(qp.control_upper - margin);
  }
  reserve_for_node_qps(qp, ws);
  ws.possible_modes.assign(n + 1, ~0U);
  ws.reach_lower.assign(n + 1, State::Constant(-kInfinity));
  ws.reach_upper.assign(n + 1, State::Constant(kInfinity));
  if (reachable_modes) find_possible_modes(qp, ws);
}

namespace {

// How far node k's relaxed state is from the nearest mode the node can reach.
double least_violation(const LaneChangeQp& qp, const FastWorkspace& ws, const State& z, int k) {
  double least = kInfinity;
  for (int m = 0; m < static_cast<int>(qp.node_modes[k].size()); ++m) {
    if (ws.possible(k, m)) least = std::min(least, mode_violation(qp.node_modes[k][m], z));
  }
  return least;
}

// The free node to branch on, or -1 when every free node's relaxed state
// meets one of its modes (within `threshold`): the earliest node that misses
// its modes by at least half as much as the worst one. Its mode shapes the
// path from there on, so its children's bounds rise more than those of the
// worst node, which usually sits in the middle of the change: branching on
// that one took 30% more interior-point iterations over 100 sampled plans.
int branching_node(const LaneChangeQp& qp, const FastWorkspace& ws, const std::vector<int>& modes,
                   const Iterate& path, double threshold) {
  auto branchable = [&](int k) { return modes[k] == kFree && !qp.node_modes[k].empty(); };
  double worst = threshold;
  for (int k = 1; k <= qp.steps; ++k) {
    if (branchable(k)) worst = std::max(worst, least_violation(qp, ws, path.states[k], k));
  }
  if (worst <= threshold) return -1;
  constexpr double kShareOfWorst = 0.5;
  for (int k = 1; k <= qp.steps; ++k) {
    if (!branchable(k)) continue;
    const double v = least_violation(qp, ws, path.states[k], k);
    if (v > threshold && v >= kShareOfWorst * worst) return k;
  }
  return -1;
}

// The modes that a feasible path satisfies, node by node.
void modes_of(const LaneChangeQp& qp, const Iterate& path, std::vector<int>& modes) {
  modes.assign(qp.steps + 1, kFree);
  for (int k = 0; k <= qp.steps; ++k) {
    if (!qp.node_modes[k].empty()) modes[k] = qp.best_mode(path, k);
  }
}

using Clock = std::chrono::steady_clock;

// A node whose bound reaches this cannot improve the incumbent by more than the gap.
double prune_above(double incumbent, const MiqpSettings& settings) {
  return incumbent - std::max(settings.absolute_gap, settings.relative_gap * std::abs(incumbent));
}

// Moves the lane switch between nodes j - 1 and j by `step` nodes (later
// when positive, earlier when negative) within the two segments it joins;
// false when the move would cross another switch or reach node 0.
bool move_switch(const std::vector<int>& modes, int j, int step, std::vector<int>& out) {
  const int before = modes[j - 1];
  const int after = modes[j];
  const int first = step > 0 ? j : j + step;
  const int last = step > 0 ? j + step - 1 : j - 1;
  if (first < 1 || last >= static_cast<int>(modes.size())) return false;
  out = modes;
  for (int i = first; i <= last; ++i) {
    if (modes[i] != (step > 0 ? after : before)) return false;
    out[i] = step > 0 ? before : after;
  }
  return true;
}

// True when `modes` fixes every node that has lane modes: only then is its
// QP's solution a candidate incumbent (a hint may leave nodes free).
bool complete(const LaneChangeQp& qp, const std::vector<int>& modes) {
  for (int k = 1; k <= qp.steps; ++k) {
    if (!qp.node_modes[k].empty() && modes[k] == kFree) return false;
  }
  return true;
}

// False when some node of `modes` is fixed to a mode it cannot reach: such a
// QP is infeasible, and need not be solved to tell.
bool reachable(const FastWorkspace& ws, const std::vector<int>& modes) {
  for (std::size_t k = 1; k < modes.size(); ++k) {
    if (modes[k] != kFree && !ws.possible(static_cast<int>(k), modes[k])) return false;
  }
  return true;
}

// Moves each lane switch of a complete mode sequence earlier or later while
// that lowers the objective: a cheap way to an incumbent close to the
// optimum, which lets the search prune most of its tree. A switch that moved
// keeps moving the same way with doubling steps (the warm start's switch
// times can be a second or more off), and the search stops as soon as
// `settled()` says no sequence can beat the incumbent by more than the gap.
template <class Accept, class Settled, class Level>
void improve_switches(const LaneChangeQp& qp, const std::vector<int>& start, double objective,
                      FastWorkspace& ws, long& nodes, Accept&& accept, Settled&& settled,
                      Level&& prune_level) {
  std::vector<int>& modes = ws.switch_modes;
  modes.assign(start.begin(), start.end());
  std::vector<int>& trial = ws.switch_trial;
  auto try_move = [&](int j, int step) {
    if (!move_switch(modes, j, step, trial) || !reachable(ws, trial)) return false;
    // Only a move that could still become the incumbent counts: one above
    // the search's prune level (the incumbent, or the caller's cutoff) is
    // stopped by its dual bound within a few iterations.
    const double cap = std::min(objective, prune_level());
    NodeOutcome o = solve_node(qp, trial, ws, cap);
    ++nodes;
    const bool better = o.feasible && o.objective < cap - 1e-12;
    if (better) {
      objective = o.objective;
      modes = trial;
      accept(o);
    }
    ws.recycle(o.path);
    return better;
  };
  for (bool improved = true; improved && !settled();) {
    improved = false;
    for (int j = 2; j <= qp.steps && !improved && !settled(); ++j) {
      if (modes[j] == modes[j - 1]) continue;
      for (const int direction : {1, -1}) {
        if (improved || settled() || !try_move(j, direction)) continue;
        improved = true;
        // The switch now sits at j + direction; keep going that way.
        int at = j + direction;
        for (int step = 2; !settled();) {
          if (try_move(at, direction * step)) {
            at += direction * step;
            step *= 2;
          } else if (step > 1) {
            step = 1;
          } else {
            break;
          }
        }
      }
    }
  }
}

// A complete mode sequence from a path: at each node, the reachable mode it comes closest to.
void rounded_modes(const LaneChangeQp& qp, const FastWorkspace& ws, const Iterate& path,
                   std::vector<int>& modes) {
  modes.assign(qp.steps + 1, kFree);
  for (int k = 1; k <= qp.steps; ++k) {
    modes[k] = qp.best_mode(path, k, ws.possible_modes[static_cast<std::size_t>(k)]);
  }
}

// Room for the search of a round, made before it starts: a stack as deep as
// a depth-first search over the nodes' modes can grow, with a mode list for
// each entry, and the lists of the root and of the incumbent search.
void reserve_for_search(int steps, FastWorkspace& ws) {
  const auto nodes = static_cast<std::size_t>(steps) + 1;
  ws.child_order.reserve(4);
  for (std::vector<int>* modes : {&ws.root_modes, &ws.switch_modes, &ws.switch_trial,
                                  &ws.start_modes[0], &ws.start_modes[1]}) {
    modes->reserve(nodes);
  }
  const std::size_t deepest = 3 * nodes;
  ws.stack.reserve(deepest);
  ws.spare_modes.reserve(deepest);
  while (ws.spare_modes.size() + ws.stack.size() < deepest) {
    ws.spare_modes.emplace_back().reserve(nodes);
  }
}

double least_open_bound(const std::vector<OpenNode>& open) {
  double least = kInfinity;
  for (const OpenNode& node : open) least = std::min(least, node.bound);
  return least;
}

// Infeasibility that needs no QP, found in microseconds where the search
// would solve its root first. True when the search must run (the workspace
// is then ready for it); false when `out` holds the verdict.
bool pre_check(const LaneChangeQp& qp, const SolveHints& hints, bool reachable_modes,
               FastWorkspace& ws, LaneChangeSolution& out) {
  // The initial state is given: some mode of node 0 must already hold.
  if (!initial_state_allowed(qp)) {
    out.status = MiqpStatus::Infeasible;
    out.best_bound = kInfinity;
    out.message = "the initial state breaks the lane rules";
    return false;
  }
  prepare_round(qp, hints, ws, reachable_modes);
  // Every feasible point lies in the reachable boxes and meets some mode at
  // each node: a node where no mode can hold leaves none.
  for (int k = 1; k <= qp.steps; ++k) {
    if (!qp.node_modes[k].empty() && ws.possible_modes[k] == 0) {
      out.status = MiqpStatus::Infeasible;
      out.best_bound = kInfinity;
      out.message = "no lane mode can hold at node ";
      out.message += std::to_string(k);
      out.qp_iterations = ws.iterations;
      return false;
    }
  }
  return true;
}

// The stages of one solve after the pre-check share the incumbent, the
// clock and the solution they fill in; the open nodes live in the workspace,
// whose memory outlasts the solve.
class Search {
 public:
  Search(const LaneChangeQp& qp, const MiqpSettings& settings, FastWorkspace& ws,
         Clock::time_point start, LaneChangeSolution& out)
      : qp_(qp), settings_(settings), ws_(ws), start_(start), out_(out) {}

  void find_incumbent(const NodeOutcome& root, const SolveHints& hints);
  bool branch_and_bound(const std::vector<int>& root_modes, NodeOutcome& root);
  void finish();

 private:
  [[nodiscard]] double seconds_so_far() const {
    return std::chrono::duration<double>(Clock::now() - start_).count();
  }
  [[nodiscard]] bool out_of_work() const { return ws_.iterations > settings_.qp_iteration_limit; }
  /// Nodes whose bound reaches this are pruned: the incumbent's gap, or the
  /// caller's cutoff while no incumbent beats it.
  [[nodiscard]] double prune_level() const {
    if (std::isinf(incumbent_) && std::isfinite(settings_.objective_cutoff)) {
      return settings_.objective_cutoff;
    }
    return std::min(prune_above(incumbent_, settings_), settings_.objective_cutoff);
  }
  void accept(NodeOutcome& o);
  bool stopped_at_limit(double pending_bound);
  void explore(const std::vector<int>& modes, NodeOutcome& o, double inherited_bound);
  void push_children(const std::vector<int>& modes, int k, const State& relaxed, double bound);

  const LaneChangeQp& qp_;
  const MiqpSettings& settings_;
  FastWorkspace& ws_;
  Clock::time_point start_;
  LaneChangeSolution& out_;
  double incumbent_ = kInfinity;
  bool numerical_trouble_ = false;
  bool cut_off_ = false;  ///< a node was pruned by the cutoff alone
};

void Search::accept(NodeOutcome& o) {
  if (o.objective < incumbent_ && o.objective < settings_.objective_cutoff) {
    incumbent_ = o.objective;
    std::swap(out_.path, o.path);
    out_.objective = incumbent_;
  }
}

// The hinted modes, and the rounded root relaxation, each improved by moving
// its lane switches: with an incumbent near the optimum from the start, the
// search prunes most of its tree at once.
void Search::find_incumbent(const NodeOutcome& root, const SolveHints& hints) {
  // Nothing beats the root relaxation: once an incumbent is within the gap
  // of it, the search is over (in later rounds the hint is usually there).
  const double root_bound = root.objective;
  // Out of time, the search returns at once: the heuristics must not run on
  // past the limit either (a real-time step budget).
  auto settled = [&] {
    return root_bound >= prune_level() || seconds_so_far() > settings_.time_limit_s ||
           out_of_work();
  };
  auto accept = [this](NodeOutcome& o) { this->accept(o); };
  auto level = [this] { return prune_level(); };
  // Up to two starts, in the workspace's lists: the hint's modes, and the
  // rounded root where it differs.
  auto& starts = ws_.start_modes;
  std::array<double, 2> objectives{kInfinity, kInfinity};
  std::size_t count = 0;
  if (hints.modes != nullptr && static_cast<int>(hints.modes->size()) == qp_.steps + 1) {
    starts[count++].assign(hints.modes->begin(), hints.modes->end());
  }
  rounded_modes(qp_, ws_, root.path, starts[count]);
  if (count == 0 || starts[1] != starts[0]) ++count;
  for (std::size_t i = 0; i < count; ++i) {
    if (settled()) break;
    if (!complete(qp_, starts[i]) || !reachable(ws_, starts[i])) continue;
    NodeOutcome o = solve_node(qp_, starts[i], ws_);
    ++out_.nodes;
    if (o.feasible) {
      objectives[i] = o.objective;
      accept(o);
    }
    ws_.recycle(o.path);
  }
  // The better start first: its switches are likely nearer the optimum.
  const std::size_t first = count == 2 && objectives[1] < objectives[0] ? 1 : 0;
  for (std::size_t j = 0; j < count; ++j) {
    const std::size_t i = j == 0 ? first : 1 - first;
    if (!std::isfinite(objectives[i]) || settled()) continue;
    improve_switches(qp_, starts[i], objectives[i], ws_, out_.nodes, accept, settled, level);
  }
}

// Depth first from the root, best child first. True when the search ran to
// its end; false when a limit stopped it, with the solution filled in.
bool Search::branch_and_bound(const std::vector<int>& root_modes, NodeOutcome& root) {
  for (OpenNode& left : ws_.stack) ws_.spare_modes.push_back(std::move(left.modes));
  ws_.stack.clear();
  numerical_trouble_ = root.numerical_failure;
  if (!root.feasible) return true;
  // The root's QP is solved already, but the limits hold for it as for any
  // node: the incumbent search may have used up the time.
  if (stopped_at_limit(root.objective)) return false;
  explore(root_modes, root, -kInfinity);
  ws_.recycle(root.path);
  while (!ws_.stack.empty()) {
    if (stopped_at_limit(kInfinity)) return false;
    OpenNode node = std::move(ws_.stack.back());
    ws_.stack.pop_back();
    NodeOutcome o =
        solve_node(qp_, node.modes, ws_, prune_level(), NodePrecision::RoughBelowCutoff);
    ++out_.nodes;
    explore(node.modes, o, node.bound);
    ws_.recycle(o.path);
    ws_.spare_modes.push_back(std::move(node.modes));
  }
  return true;
}

// False while the time, the work and the nodes last. At a limit the solution takes the
// incumbent and the least bound of the nodes left (`pending_bound` for one
// not yet on the stack): no completion of theirs is cheaper.
bool Search::stopped_at_limit(double pending_bound) {
  const double elapsed = seconds_so_far();
  const bool out_of_time = elapsed > settings_.time_limit_s;
  const bool spent = out_of_work();
  if (!out_of_time && !spent && out_.nodes < settings_.node_limit) return false;
  out_.status = out_of_time ? MiqpStatus::TimeLimit
                : spent     ? MiqpStatus::WorkLimit
                            : MiqpStatus::NodeLimit;
  out_.solve_ms = elapsed * 1000.0;
  out_.qp_iterations = ws_.iterations;
  if (out_.has_solution()) modes_of(qp_, out_.path, out_.modes);
  out_.best_bound = std::min({out_.objective, pending_bound, least_open_bound(ws_.stack)});
  return true;
}

// Prunes the node, takes its point as an incumbent when that meets some mode
// at every node, or branches on it.
// The caller gives o's path back once it returns.
void Search::explore(const std::vector<int>& modes, NodeOutcome& o, double inherited_bound) {
  numerical_trouble_ = numerical_trouble_ || o.numerical_failure;
  cut_off_ = cut_off_ || o.cut_off || (o.feasible && o.objective >= settings_.objective_cutoff);
  if (!o.feasible || o.objective >= prune_level()) return;
  int k = branching_node(qp_, ws_, modes, o.path, o.coarse ? kCoarseViolation : kModeTolerance);
  if (k < 0 && o.coarse) {  // maybe a leaf: only a solution can tell
    ws_.recycle(o.path);
    o = solve_node(qp_, modes, ws_, prune_level());
    numerical_trouble_ = numerical_trouble_ || o.numerical_failure;
    cut_off_ = cut_off_ || o.cut_off;
    if (!o.feasible || o.objective >= prune_level()) return;
    k = branching_node(qp_, ws_, modes, o.path, kModeTolerance);
  }
  if (k < 0) {
    accept(o);
    return;
  }
  // A child's QP has this one's rows and more: its optimum is no lower.
  push_children(modes, k, o.path.states[k], std::max(inherited_bound, o.lower_bound));
}

// Children in order of how far the relaxed state is from each mode; the
// nearest is pushed last so that it is explored first.
void Search::push_children(const std::vector<int>& modes, int k, const State& relaxed,
                           double bound) {
  const auto& options = qp_.node_modes[k];
  auto& order = ws_.child_order;
  order.clear();
  for (int m = 0; m < static_cast<int>(options.size()); ++m) {
    if (ws_.possible(k, m)) order.emplace_back(mode_violation(options[m], relaxed), m);
  }
  std::sort(order.begin(), order.end(), std::greater<>());
  for (const auto& [violation, m] : order) {
    std::vector<int> child;
    if (!ws_.spare_modes.empty()) {
      child = std::move(ws_.spare_modes.back());
      ws_.spare_modes.pop_back();
    }
    child.assign(modes.begin(), modes.end());
    child[k] = m;
    ws_.stack.push_back(OpenNode{std::move(child), bound});
  }
}

// The search ran to its end: the incumbent is optimal, or no point exists.
void Search::finish() {
  out_.solve_ms = seconds_so_far() * 1000.0;
  out_.qp_iterations = ws_.iterations;
  if (out_.has_solution()) {
    out_.status = MiqpStatus::Optimal;
    modes_of(qp_, out_.path, out_.modes);
    // Every node left behind was pruned within the gap of the incumbent.
    out_.best_bound = out_.objective;
    return;
  }
  if (cut_off_ && !numerical_trouble_) {
    out_.status = MiqpStatus::Cutoff;
    out_.best_bound = settings_.objective_cutoff;
    out_.objective = settings_.objective_cutoff;
    out_.message = "no point is cheaper than the cutoff";
    return;
  }
  out_.status = numerical_trouble_ ? MiqpStatus::NumericalError : MiqpStatus::Infeasible;
  out_.message = numerical_trouble_ ? "a QP relaxation failed" : "no lane sequence is feasible";
  // A failed relaxation proves nothing about its subtree.
  out_.best_bound = numerical_trouble_ ? -kInfinity : kInfinity;
}

}  // namespace

}  // namespace detail

using namespace detail;  // NOLINT(google-build-using-namespace): this file's own functions

std::unique_ptr<LaneChangeWorkspace> FastLaneChangeSolver::make_workspace() const {
  return std::make_unique<FastWorkspace>();
}

LaneChangeSolution FastLaneChangeSolver::solve(const LaneChangeQp& qp, const MiqpSettings& settings,
                                               const SolveHints& hints) const {
  LaneChangeSolution out;
  solve_into(qp, settings, hints, out);
  return out;
}

void FastLaneChangeSolver::solve_into(const LaneChangeQp& qp, const MiqpSettings& settings,
                                      const SolveHints& hints, LaneChangeSolution& out) const {
  const auto start = Clock::now();
  std::unique_ptr<LaneChangeWorkspace> owned;
  FastWorkspace& ws = workspace_for(hints, owned);
  out.clear();
  ws.iterations = 0;
  if (!pre_check(qp, hints, options_.reachable_modes, ws, out)) return;
  reserve_for_search(qp.steps, ws);
  std::vector<int>& root_modes = ws.root_modes;
  root_modes.assign(qp.steps + 1, kFree);
  NodeOutcome root = solve_node(qp, root_modes, ws);
  ++out.nodes;
  Search search(qp, settings, ws, start, out);
  if (root.feasible) search.find_incumbent(root, hints);
  out.incumbent_qps = out.nodes;
  if (search.branch_and_bound(root_modes, root)) search.finish();
  ws.recycle(root.path);
}

}  // namespace lanechange::expert
