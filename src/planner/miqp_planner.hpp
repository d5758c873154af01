#pragma once
// The planners' internals, shared by the planners of src/planner/ (and the
// hierarchical planner's take-over, which is this session).
#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "lanechange/expert/gap_slots.hpp"
#include "lanechange/expert/planner.hpp"
#include "lanechange/planner/planner.hpp"

namespace lanechange::planner {

/// The scene as it is now: the initial scene's fields with the current
/// states of every car, and the horizon the config's mode asks for. A
/// shrinking horizon ends the initial horizon after `deadline_set_at` (s).
[[nodiscard]] Scenario scene_now(const Observation& observation, const Config& config,
                                 double deadline_set_at = 0.0);
/// The same into `out`, whose lists keep their memory.
void scene_now(const Observation& observation, const Config& config, Scenario& out,
               double deadline_set_at = 0.0);

/// The path shifted forward by `by` nodes and cut or padded (the last node
/// coasting along its heading) to `steps` steps: a plan made `by` steps ago,
/// as a guess for one from now.
[[nodiscard]] expert::Iterate shifted(const expert::Iterate& path, int by, int steps, double dt);
/// The same into `out`, whose lists keep their memory.
void shifted(const expert::Iterate& path, int by, int steps, double dt, expert::Iterate& out);
/// The lane modes likewise (node 0 free: its state is given).
[[nodiscard]] std::vector<int> shifted(const std::vector<int>& modes, int by, int steps);
void shifted(const std::vector<int>& modes, int by, int steps, std::vector<int>& out);

/// Where a re-planning session gets its plans: the exact expert, or
/// predicted strategies finished by QPs. Called with the scene now, the
/// step's time limit, the last plan shifted to now as hints, and the
/// session's result to fill (its lists keep their memory from step to step).
using PlanFunction = std::function<void(const Scenario&, const expert::PlanLimits&,
                                        const expert::PlanHints&, expert::ExpertResult&)>;

/// Re-plans every replan_period steps and follows the plan: the exact
/// expert's way in closed loop, shared by every planner that re-plans.
class MiqpSession final : public PlannerSession {
 public:
  /// Its re-plans keep a workspace of the expert's solver and their memory:
  /// once the session has planned, a step that follows a new plan allocates
  /// nothing.
  MiqpSession(const expert::ExpertPlanner& expert, const Config& config);
  /// With a workspace, every re-plan solves in it (PlanHints::workspace),
  /// advanced by the steps since the last: the next plan's QPs warm-start
  /// from this one's.
  MiqpSession(PlanFunction plan, const Config& config,
              std::unique_ptr<expert::LaneChangeWorkspace> workspace = nullptr);
  [[nodiscard]] Decision act(const Observation& observation) override;
  /// Time of the last re-plan (ms), for benchmarks.
  [[nodiscard]] double last_plan_ms() const { return last_plan_ms_; }
  /// How the last re-plan ended; Converged before the first.
  [[nodiscard]] expert::PlanStatus last_status() const { return last_status_; }
  /// The gap of the plan it follows (by the observation's car indices).
  [[nodiscard]] const expert::GapFrame& plan_gap() const { return plan_gap_; }

 private:
  /// Re-plans from the observation; returns why it failed ("" on success).
  std::string replan(const Observation& observation);
  /// Plans `scene` from a warm start per gap, without the last plan.
  void plan_cold(const Scenario& scene, const expert::PlanLimits& limits, expert::PlanHints hints);
  /// Where the plan's own path, the ego an oriented box, first meets a car
  /// as the plan predicts it: "" where it meets none.
  std::string collision_of(const expert::ExpertResult& plan, const Scenario& scene);
  [[nodiscard]] Decision fallback(const Observation& observation, const std::string& why);

  PlanFunction plan_function_;
  const Config& config_;
  LaneKeeper keeper_;
  std::optional<expert::Iterate> plan_;
  std::vector<int> modes_;
  int plan_step_ = 0;
  std::unique_ptr<expert::LaneChangeWorkspace> workspace_;
  int workspace_step_ = 0;     ///< the step of the last re-plan that used workspace_
  expert::PlanMemory memory_;  ///< where every re-plan builds and predicts (PlanHints::memory)
  Scenario scene_;             ///< the scene of the last re-plan
  /// s: the shrinking horizon ends the initial horizon after this, moved on
  /// when no lane change meets it.
  double deadline_set_at_ = 0.0;
  std::vector<EgoState> poses_;  ///< the plan's path, for collision_of
  expert::Iterate guess_;        ///< the last plan shifted to now
  std::vector<int> guess_modes_;
  expert::ExpertResult result_;  ///< of the last re-plan
  double last_plan_ms_ = 0.0;
  expert::PlanStatus last_status_ = expert::PlanStatus::Converged;
  expert::GapFrame plan_gap_;
};

/// The expert's config in closed loop (closed_loop.monotone_lateral).
[[nodiscard]] Config closed_loop_expert(Config config);

class MiqpPlanner final : public ClosedLoopPlanner {
 public:
  MiqpPlanner(Config config, std::shared_ptr<const expert::LaneChangeSolver> solver)
      : config_(closed_loop_expert(std::move(config))), expert_(config_, std::move(solver)) {}
  [[nodiscard]] std::string_view name() const override { return "miqp"; }
  [[nodiscard]] std::unique_ptr<PlannerSession> start(const Scenario& scene) const override;

 private:
  Config config_;
  expert::ExpertPlanner expert_;
};

}  // namespace lanechange::planner
