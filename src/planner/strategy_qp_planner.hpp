#pragma once
// strategy-qp (docs/strategy.md): the learned lane strategy finished by the
// exact structured QP. The strategy model ranks the integer parts (lane
// modes per node) that plans of similar scenes took; a candidate is fixed and
// solved by the expert's successive linearization with one QP per round and
// no search. By default the candidates are first ranked by one QP each at
// the first round's shared linearization, and the rounds run for them in
// that order until one converges collision-free; that one is followed.
// Where none does, the exact search runs with the predictions as hints, so
// the answer is then the expert's own.
#include <memory>
#include <vector>

#include "lanechange/learn/strategy.hpp"
#include "planner/miqp_planner.hpp"

namespace lanechange::planner {

/// How one candidate strategy fared.
struct CandidateOutcome {
  learn::Strategy strategy;  ///< empty for the last plan's modes (closed loop)
  /// Its QP at the first round's linearization (selection "screened"; infinite
  /// when that QP has no solution, and then the status is Infeasible).
  double screen_objective = expert::kInfinity;
  bool rounds_run = false;  ///< false: an earlier candidate was followed first
  expert::PlanStatus status = expert::PlanStatus::SolverError;
  bool collision = false;
  bool rescued = false;  ///< converged in the trust region (expert.globalisation)
  double objective = expert::kInfinity;
  int rounds = 0;          ///< QPs of its successive linearization
  double rounds_ms = 0.0;  ///< their time, with the collision check
  [[nodiscard]] bool feasible() const {
    return status == expert::PlanStatus::Converged && !collision;
  }
};

struct StrategyPlan {
  expert::ExpertResult result;  ///< the plan followed (the exact one when no candidate was)
  std::vector<CandidateOutcome> candidates;  ///< in the model's order
  int chosen = -1;                           ///< index into candidates; -1: the exact search
  double predict_ms = 0.0;  ///< ordering the gaps and every gap's vote with its candidates' set-up
  double screen_ms = 0.0;   ///< the first round's QPs of every candidate, over every gap tried
  /// Interior-point iterations over every QP the plan solved (screen, rounds,
  /// the exact search's): with the time per iteration, where the time goes.
  long qp_iterations = 0;
  double total_ms = 0.0;
};

/// The lane modes (indices of LaneChangeQp::node_modes, as the solvers take
/// them) of a strategy on a horizon of `steps` steps under `rule`; a mode the
/// rule lacks becomes -1, which no fixed-mode solve accepts.
[[nodiscard]] std::vector<int> modes_of_strategy(const learn::Strategy& strategy, int steps,
                                                 LaneRule rule);

/// The lane changes whose switch nodes (first out of the ego lane, first in the
/// target lane) each lie within `reach` nodes of `strategy`'s, nearest first
/// (by the sum of the shifts); none unless `strategy` is one lane change
/// (ego lane, across, target lane, each once and in that order).
[[nodiscard]] std::vector<learn::Strategy> neighbour_strategies(const learn::Strategy& strategy,
                                                                int reach);

class StrategyQpPlanner final : public ClosedLoopPlanner {
 public:
  StrategyQpPlanner(Config config, std::shared_ptr<const learn::StrategyModel> model);
  [[nodiscard]] std::string_view name() const override { return "strategy-qp"; }
  [[nodiscard]] std::unique_ptr<PlannerSession> start(const Scenario& scene) const override;

  /// One plan of `scene`. Const and safe to call from many threads.
  [[nodiscard]] StrategyPlan plan(const Scenario& scene, const expert::PlanLimits& limits = {},
                                  const expert::PlanHints& hints = {}) const;
  /// Every candidate of `plan`, each with its rounds run (none followed):
  /// what the study counts as top-1 and top-k feasible.
  /// One strategy's rounds from the expert's warm start, as assess() runs
  /// each candidate: with a plan's own strategy, what a perfect vote gets.
  [[nodiscard]] CandidateOutcome assess_strategy(const Scenario& scene,
                                                 const learn::Strategy& strategy) const;
  [[nodiscard]] std::vector<CandidateOutcome> assess(const Scenario& scene,
                                                     const expert::PlanLimits& limits = {},
                                                     const expert::PlanHints& hints = {}) const;
  /// The exact expert it falls back on (config as this planner's).
  [[nodiscard]] const expert::ExpertPlanner& exact() const { return exact_; }

 private:
  struct Candidate {
    learn::Strategy strategy;
    std::vector<int> modes;
    /// Its first linearization point when the plan has no path to start
    /// from (StrategyQpSettings::timed_warm_start), else empty.
    expert::Iterate start;
    /// The path its rounds start from: its own, else the plan's hint.
    /// Its first round's linearization at first_point, when the vote pool's
    /// check made it (StrategyQpSettings::vote_pool): the screen reuses it.
    std::shared_ptr<const expert::LinearizedRound> first;
    expert::Gap gap;  ///< the gap its modes drive into
    [[nodiscard]] const expert::Iterate* first_point(const expert::PlanHints& hints) const {
      return start.states.empty() ? hints.path : &start;
    }
    /// Whether first_point is a plan's path (PlanHints::path_is_plan).
    [[nodiscard]] bool starts_from_plan(const expert::PlanHints& hints) const {
      return start.states.empty() && hints.path_is_plan;
    }
  };
  using Linearization = std::shared_ptr<const expert::LinearizedRound>;
  /// Gives `c` its first round (`shared` for every candidate without a start
  /// of its own, made once) and says whether its modes can hold there.
  [[nodiscard]] bool can_hold(const Scenario& scene, const expert::PlanHints& hints, Candidate& c,
                              Linearization& shared) const;
  /// Gives candidates their timed warm starts where the plan has no path,
  /// one at a time on one traffic prediction: a vote pool ranks more
  /// strategies than the plan looks at (strategy_qp_planner.cpp).
  class StartTimer;
  /// The gaps whose strategies a plan tries, in order: the last plan's
  /// (hints.last_gap), else Eq. 1's, else the one beside the ego; then up to
  /// strategy_qp.other_gaps others around the ego, soonest open first.
  [[nodiscard]] std::vector<expert::Gap> gaps_to_try(const Scenario& scene,
                                                     const expert::PlanHints& hints) const;
  /// The predicted strategies into `gap` (after the last plan's modes, in
  /// closed loop), each once on this horizon, the first `candidates` of the
  /// vote pool that can hold (`replan_candidates` for a gap after the first).
  [[nodiscard]] std::vector<Candidate> candidates_of(const Scenario& scene,
                                                     const expert::PlanHints& hints,
                                                     const expert::Gap& gap,
                                                     bool first_gap = true) const;
  /// The candidates of `gaps[i]`, screened or in order as configured.
  void follow_gap(const Scenario& scene, const expert::PlanLimits& limits,
                  const expert::PlanHints& hints, const expert::Gap& gap, bool first_gap,
                  StrategyPlan& out, std::vector<int>& rescued_hint) const;
  /// Runs the candidates' rounds in the list's order; follows the cheapest,
  /// or the first that holds when `stop_at_first`.
  void follow_in_order(const Scenario& scene, const expert::PlanLimits& limits,
                       const expert::PlanHints& hints, const std::vector<Candidate>& list,
                       bool stop_at_first, StrategyPlan& out, std::vector<int>& rescued_hint) const;
  /// Ranks the candidates by one QP each on the first round's linearization,
  /// then runs the rounds in that order and follows the first that holds.
  void follow_screened(const Scenario& scene, const expert::PlanLimits& limits,
                       const expert::PlanHints& hints, const std::vector<Candidate>& list,
                       StrategyPlan& out, std::vector<int>& rescued_hint) const;
  /// A screen's solver (screen_solver_ or neighbour_screen_solver_) and its workspace.
  struct Screener {
    const expert::FixedModeLaneChangeSolver& solver;
    expert::LaneChangeWorkspace* workspace;
  };
  /// The first round's QP of `c` solved with its modes fixed and `cutoff`
  /// by `screener`, within what is `left` of the plan's budget; `first` holds
  /// the shared linearization and is rebuilt when `c` has a start of its own.
  [[nodiscard]] expert::LaneChangeSolution screen_one(const Scenario& scene,
                                                      const expert::PlanHints& hints,
                                                      const Candidate& c, double cutoff,
                                                      const expert::PlanLimits& left,
                                                      expert::LinearizedRound& first,
                                                      const Screener& screener) const;
  /// neighbour_nodes: tries the followed strategy's neighbours.
  void search_neighbours(const Scenario& scene, const expert::PlanLimits& limits,
                         StrategyPlan& out) const;
  /// Records one candidate's rounds; true when the plan follows it.
  bool take_candidate(CandidateOutcome& outcome, const std::vector<int>& modes,
                      expert::ExpertResult& plan, StrategyPlan& out,
                      std::vector<int>& rescued_hint) const;
  [[nodiscard]] CandidateOutcome solve_candidate(const Scenario& scene,
                                                 const std::vector<int>& modes,
                                                 const expert::Gap& gap,
                                                 const expert::PlanLimits& limits,
                                                 const expert::PlanHints& hints,
                                                 expert::ExpertResult& result) const;

  Config config_;
  std::shared_ptr<const learn::StrategyModel> model_;
  expert::ExpertPlanner fixed_;  ///< the expert's rounds with the fixed-mode solver
  expert::FixedModeLaneChangeSolver screen_solver_;
  /// Neighbours cost within tenths of a percent of the plan: their screen
  /// needs at least the default rough precision (1e-3).
  expert::FixedModeLaneChangeSolver neighbour_screen_solver_;
  expert::ExpertPlanner exact_;
};

}  // namespace lanechange::planner
