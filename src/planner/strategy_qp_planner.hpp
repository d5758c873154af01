#pragma once
// strategy-qp (docs/strategy.md): the learned lane strategy finished by the
// exact structured QP. The strategy model ranks the integer parts (lane
// modes per node) that plans of similar scenes took; each of the top k is
// fixed and solved by the expert's successive linearization with one QP per
// round and no search; the cheapest converged, collision-free one is
// followed. Where none is, the exact search runs with the predictions as
// hints, so the answer is then the expert's own.
#include <memory>
#include <vector>

#include "lanechange/learn/strategy.hpp"
#include "planner/miqp_planner.hpp"

namespace lanechange::planner {

/// How one candidate strategy fared.
struct CandidateOutcome {
  learn::Strategy strategy;  ///< empty for the last plan's modes (closed loop)
  expert::PlanStatus status = expert::PlanStatus::SolverError;
  bool collision = false;
  bool rescued = false;  ///< converged in the trust region (expert.globalisation)
  double objective = expert::kInfinity;
  [[nodiscard]] bool feasible() const {
    return status == expert::PlanStatus::Converged && !collision;
  }
};

struct StrategyPlan {
  expert::ExpertResult result;  ///< the plan followed (the exact one when no candidate was)
  std::vector<CandidateOutcome> candidates;  ///< in the model's order
  int chosen = -1;                           ///< index into candidates; -1: the exact search
  double predict_ms = 0.0;
  double total_ms = 0.0;
};

/// The lane modes (indices of LaneChangeQp::node_modes, as the solvers take
/// them) of a strategy on a horizon of `steps` steps under `rule`; a mode the
/// rule lacks becomes -1, which no fixed-mode solve accepts.
[[nodiscard]] std::vector<int> modes_of_strategy(const learn::Strategy& strategy, int steps,
                                                 LaneRule rule);

class StrategyQpPlanner final : public ClosedLoopPlanner {
 public:
  StrategyQpPlanner(Config config, std::shared_ptr<const learn::StrategyModel> model);
  [[nodiscard]] std::string_view name() const override { return "strategy-qp"; }
  [[nodiscard]] std::unique_ptr<PlannerSession> start(const Scenario& scene) const override;

  /// One plan of `scene`. Const and safe to call from many threads.
  [[nodiscard]] StrategyPlan plan(const Scenario& scene, const expert::PlanLimits& limits = {},
                                  const expert::PlanHints& hints = {}) const;
  /// The exact expert it falls back on (config as this planner's).
  [[nodiscard]] const expert::ExpertPlanner& exact() const { return exact_; }

 private:
  [[nodiscard]] CandidateOutcome solve_candidate(const Scenario& scene,
                                                 const std::vector<int>& modes,
                                                 const expert::PlanLimits& limits,
                                                 const expert::PlanHints& hints,
                                                 expert::ExpertResult& result) const;

  Config config_;
  std::shared_ptr<const learn::StrategyModel> model_;
  expert::ExpertPlanner fixed_;  ///< the expert's rounds with the fixed-mode solver
  expert::ExpertPlanner exact_;
};

}  // namespace lanechange::planner
