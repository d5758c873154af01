#pragma once
// The paper's MPC baseline after Sun et al. 2017 without DAgger
// (docs/baselines.md, "mpc"): a receding-horizon nonlinear program over the
// unicycle with the expert's horizon, weights and limits; the other cars are
// covered by circles kept apart from the ego's, with no lane logic. Solved by
// Ipopt, warm-started from the last solution shifted by the steps since.
#include <coin/IpIpoptApplication.hpp>
#include <memory>
#include <optional>
#include <string>
#include <string_view>

#include "baselines/mpc_problem.hpp"
#include "lanechange/planner/planner.hpp"

namespace lanechange::baselines {

/// How one solve ended. Only Solved yields a plan to follow.
enum class MpcStatus {
  Solved,          ///< Ipopt converged (or reached its acceptable level)
  Infeasible,      ///< Ipopt found it locally infeasible, or the terminal gap is too short
  IterationLimit,  ///< mpc.max_iterations ran out
  TimeLimit,       ///< mpc.time_limit_ms ran out
  NumericalError,  ///< anything else Ipopt reports
  GateMissed,      ///< the solution reaches circles left out of the rows (mpc.gate_distance)
};
[[nodiscard]] std::string_view to_string(MpcStatus status);

struct MpcResult {
  MpcStatus status = MpcStatus::NumericalError;
  MpcPlan plan;  ///< the last iterate (the solution when Solved)
  double objective = 0.0;
  int iterations = 0;
  double solve_ms = 0.0;
  std::string message;  ///< why it failed, in words; empty when Solved
};

/// The program for the scene as it is now (scene_now), starting from
/// `guess` (whose steps must match the scene's): the cars predicted by their
/// behavior from their current states, along the guess for IDM cars.
[[nodiscard]] MpcProblemData build_mpc_problem(const Scenario& scene, const Config& config,
                                               const MpcPlan& guess);

/// A lane change without regard to the cars: y follows a smoothstep to the
/// target-lane centre at the current speed. The start when there is no plan.
[[nodiscard]] MpcPlan cold_guess(const Scenario& scene);

/// `plan` shifted forward by `by` steps, cut or padded (the last node
/// coasting at its speed and heading) to `steps` steps, from `now`.
[[nodiscard]] MpcPlan shifted(const MpcPlan& plan, int by, int steps, double dt,
                              const EgoState& now);

/// One Ipopt application and one program, reused for every solve of a
/// session. Solves are serialised process-wide (MUMPS is not thread-safe).
class MpcSolver {
 public:
  explicit MpcSolver(const MpcSettings& settings);
  ~MpcSolver();
  MpcSolver(const MpcSolver&) = delete;
  MpcSolver& operator=(const MpcSolver&) = delete;
  /// Stops at `time_limit_ms` of wall time or `max_iterations` Ipopt iterations.
  [[nodiscard]] MpcResult solve(MpcProblemData data, MpcPlan guess, double time_limit_ms,
                                int max_iterations);

 private:
  MpcSettings settings_;
  Ipopt::SmartPtr<Ipopt::IpoptApplication> app_;
  Ipopt::SmartPtr<MpcNlp> nlp_;
};

/// Solves the program for `scene` from `guess`; where the solution reaches
/// circles the gate left out, once more around the solution.
[[nodiscard]] MpcResult solve_mpc(MpcSolver& solver, const Scenario& scene, const Config& config,
                                  const MpcPlan& guess);

/// Holds the process's one turn to run an mpc rollout (mpc.cpp says why).
/// Must be released on the thread that took it; a thread's nested turns
/// share the one it holds.
class MpcRolloutTurn {
 public:
  MpcRolloutTurn();
  ~MpcRolloutTurn();
  MpcRolloutTurn(const MpcRolloutTurn&) = delete;
  MpcRolloutTurn& operator=(const MpcRolloutTurn&) = delete;
  MpcRolloutTurn(MpcRolloutTurn&&) = delete;
  MpcRolloutTurn& operator=(MpcRolloutTurn&&) = delete;
};

class MpcSession final : public planner::PlannerSession {
 public:
  explicit MpcSession(const Config& config);
  [[nodiscard]] planner::Decision act(const planner::Observation& observation) override;
  [[nodiscard]] const MpcResult& last_result() const { return last_; }

 private:
  /// Solves from the observation; returns why it failed ("" on success).
  std::string replan(const planner::Observation& observation);
  /// The shifted plan while fresh, else the unfinished last solve, else a cold guess.
  [[nodiscard]] MpcPlan starting_point(int step, const Scenario& scene) const;

  MpcRolloutTurn turn_;  // first: taken before, released after everything else
  const Config& config_;
  planner::LaneKeeper keeper_;
  MpcSolver solver_;
  std::optional<MpcPlan> plan_;
  int plan_step_ = 0;
  MpcResult last_;
  int last_step_ = -1;  ///< the step of last_
};

class MpcPlanner final : public planner::ClosedLoopPlanner {
 public:
  explicit MpcPlanner(Config config) : config_(std::move(config)) {}
  [[nodiscard]] std::string_view name() const override { return "mpc"; }
  [[nodiscard]] std::unique_ptr<planner::PlannerSession> start(
      const Scenario& scene) const override;

 private:
  Config config_;
};

[[nodiscard]] std::shared_ptr<const planner::ClosedLoopPlanner> make_mpc_planner(
    const Config& config);

}  // namespace lanechange::baselines
