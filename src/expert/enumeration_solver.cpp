#include "lanechange/expert/enumeration_solver.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <coin/ClpSimplex.hpp>
#include <coin/IpIpoptApplication.hpp>
#include <coin/IpTNLP.hpp>
#include <cstdint>
#include <exception>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "expert/coin_glue.hpp"
#include "lanechange/expert/bonmin_solver.hpp"

namespace lanechange::expert {
namespace {

using Clock = std::chrono::steady_clock;
using coin::milliseconds_since;
using coin::set_option;
using coin::SparseTriplets;
using coin::triplets_of;
using Ipopt::Index;
using Ipopt::Number;

// The QP over the variables left free once the binaries (and any continuous variable
// with equal bounds) are fixed. Eliminating the fixed variables, rather than fixing
// them through Ipopt's bounds, keeps rows such as "b1 + b2 == 1" from turning into
// constant equality rows that Ipopt reports as too few degrees of freedom.
struct ReducedQp {
  std::vector<Eigen::Index> free_columns;  ///< reduced index -> original index
  Eigen::VectorXd fixed_point;             ///< original size; zero at free columns
  Eigen::SparseMatrix<double> hessian;     ///< full symmetric, free x free
  Eigen::VectorXd gradient;
  Eigen::SparseMatrix<double> constraints;
  Eigen::VectorXd row_lower;
  Eigen::VectorXd row_upper;
  Eigen::VectorXd col_lower;
  Eigen::VectorXd col_upper;

  [[nodiscard]] Eigen::VectorXd expand(const Eigen::VectorXd& free_values) const {
    Eigen::VectorXd x = fixed_point;
    for (std::size_t k = 0; k < free_columns.size(); ++k) {
      x[free_columns[k]] = free_values[static_cast<Eigen::Index>(k)];
    }
    return x;
  }
};

bool outside(double value, double lower, double upper, double tolerance) {
  return value < lower - tolerance || value > upper + tolerance;
}

// Returns the reduced-problem index of each column (-1 when fixed), or nullopt when a
// binary's value is outside its bounds.
std::optional<std::vector<int>> fix_columns(const MiqpProblem& problem,
                                            const Eigen::VectorXd& values, double tolerance,
                                            ReducedQp& qp) {
  const Eigen::Index n = problem.num_variables();
  std::vector<int> reduced_index(static_cast<std::size_t>(n), -1);
  qp.fixed_point = Eigen::VectorXd::Zero(n);
  for (Eigen::Index j = 0; j < n; ++j) {
    const double lower = problem.col_lower[j];
    const double upper = problem.col_upper[j];
    if (problem.kinds[static_cast<std::size_t>(j)] == VariableKind::Binary) {
      const double value = values[j] >= 0.5 ? 1.0 : 0.0;
      if (outside(value, lower, upper, tolerance)) return std::nullopt;
      qp.fixed_point[j] = value;
    } else if (lower == upper) {
      qp.fixed_point[j] = lower;
    } else {
      reduced_index[static_cast<std::size_t>(j)] = static_cast<int>(qp.free_columns.size());
      qp.free_columns.push_back(j);
    }
  }
  const auto f = static_cast<Eigen::Index>(qp.free_columns.size());
  qp.col_lower.resize(f);
  qp.col_upper.resize(f);
  for (Eigen::Index k = 0; k < f; ++k) {
    qp.col_lower[k] = problem.col_lower[qp.free_columns[static_cast<std::size_t>(k)]];
    qp.col_upper[k] = problem.col_upper[qp.free_columns[static_cast<std::size_t>(k)]];
  }
  return reduced_index;
}

void reduce_objective(const MiqpProblem& problem, const std::vector<int>& reduced_index,
                      ReducedQp& qp) {
  const Eigen::VectorXd fixed_curvature = problem.hessian * qp.fixed_point;
  const auto f = static_cast<Eigen::Index>(qp.free_columns.size());
  qp.gradient.resize(f);
  for (Eigen::Index k = 0; k < f; ++k) {
    const Eigen::Index j = qp.free_columns[static_cast<std::size_t>(k)];
    qp.gradient[k] = problem.gradient[j] + fixed_curvature[j];
  }
  std::vector<Eigen::Triplet<double>> entries;
  const SparseTriplets all = triplets_of(problem.hessian, false);
  for (Index e = 0; e < all.size(); ++e) {
    const int row = reduced_index[static_cast<std::size_t>(all.rows[e])];
    const int col = reduced_index[static_cast<std::size_t>(all.cols[e])];
    if (row >= 0 && col >= 0) entries.emplace_back(row, col, all.values[e]);
  }
  qp.hessian.resize(f, f);
  qp.hessian.setFromTriplets(entries.begin(), entries.end());
}

struct RowRange {
  int free_entries = 0;
  double min_activity = 0.0;  ///< over the free columns' bounds
  double max_activity = 0.0;
};

// Keeps the rows that still involve a free column, shifted by the fixed part. Returns
// false when a row is violated regardless of the free columns: then no QP is needed.
bool reduce_rows(const MiqpProblem& problem, const std::vector<int>& reduced_index,
                 double tolerance, ReducedQp& qp) {
  const Eigen::VectorXd fixed_activity = problem.constraints * qp.fixed_point;
  std::vector<RowRange> ranges(static_cast<std::size_t>(problem.num_rows()));
  std::vector<Eigen::Triplet<double>> free_entries;
  const SparseTriplets all = triplets_of(problem.constraints, false);
  for (Index e = 0; e < all.size(); ++e) {
    const int col = reduced_index[static_cast<std::size_t>(all.cols[e])];
    const double a = all.values[e];
    if (col < 0 || a == 0.0) continue;
    RowRange& range = ranges[static_cast<std::size_t>(all.rows[e])];
    ++range.free_entries;
    range.min_activity += a * (a > 0 ? qp.col_lower[col] : qp.col_upper[col]);
    range.max_activity += a * (a > 0 ? qp.col_upper[col] : qp.col_lower[col]);
    free_entries.emplace_back(all.rows[e], col, a);
  }
  std::vector<int> kept_index(ranges.size(), -1);
  std::vector<double> lower;
  std::vector<double> upper;
  for (std::size_t i = 0; i < ranges.size(); ++i) {
    const auto row = static_cast<Eigen::Index>(i);
    const double row_lower = problem.row_lower[row] - fixed_activity[row];
    const double row_upper = problem.row_upper[row] - fixed_activity[row];
    if (ranges[i].min_activity > row_upper + tolerance ||
        ranges[i].max_activity < row_lower - tolerance) {
      return false;
    }
    if (ranges[i].free_entries == 0) continue;
    kept_index[i] = static_cast<int>(lower.size());
    lower.push_back(row_lower);
    upper.push_back(row_upper);
  }
  for (auto& entry : free_entries) {
    entry = {kept_index[static_cast<std::size_t>(entry.row())], entry.col(), entry.value()};
  }
  qp.constraints.resize(static_cast<Eigen::Index>(lower.size()),
                        static_cast<Eigen::Index>(qp.free_columns.size()));
  qp.constraints.setFromTriplets(free_entries.begin(), free_entries.end());
  qp.row_lower = Eigen::Map<const Eigen::VectorXd>(lower.data(), std::ssize(lower));
  qp.row_upper = Eigen::Map<const Eigen::VectorXd>(upper.data(), std::ssize(upper));
  return true;
}

/// nullopt when the fixed values alone already make the problem infeasible.
std::optional<ReducedQp> reduce(const MiqpProblem& problem, const Eigen::VectorXd& values,
                                double tolerance) {
  ReducedQp qp;
  const auto reduced_index = fix_columns(problem, values, tolerance, qp);
  if (!reduced_index) return std::nullopt;
  reduce_objective(problem, *reduced_index, qp);
  if (!reduce_rows(problem, *reduced_index, tolerance, qp)) return std::nullopt;
  return qp;
}

// Most assignments of a big-M model are infeasible, and Ipopt spends ~10 ms in its
// restoration phase proving each one; Clp's dual simplex settles the linear rows in a
// fraction of that. Ipopt then sees only assignments whose rows Clp can satisfy.
bool linear_rows_feasible(const ReducedQp& qp, double tolerance) {
  static_assert(std::is_same_v<CoinBigIndex, Eigen::SparseMatrix<double>::StorageIndex>);
  if (qp.row_lower.size() == 0) return true;
  Eigen::SparseMatrix<double> matrix = qp.constraints;
  matrix.makeCompressed();
  const Eigen::VectorXd no_objective = Eigen::VectorXd::Zero(matrix.cols());
  ClpSimplex lp;
  lp.setLogLevel(0);
  lp.loadProblem(static_cast<int>(matrix.cols()), static_cast<int>(matrix.rows()),
                 matrix.outerIndexPtr(), matrix.innerIndexPtr(), matrix.valuePtr(),
                 qp.col_lower.data(), qp.col_upper.data(), no_objective.data(), qp.row_lower.data(),
                 qp.row_upper.data());
  lp.setPrimalTolerance(std::max(tolerance, 1e-10));
  lp.dual();
  return !lp.isProvenPrimalInfeasible();
}

class ReducedQpTnlp final : public coin::LinearRowsNlp<Ipopt::TNLP> {
 public:
  explicit ReducedQpTnlp(const ReducedQp& qp)
      : LinearRowsNlp(qp.hessian, qp.constraints), qp_(qp) {}

  [[nodiscard]] const Eigen::VectorXd& solution() const { return solution_; }

  bool eval_f(Index n, const Number* x, bool, Number& obj_value) override {
    const Eigen::Map<const Eigen::VectorXd> point(x, n);
    obj_value = 0.5 * point.dot(qp_.hessian * point) + qp_.gradient.dot(point);
    return true;
  }

  void finalize_solution(Ipopt::SolverReturn, Index n, const Number* x, const Number*,
                         const Number*, Index, const Number*, const Number*, Number,
                         const Ipopt::IpoptData*, Ipopt::IpoptCalculatedQuantities*) override {
    solution_ = Eigen::Map<const Eigen::VectorXd>(x, n);
  }

 private:
  [[nodiscard]] coin::LinearRowsQp qp() const override {
    return {qp_.hessian,   qp_.gradient,  qp_.constraints, qp_.col_lower,
            qp_.col_upper, qp_.row_lower, qp_.row_upper};
  }

  const ReducedQp& qp_;
  Eigen::VectorXd solution_;
};

// The caller holds lock_coin_or_libraries().
Ipopt::SmartPtr<Ipopt::IpoptApplication> make_ipopt(const MiqpSettings& settings) {
  Ipopt::SmartPtr<Ipopt::IpoptApplication> app =
      new Ipopt::IpoptApplication(/*create_console_out=*/settings.verbose);
  Ipopt::OptionsList& options = *app->Options();
  set_option(options, "print_level", settings.verbose ? 5 : 0);
  set_option(options, "sb", "yes");  // no banner
  // The reference must be accurate: objectives to ~1e-10 relative, and no bound
  // relaxation, which by default leaves violations of ~1e-8 * |bound|.
  set_option(options, "tol", 1e-10);
  set_option(options, "constr_viol_tol", settings.feasibility_tolerance);
  set_option(options, "bound_relax_factor", 0.0);
  set_option(options, "honor_original_bounds", "yes");
  set_option(options, "mu_strategy", "adaptive");
  set_option(options, "hessian_constant", "yes");
  set_option(options, "jac_c_constant", "yes");
  set_option(options, "jac_d_constant", "yes");
  if (app->Initialize("") != Ipopt::Solve_Succeeded) {
    throw std::runtime_error("Ipopt failed to initialise");
  }
  return app;
}

// Owns an IpoptApplication. Creating and destroying one (which frees its MUMPS
// instance) happens under the library lock, like every solve.
class IpoptSession {
 public:
  explicit IpoptSession(const MiqpSettings& settings) {
    const auto lock = lock_coin_or_libraries();
    app_ = make_ipopt(settings);
  }
  ~IpoptSession() {
    const auto lock = lock_coin_or_libraries();
    app_ = nullptr;
  }
  IpoptSession(const IpoptSession&) = delete;
  IpoptSession& operator=(const IpoptSession&) = delete;

  Ipopt::ApplicationReturnStatus optimize(const Ipopt::SmartPtr<Ipopt::TNLP>& tnlp,
                                          double seconds_left) {
    const auto lock = lock_coin_or_libraries();
    set_option(*app_->Options(), "max_cpu_time", std::max(seconds_left, 1e-3));
    return app_->OptimizeTNLP(tnlp);
  }

 private:
  Ipopt::SmartPtr<Ipopt::IpoptApplication> app_;
};

struct QpOutcome {
  MiqpStatus status = MiqpStatus::NumericalError;
  Eigen::VectorXd x;
  double objective = kInfinity;
  std::string message;
};

MiqpStatus status_of(Ipopt::ApplicationReturnStatus status) {
  switch (status) {
    case Ipopt::Solve_Succeeded:
    case Ipopt::Solved_To_Acceptable_Level: return MiqpStatus::Optimal;
    case Ipopt::Infeasible_Problem_Detected: return MiqpStatus::Infeasible;
    case Ipopt::Maximum_CpuTime_Exceeded: return MiqpStatus::TimeLimit;
    default: return MiqpStatus::NumericalError;
  }
}

std::string describe_failure(Ipopt::ApplicationReturnStatus status) {
  switch (status) {
    case Ipopt::Diverging_Iterates: return "Ipopt's iterates diverged (is the QP unbounded?)";
    case Ipopt::Maximum_Iterations_Exceeded: return "Ipopt reached its iteration limit";
    case Ipopt::Restoration_Failed: return "Ipopt's restoration phase failed";
    default: return "Ipopt returned status " + std::to_string(static_cast<int>(status));
  }
}

QpOutcome solve_reduced(IpoptSession& ipopt, const MiqpProblem& problem, const ReducedQp& qp,
                        double seconds_left) {
  QpOutcome outcome;
  if (qp.free_columns.empty()) {  // nothing left to optimise; reduce() checked every row
    outcome.status = MiqpStatus::Optimal;
    outcome.x = qp.fixed_point;
    outcome.objective = problem.objective(outcome.x);
    return outcome;
  }
  Ipopt::SmartPtr<ReducedQpTnlp> tnlp = new ReducedQpTnlp(qp);
  const Ipopt::ApplicationReturnStatus status = ipopt.optimize(GetRawPtr(tnlp), seconds_left);
  outcome.status = status_of(status);
  if (outcome.status == MiqpStatus::Optimal) {
    outcome.x = qp.expand(tnlp->solution());
    outcome.objective = problem.objective(outcome.x);
  } else if (outcome.status == MiqpStatus::NumericalError) {
    outcome.message = describe_failure(status);
  }
  return outcome;
}

QpOutcome solve_fixed(IpoptSession& ipopt, const MiqpProblem& problem,
                      const Eigen::VectorXd& values, const MiqpSettings& settings,
                      double seconds_left) {
  const std::optional<ReducedQp> qp = reduce(problem, values, settings.feasibility_tolerance);
  if (!qp || !linear_rows_feasible(*qp, settings.feasibility_tolerance)) {
    QpOutcome infeasible;
    infeasible.status = MiqpStatus::Infeasible;
    return infeasible;
  }
  QpOutcome outcome = solve_reduced(ipopt, problem, *qp, seconds_left);
  // Skipping such an assignment silently could hide the optimum, so it counts as a failure.
  if (outcome.status == MiqpStatus::Infeasible) {
    outcome.status = MiqpStatus::NumericalError;
    outcome.message = "Ipopt reports infeasible a QP whose rows Clp can satisfy";
  }
  return outcome;
}

std::vector<Eigen::Index> binary_columns(const MiqpProblem& problem) {
  std::vector<Eigen::Index> columns;
  for (std::size_t j = 0; j < problem.kinds.size(); ++j) {
    if (problem.kinds[j] == VariableKind::Binary) columns.push_back(static_cast<Eigen::Index>(j));
  }
  return columns;
}

// Tracks the best assignment and why the enumeration may not be conclusive.
class Enumeration {
 public:
  Enumeration(const MiqpProblem& problem, const MiqpSettings& settings)
      : problem_(problem), settings_(settings), ipopt_(settings) {}

  void run(MiqpResult& result) {
    const std::vector<Eigen::Index> binaries = binary_columns(problem_);
    const std::uint64_t assignments = std::uint64_t{1} << binaries.size();
    Eigen::VectorXd values = Eigen::VectorXd::Zero(problem_.num_variables());
    for (std::uint64_t mask = 0; mask < assignments; ++mask) {
      if (const auto limit = limit_reached(result.nodes)) {
        stopped_by_ = limit;
        break;
      }
      for (std::size_t b = 0; b < binaries.size(); ++b) {
        values[binaries[b]] = static_cast<double>((mask >> b) & 1U);
      }
      ++result.nodes;
      record(solve_fixed(ipopt_, problem_, values, settings_, seconds_left()));
    }
    fill(result);
  }

 private:
  double seconds_left() const { return settings_.time_limit_s - milliseconds_since(start_) / 1e3; }

  std::optional<MiqpStatus> limit_reached(long nodes) const {
    if (seconds_left() <= 0.0) return MiqpStatus::TimeLimit;
    if (nodes >= settings_.node_limit) return MiqpStatus::NodeLimit;
    return std::nullopt;
  }

  void record(QpOutcome outcome) {
    if (outcome.status == MiqpStatus::TimeLimit) stopped_by_ = MiqpStatus::TimeLimit;
    if (outcome.status == MiqpStatus::NumericalError) {
      if (failures_++ == 0) first_failure_ = outcome.message;
    }
    if (outcome.status == MiqpStatus::Optimal && outcome.objective < best_.objective) {
      best_ = std::move(outcome);
    }
  }

  void fill(MiqpResult& result) const {
    result.x = best_.x;
    result.objective = best_.objective;
    std::ostringstream message;
    if (stopped_by_) {
      result.status = *stopped_by_;
      message << "stopped after " << result.nodes << " assignments";
    } else if (failures_ > 0) {
      result.status = MiqpStatus::NumericalError;
      message << failures_ << " of " << result.nodes
              << " QPs failed, so the best point is not proven optimal; first: " << first_failure_;
    } else if (best_.status == MiqpStatus::Optimal) {
      result.status = MiqpStatus::Optimal;
      result.best_bound = best_.objective;
    } else {
      result.status = MiqpStatus::Infeasible;
      result.best_bound = kInfinity;
    }
    result.message = message.str();
  }

  const MiqpProblem& problem_;
  const MiqpSettings& settings_;
  Clock::time_point start_ = Clock::now();
  IpoptSession ipopt_;
  QpOutcome best_;
  std::optional<MiqpStatus> stopped_by_;
  int failures_ = 0;
  std::string first_failure_;
};

MiqpResult invalid_problem(std::string message) {
  MiqpResult result;
  result.status = MiqpStatus::InvalidProblem;
  result.message = std::move(message);
  return result;
}

std::optional<MiqpResult> refuse_invalid(const MiqpProblem& problem) {
  if (std::string problem_error = problem.check(); !problem_error.empty()) {
    return invalid_problem(std::move(problem_error));
  }
  return std::nullopt;
}

std::string describe_current_exception() {
  try {
    throw;
  } catch (const Ipopt::IpoptException& error) {
    return "Ipopt exception: " + error.Message();
  } catch (const std::exception& error) {
    return error.what();
  } catch (...) {
    return "unknown exception";
  }
}

}  // namespace

MiqpResult EnumerationSolver::solve(const MiqpProblem& problem,
                                    const MiqpSettings& settings) const {
  const Clock::time_point start = Clock::now();
  if (auto refused = refuse_invalid(problem)) return *refused;
  if (std::string nonconvex = check_convexity(problem, /*binaries_fixed=*/true);
      !nonconvex.empty()) {
    return invalid_problem(std::move(nonconvex));
  }
  if (problem.num_binaries() > kMaxBinaries) {
    return invalid_problem(std::to_string(problem.num_binaries()) +
                           " binaries; enumeration takes at most " + std::to_string(kMaxBinaries));
  }
  MiqpResult result;
  try {
    Enumeration(problem, settings).run(result);
  } catch (...) {
    result.status = MiqpStatus::NumericalError;
    result.message = describe_current_exception();
  }
  result.solve_ms = milliseconds_since(start);
  return result;
}

MiqpResult solve_with_fixed_binaries(const MiqpProblem& problem, const Eigen::VectorXd& values,
                                     const MiqpSettings& settings) {
  const Clock::time_point start = Clock::now();
  if (auto refused = refuse_invalid(problem)) return *refused;
  if (values.size() != problem.num_variables()) {
    return invalid_problem("values has " + std::to_string(values.size()) + " entries, expected " +
                           std::to_string(problem.num_variables()));
  }
  MiqpResult result;
  result.nodes = 1;
  try {
    IpoptSession ipopt(settings);
    QpOutcome outcome = solve_fixed(ipopt, problem, values, settings, settings.time_limit_s);
    result.status = outcome.status;
    result.x = std::move(outcome.x);
    result.objective = outcome.objective;
    result.message = std::move(outcome.message);
    if (result.status == MiqpStatus::Optimal) result.best_bound = result.objective;
    if (result.status == MiqpStatus::Infeasible) result.best_bound = kInfinity;
  } catch (...) {
    result.status = MiqpStatus::NumericalError;
    result.message = describe_current_exception();
  }
  result.solve_ms = milliseconds_since(start);
  return result;
}

}  // namespace lanechange::expert
