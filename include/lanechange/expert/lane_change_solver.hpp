#pragma once
// A back-end that solves one round's lane-change MIQP (formulation.hpp).
// Implementations are const and hold no per-solve state, so one instance can
// serve many threads (the Bonmin one serialises itself: see bonmin_solver.hpp).
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "lanechange/expert/formulation.hpp"
#include "lanechange/expert/miqp.hpp"

namespace lanechange::expert {

struct LaneChangeSolution {
  MiqpStatus status = MiqpStatus::NumericalError;
  Iterate path;            ///< empty unless a point was found
  std::vector<int> modes;  ///< the lane mode chosen at each node (-1 where none applies)
  double objective = kInfinity;
  /// Proven lower bound on the optimum, as MiqpResult::best_bound (see
  /// relative_gap): -infinity where none is known, +infinity when
  /// Infeasible, the objective when a search ends Optimal (it proved nothing
  /// cheaper by more than its gap tolerances), and the least bound of its
  /// open nodes when a limit stopped it. The fixed-mode back-end searches
  /// nothing and leaves it -infinity.
  double best_bound = -kInfinity;
  long nodes = 0;          ///< QPs (ours) or tree nodes (Bonmin) solved
  long qp_iterations = 0;  ///< interior-point iterations over all QPs (ours)
  long incumbent_qps = 0;  ///< QPs spent finding a first solution before the search (ours)
  double solve_ms = 0.0;
  std::string message;
  [[nodiscard]] bool has_solution() const { return !path.states.empty(); }
  /// As a solution made afresh, keeping the memory of its lists.
  void clear();
};

/// Memory a back-end may keep between solves (rounds of one plan, or plans of
/// one thread). A workspace must not be shared by two solves at once.
class LaneChangeWorkspace {
 public:
  virtual ~LaneChangeWorkspace() = default;
  /// The next problems start `nodes` nodes later than the last one solved
  /// here: a re-planning session's step. A back-end that warm-starts from
  /// its last solution lines it up with them.
  virtual void advance(int /*nodes*/) {}
};

/// What a caller may pass to speed a solve up without changing its answer.
struct SolveHints {
  LaneChangeWorkspace* workspace = nullptr;
  const std::vector<int>* modes = nullptr;  ///< a lane mode per node, likely near the optimum
  const std::vector<Control>* controls = nullptr;  ///< a starting guess for the controls
};

class LaneChangeSolver {
 public:
  virtual ~LaneChangeSolver() = default;
  [[nodiscard]] virtual std::string_view name() const = 0;
  /// A workspace for this back-end (nullptr if it keeps none).
  [[nodiscard]] virtual std::unique_ptr<LaneChangeWorkspace> make_workspace() const {
    return nullptr;
  }
  [[nodiscard]] virtual LaneChangeSolution solve(const LaneChangeQp& qp,
                                                 const MiqpSettings& settings,
                                                 const SolveHints& hints = {}) const = 0;
  /// The same into `out`, whose lists keep their memory: with the same
  /// workspace, a caller that solves again allocates nothing once they have
  /// grown (the fast and fixed-mode back-ends; the others fill it by value).
  virtual void solve_into(const LaneChangeQp& qp, const MiqpSettings& settings,
                          const SolveHints& hints, LaneChangeSolution& out) const {
    out = solve(qp, settings, hints);
  }
};

/// The reference: the MIQP form (to_miqp) solved by Bonmin's B-BB to proven
/// optimality. Slow; the ground truth for the others.
class ReferenceLaneChangeSolver final : public LaneChangeSolver {
 public:
  explicit ReferenceLaneChangeSolver(double big_m = 1000.0) : big_m_(big_m) {}
  [[nodiscard]] std::string_view name() const override { return "reference"; }
  [[nodiscard]] LaneChangeSolution solve(const LaneChangeQp& qp, const MiqpSettings& settings,
                                         const SolveHints& hints = {}) const override;

 private:
  double big_m_;
};

/// Our own exact solver (fast_solver.cpp): branch and bound over the lane
/// mode of each node, each node a structured QP solved by a Riccati-based
/// interior-point method.
struct FastSolverOptions {
  /// Drop, before the search, the lane modes that no state the round can
  /// reach satisfies (bound tightening from the dynamics, the state bounds and
  /// the control box; docs/expert.md). It changes no answer, only the work.
  bool reachable_modes = true;
};

class FastLaneChangeSolver final : public LaneChangeSolver {
 public:
  explicit FastLaneChangeSolver(FastSolverOptions options = {}) : options_(options) {}
  [[nodiscard]] std::string_view name() const override { return "fast"; }
  [[nodiscard]] std::unique_ptr<LaneChangeWorkspace> make_workspace() const override;
  [[nodiscard]] LaneChangeSolution solve(const LaneChangeQp& qp, const MiqpSettings& settings,
                                         const SolveHints& hints = {}) const override;
  void solve_into(const LaneChangeQp& qp, const MiqpSettings& settings, const SolveHints& hints,
                  LaneChangeSolution& out) const override;

 private:
  FastSolverOptions options_;
};

/// No search: the one structured QP of the lane modes in SolveHints::modes
/// (one index per node, as LaneChangeSolution::modes; -1 where no lane rule
/// applies). The convex part of the MIQP once its integer part is fixed, as
/// CoCo and MLOPT solve a predicted strategy (docs/strategy.md). Infeasible
/// when the modes are missing, do not fit the problem, or leave no point; the
/// solution's modes are the given ones, so the next round keeps them.
/// Shares FastLaneChangeSolver's workspace type.
struct FixedModeSettings {
  /// Stop at the first iterate within `rough_tolerance` of the optimum
  /// (complementarity, rows and slack): enough to rank candidate modes, as
  /// strategy-qp's screen does, in about half the iterations; not a plan to
  /// follow.
  bool rough = false;
  double rough_tolerance = 1e-3;
};

class FixedModeLaneChangeSolver final : public LaneChangeSolver {
 public:
  explicit FixedModeLaneChangeSolver(FixedModeSettings settings = {}) : settings_(settings) {}
  [[nodiscard]] std::string_view name() const override { return "fixed-mode"; }
  [[nodiscard]] std::unique_ptr<LaneChangeWorkspace> make_workspace() const override;
  [[nodiscard]] LaneChangeSolution solve(const LaneChangeQp& qp, const MiqpSettings& settings,
                                         const SolveHints& hints = {}) const override;
  void solve_into(const LaneChangeQp& qp, const MiqpSettings& settings, const SolveHints& hints,
                  LaneChangeSolution& out) const override;

 private:
  FixedModeSettings settings_;
};

/// What FixedModeLaneChangeSolver::solve checks before any QP: the modes fit
/// `qp`, its initial state meets the lane rules, and bound tightening over the
/// round's dynamics, boxes and mode rows leaves a state at every node. False
/// proves the modes infeasible in this round, in microseconds; true proves
/// nothing. strategy-qp skips the votes it refuses (docs/strategy.md).
[[nodiscard]] bool lane_modes_can_hold(const LaneChangeQp& qp, const std::vector<int>& modes);

/// The solver named `name`: "fast" or "reference".
[[nodiscard]] std::shared_ptr<const LaneChangeSolver> make_lane_change_solver(std::string_view name,
                                                                              double big_m);

}  // namespace lanechange::expert
