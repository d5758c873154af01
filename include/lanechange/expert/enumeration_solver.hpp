#pragma once
// Brute force over every 0/1 assignment of the binaries, each remaining convex QP
// solved by Ipopt. Exponential, so only for small instances: it exists to check the
// Bonmin reference (and any other solver) on problems where enumeration is cheap.
#include <string_view>

#include "lanechange/expert/miqp.hpp"

namespace lanechange::expert {

class EnumerationSolver final : public MiqpSolver {
 public:
  /// Larger problems are refused with InvalidProblem: 2^16 QPs already take about a minute.
  static constexpr int kMaxBinaries = 16;

  [[nodiscard]] std::string_view name() const override { return "enumeration"; }
  /// nodes counts the assignments examined, including those rejected without a QP
  /// solve. Absolute and relative gaps and integer_tolerance play no part.
  [[nodiscard]] MiqpResult solve(const MiqpProblem& problem,
                                 const MiqpSettings& settings) const override;
};

/// Solves the convex QP that remains when every binary j is fixed to round(values[j])
/// (values has one entry per variable; entries of continuous variables are ignored).
/// Status is Optimal, Infeasible, TimeLimit, NumericalError or InvalidProblem; nodes is 1.
/// Useful to polish a point from another solver so that its binaries are exact.
[[nodiscard]] MiqpResult solve_with_fixed_binaries(const MiqpProblem& problem,
                                                   const Eigen::VectorXd& values,
                                                   const MiqpSettings& settings);

}  // namespace lanechange::expert
