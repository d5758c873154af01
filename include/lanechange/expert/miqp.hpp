#pragma once
// A general mixed-integer QP in the form every expert back-end takes:
//
//   minimize    0.5 x' H x + g' x + constant
//   subject to  row_lower <= A x <= row_upper
//               col_lower <=  x  <= col_upper
//               x_j in {0, 1} for every j with kind Binary
//
// H is symmetric positive semidefinite (the expert's problems are convex once
// the binaries are fixed). Infinite bounds are written as +-infinity.
#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <limits>
#include <string>
#include <string_view>
#include <vector>

namespace lanechange::expert {

inline constexpr double kInfinity = std::numeric_limits<double>::infinity();

enum class VariableKind { Continuous, Binary };

struct MiqpProblem {
  Eigen::SparseMatrix<double> hessian;  ///< n x n, full symmetric (both triangles stored)
  Eigen::VectorXd gradient;             ///< n
  double constant = 0.0;
  Eigen::SparseMatrix<double> constraints;  ///< m x n
  Eigen::VectorXd row_lower;                ///< m
  Eigen::VectorXd row_upper;                ///< m
  Eigen::VectorXd col_lower;                ///< n
  Eigen::VectorXd col_upper;                ///< n
  std::vector<VariableKind> kinds;          ///< n

  [[nodiscard]] int num_variables() const { return static_cast<int>(gradient.size()); }
  [[nodiscard]] int num_rows() const { return static_cast<int>(row_lower.size()); }
  [[nodiscard]] int num_binaries() const;
  [[nodiscard]] double objective(const Eigen::VectorXd& x) const;
  /// Largest violation of rows, bounds and integrality at x (0 when feasible).
  [[nodiscard]] double max_violation(const Eigen::VectorXd& x) const;
  /// Empty when the sizes agree and every number is finite (bounds may be infinite);
  /// otherwise a sentence that says what is wrong.
  [[nodiscard]] std::string check() const;
};

enum class MiqpStatus {
  Optimal,     ///< proven optimal within the gap tolerances
  Infeasible,  ///< proven infeasible
  TimeLimit,   ///< stopped by the time limit; x is the best point found, if any
  NodeLimit,   ///< stopped by the node limit; x is the best point found, if any
  /// Stopped by MiqpSettings::qp_iteration_limit; x is the best point found, if any.
  WorkLimit,
  NumericalError,  ///< the back-end failed; message says why
  InvalidProblem,  ///< check() failed; nothing was solved
  /// Stopped once its lower bound passed MiqpSettings::objective_cutoff; the
  /// objective is that bound (no point is given).
  Cutoff,
};

[[nodiscard]] std::string_view to_string(MiqpStatus status);

struct MiqpSettings {
  double time_limit_s = 600.0;
  long node_limit = 10'000'000;
  /// Interior-point iterations of the node QPs over the whole solve: a
  /// budget of work, so that where it binds the answer does not depend on
  /// the machine's load. Honoured by our solvers (fast and fixed-mode);
  /// Bonmin ignores it.
  long qp_iteration_limit = std::numeric_limits<long>::max();
  double absolute_gap = 1e-9;
  double relative_gap = 1e-9;
  double integer_tolerance = 1e-6;
  double feasibility_tolerance = 1e-8;  ///< of the continuous relaxations
  /// A solve may stop (status Cutoff) once it proves no point is cheaper
  /// than this: a caller who holds a better answer already. Honoured by our
  /// solvers (fast and fixed-mode); Bonmin ignores it.
  double objective_cutoff = kInfinity;
  bool verbose = false;
};

struct MiqpResult {
  MiqpStatus status = MiqpStatus::NumericalError;
  Eigen::VectorXd x;               ///< best point found (empty when none)
  double objective = kInfinity;    ///< objective at x
  double best_bound = -kInfinity;  ///< proven lower bound
  long nodes = 0;
  double solve_ms = 0.0;
  std::string message;
  [[nodiscard]] bool has_solution() const { return x.size() > 0; }
};

/// How far a best point's objective may lie above the optimum, relative to
/// the objective (at least 1, as the cross-check compares objectives): 0
/// where they meet (an Optimal exact search; Infeasible, both +infinity),
/// +infinity where either is unknown, below 0 only by rounding.
[[nodiscard]] double relative_gap(double objective, double best_bound);

/// A back-end. Implementations are stateless across calls, so one instance may
/// solve many problems on many threads at once.
class MiqpSolver {
 public:
  virtual ~MiqpSolver() = default;
  [[nodiscard]] virtual std::string_view name() const = 0;
  [[nodiscard]] virtual MiqpResult solve(const MiqpProblem& problem,
                                         const MiqpSettings& settings) const = 0;
};

}  // namespace lanechange::expert
