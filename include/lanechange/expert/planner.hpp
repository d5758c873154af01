#pragma once
// The expert: successive linearization of the lane-change MIQP (paper Sec. II).
// Round r linearizes the dynamics about round r-1's solution (the warm start
// first), re-predicts the cars (IDM reacts to that path), and solves the MIQP
// exactly over every gap config.expert.gap allows (one MIQP per gap, each cut
// off by the best found before it).
// It stops when the largest change of x and y between two rounds' solutions is
// within the tolerance, or at the round limit. Where those rounds fail (a
// cycle or the limit), config.expert.globalisation may go on with rounds kept
// within a trust region of the last solution (docs/expert.md).
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "lanechange/config.hpp"
#include "lanechange/expert/formulation.hpp"
#include "lanechange/expert/gap_slots.hpp"
#include "lanechange/expert/lane_change_solver.hpp"
#include "lanechange/expert/miqp.hpp"
#include "lanechange/scenario.hpp"
#include "lanechange/traffic.hpp"
#include "lanechange/trajectory.hpp"

namespace lanechange::expert {

enum class PlanStatus {
  Converged,       ///< the rounds' solutions stopped changing
  IterationLimit,  ///< the round limit came first (a failure, as in the authors' code)
  Cycling,         ///< the rounds alternate between two paths (config.expert.cycle_tolerance)
  Infeasible,      ///< a round's MIQP has no solution: no safe lane change exists
  TimeLimit,       ///< the time limit came first
  WorkLimit,       ///< the budget of interior-point iterations came first
  SolverError,     ///< the back-end failed
};
[[nodiscard]] std::string_view to_string(PlanStatus status);

struct RoundReport {
  MiqpStatus status = MiqpStatus::NumericalError;
  double objective = kInfinity;
  double max_change = kInfinity;  ///< of x and y against the previous round (m)
  long nodes = 0;
  long qp_iterations = 0;
  long incumbent_qps = 0;
  double solve_ms = 0.0;
  double trust_radius = kInfinity;  ///< m, the box of a trust-region round (none: infinite)
};

struct ExpertResult {
  PlanStatus status = PlanStatus::SolverError;
  std::string reason;      ///< in words, for anything but Converged
  Iterate path;            ///< the last round's solution (empty if none); see cut_with_incumbent
  std::vector<int> modes;  ///< lane mode per node of the last solution
  /// What those modes mean: the lanes the ego may occupy at each node
  /// (nullopt where no lane rule applies, as at t = 0). It is the integer
  /// part of the plan, in words that do not depend on the formulation.
  std::vector<std::optional<LaneOccupancy>> occupancy;
  TrafficPrediction prediction;  ///< the cars as the last round saw them
  /// The gap of the target lane the last round's solution merges into: the
  /// best of those config.expert.gap allows.
  Gap gap;
  double objective = kInfinity;  ///< of the last round's MIQP
  /// A proven lower bound on that MIQP's optimum: the objective itself where
  /// the round was solved to the end; below it where a budget cut the round
  /// with an incumbent (the least bound of the nodes and gaps left, -infinity
  /// where a gap was not reached).
  double best_bound = -kInfinity;
  std::vector<RoundReport> rounds;
  double total_ms = 0.0;
  [[nodiscard]] int iterations() const { return static_cast<int>(rounds.size()); }
  /// (objective - best_bound) / max(1, |objective|): 0 for a round solved to
  /// the end, infinite where no bound is known.
  [[nodiscard]] double relative_gap() const { return expert::relative_gap(objective, best_bound); }
  /// Stopped by its budget (TimeLimit or WorkLimit) with a path: the cut
  /// round's incumbent, else the last round's solution. Feasible for its
  /// round's MIQP, but neither proven optimal nor converged: an anytime
  /// answer for a closed loop; to_trajectory still labels it failure.
  [[nodiscard]] bool cut_with_incumbent() const {
    return (status == PlanStatus::TimeLimit || status == PlanStatus::WorkLimit) &&
           !path.states.empty();
  }
  /// As a result made afresh, keeping the memory of its lists.
  void clear();
};

struct PlanLimits {
  double time_limit_s = 60.0;  ///< whole plan
  /// Interior-point iterations over the whole plan: a deadline in work, the
  /// same on any load (closed_loop.deadline).
  long qp_iterations = std::numeric_limits<long>::max();
};

/// Where to start when a good guess is at hand (a re-plan in closed loop
/// starts from the last plan shifted by a step). Ignored when the sizes do
/// not fit the scenario's steps.
/// The memory a plan builds its problems and predicts the cars in, kept by
/// the caller across plans as PlanHints::workspace is: a thread's later plans
/// then reuse it instead of allocating their own.
/// One round's answer: the best gap's solution, what its modes mean, and the gap.
struct RoundSolution {
  LaneChangeSolution solution;
  std::vector<std::optional<LaneOccupancy>> occupancy;  ///< of the solution's modes
  Gap gap;                                              ///< the solution's
};

struct PlanMemory {
  LaneChangeQp problem;                ///< each gap's problem in turn, built in place
  TrafficModel traffic;                ///< the model each prediction resets
  std::vector<EgoFootprint> ego_path;  ///< the path the cars react to in a prediction
  TrafficPrediction round_start;       ///< the cars as a round begins
  TrafficPrediction gap_cars;          ///< the cars as the gap being solved sees them
  std::vector<Gap> gaps;               ///< a round's gaps, in the order it solves them
  Spare<Gap> spare_gaps;               ///< gaps of a larger scene, with their memory
  Gap paper_gap;                       ///< Eq. 1's, which the first warm start aims into
  std::vector<int> mode_hint;          ///< the modes a gap's search tries first
  Iterate point;                       ///< the round's linearization point
  Iterate gap_point;                   ///< a first round's warm start aimed into one gap
  Iterate two_back;                    ///< the solution of the round before the last
  Iterate previous;                    ///< the point before the last (trust region)
  LaneChangeSolution gap_solution;     ///< the gap being solved
  RoundSolution round;                 ///< the round's best gap so far
};

struct PlanHints {
  const Iterate* path = nullptr;            ///< the first linearization point
  const std::vector<int>* modes = nullptr;  ///< lane modes per node, for the first round
  /// The path is a plan's (a round's solution, or the last plan shifted by
  /// the steps since): the first round then converges as every later one
  /// does, when its solution lies within the tolerance of the path it was
  /// linearized about. A warm start's guess is no plan, and the first round
  /// from it never converges.
  bool path_is_plan = false;
  /// Where the rounds solve, kept by the caller across plans (made by this
  /// planner's solver().make_workspace()): a re-planning session's next
  /// plan then warm-starts from this one's last QP, once the session has
  /// advanced it by the steps in between. nullptr: a fresh one per plan.
  LaneChangeWorkspace* workspace = nullptr;
  /// Plan through this gap alone, whatever config.expert.gap allows: a
  /// replay of a plan's own modes, which belong to its gap.
  const Gap* gap = nullptr;
  /// The gap `path` and `modes` drive into (a re-plan's last plan's): a
  /// planner that replays the modes replays them into it. The exact search
  /// tries every allowed gap and needs none.
  const GapFrame* last_gap = nullptr;
  /// Where the rounds build each gap's problem and predict the cars, kept by
  /// the caller across plans as `workspace` is. nullptr: one per plan.
  PlanMemory* memory = nullptr;
};

/// The cars as a round linearized about `point` sees them: predicted along
/// the point's path where they react to the ego (traffic_reacts), else
/// without it. `predicted_steps` steps of `dt`.
[[nodiscard]] TrafficPrediction prediction_along(const Scenario& scenario, const Config& config,
                                                 int predicted_steps, double dt,
                                                 const Iterate& point);

/// The initial guess (config.expert.warm_start) for a scenario, aimed into
/// `gap` (the quintic ends behind its car ahead, at that car's speed).
[[nodiscard]] Iterate warm_start(const Scenario& scenario, const Config& config,
                                 const TrafficPrediction& prediction, const Gap& gap);
/// The same into `out`, whose lists keep their memory.
void warm_start(const Scenario& scenario, const Config& config, const TrafficPrediction& prediction,
                const Gap& gap, Iterate& out);
/// The same aimed into Eq. 1's gap (paper_gap).
[[nodiscard]] Iterate warm_start(const Scenario& scenario, const Config& config,
                                 const TrafficPrediction& prediction);
/// A second quintic warm start into `gap`, for a first round that found the
/// gap infeasible about warm_start()'s path: aimed where the ego's own pace
/// takes it if that lies in the gap, else at the gap's nearer end. False,
/// with `out` untouched, where warm_start()'s aim lies within the ego's reach
/// at the horizon's end (that path is one the ego can drive), or the warm
/// start is the authors'.
bool paced_warm_start(const Scenario& scenario, const Config& config,
                      const TrafficPrediction& prediction, const Gap& gap, Iterate& out);

/// The quintic warm start with its lane change timed to `modes` (lane modes
/// per node, as PlanHints::modes): the body first touches the line at the
/// first node whose mode leaves the ego lane and is first wholly across at
/// the first node in the target lane. Rounds with those modes fixed then start
/// near where they end, not from a change timed to the middle of the horizon.
[[nodiscard]] Iterate warm_start_for_modes(const Scenario& scenario, const Config& config,
                                           const TrafficPrediction& prediction,
                                           const std::vector<int>& modes, const Gap& gap);
/// The same aimed into Eq. 1's gap (paper_gap).
[[nodiscard]] Iterate warm_start_for_modes(const Scenario& scenario, const Config& config,
                                           const TrafficPrediction& prediction,
                                           const std::vector<int>& modes);

/// A round's MIQP and the point it is linearized about.
struct LinearizedRound {
  Iterate point;
  LaneChangeQp qp;
};

class ExpertPlanner {
 public:
  /// `config` is the base; each scenario's own fields override it.
  ExpertPlanner(Config config, std::shared_ptr<const LaneChangeSolver> solver);

  [[nodiscard]] ExpertResult plan(const Scenario& scenario, const PlanLimits& limits = {},
                                  const PlanHints& hints = {}) const;
  /// The same into `result`, whose memory a caller that plans again keeps:
  /// with hints.workspace and hints.memory kept too, a thread's plans
  /// allocate nothing once it has planned scenes of that size.
  void plan(const Scenario& scenario, const PlanLimits& limits, const PlanHints& hints,
            ExpertResult& result) const;

  /// The MIQP of `plan`'s first round, for the same scenario and hints: the
  /// dynamics linearized about the hint's path (else the warm start), the
  /// cars predicted along it, the target lane's rows those of the hint's gap
  /// (else Eq. 1's). Every lane-mode sequence of that round shares it, so
  /// strategy-qp ranks its candidates with one QP each on it.
  [[nodiscard]] LinearizedRound first_round(const Scenario& scenario,
                                            const PlanHints& hints = {}) const;

  /// The plan as a trajectory: the controls re-simulated through the
  /// (nonlinear) discrete model, the prediction, the label and the collision
  /// check. A plan that is not Converged is labelled failure.
  [[nodiscard]] Trajectory to_trajectory(const ExpertResult& result,
                                         const Scenario& scenario) const;

  [[nodiscard]] const Config& config() const { return config_; }
  [[nodiscard]] const LaneChangeSolver& solver() const { return *solver_; }

 private:
  Config config_;
  std::shared_ptr<const LaneChangeSolver> solver_;
};

/// The ego's states at the nodes of a path's controls, run from `start`
/// through the (nonlinear) discrete model over `steps` steps of `dt`, each
/// node's a the control applied from it: what a follower of the plan drives,
/// whatever the linearization said. `out` keeps its memory.
void poses_along(const Iterate& path, const EgoState& start, int steps, double dt,
                 std::vector<EgoState>& out);

}  // namespace lanechange::expert
