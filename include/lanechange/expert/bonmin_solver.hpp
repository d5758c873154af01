#pragma once
// The project's reference MIQP solver: COIN-OR Bonmin 1.8 (Cbc tree search, Ipopt
// for the continuous relaxations). Slow but trusted; the ground truth that our own
// solvers are checked against.
#include <mutex>
#include <string>
#include <string_view>

#include "lanechange/expert/miqp.hpp"

namespace lanechange::expert {

enum class BonminAlgorithm {
  /// Bonmin's B-BB: NLP branch-and-bound. The default, and the one to trust.
  BranchAndBound,
  /// Bonmin's B-OA: outer approximation with Cbc solving MILP masters. Often faster
  /// on small instances; exact for convex problems such as ours.
  OuterApproximation,
};

/// Bonmin's default algorithm (B-Hyb) and B-QG return wrong optima with a success
/// status on small convex MIQPs, so they are deliberately not offered.
class BonminSolver final : public MiqpSolver {
 public:
  explicit BonminSolver(BonminAlgorithm algorithm = BonminAlgorithm::BranchAndBound);

  [[nodiscard]] std::string_view name() const override;
  /// Thread-safe, but solves are serialised process-wide (see lock_coin_or_libraries);
  /// waiting for the lock counts against settings.time_limit_s. Bonmin itself measures
  /// part of the limit in process CPU seconds, so busy threads elsewhere shorten it.
  /// nodes counts Cbc's main tree; B-OA works in sub-MILPs and reports 0.
  /// InvalidProblem also when the Hessian is not positive semidefinite (check_convexity).
  [[nodiscard]] MiqpResult solve(const MiqpProblem& problem,
                                 const MiqpSettings& settings) const override;

 private:
  BonminAlgorithm algorithm_;
};

/// Empty when the objective is convex where a solver needs it, otherwise a sentence
/// saying it is not. Bonmin relaxes the binaries to [0, 1], so it needs the whole Hessian
/// positive semidefinite; with binaries_fixed only the block of the continuous variables
/// is checked, which is all that enumeration needs. Ipopt would otherwise return a local
/// optimum, and the solvers would call it Optimal. Tested by a sparse Cholesky
/// factorisation of H + 1e-8 max|H_ij| I.
[[nodiscard]] std::string check_convexity(const MiqpProblem& problem, bool binaries_fixed);

/// Ipopt 3.11 factorises with MUMPS, which is not thread-safe, and Bonmin 1.8 keeps
/// process-wide state (an abort flag, a SIGINT handler). Every call into Ipopt or
/// Bonmin in this process must therefore hold this lock. The solvers in this folder
/// take it themselves; take it too if you call Ipopt or Bonmin directly.
[[nodiscard]] std::unique_lock<std::mutex> lock_coin_or_libraries();

}  // namespace lanechange::expert
