#include "lanechange/expert/miqp.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

namespace lanechange::expert {
namespace {

bool all_finite(const Eigen::VectorXd& values) { return values.allFinite(); }

bool all_finite(const Eigen::SparseMatrix<double>& matrix) {
  for (int outer = 0; outer < matrix.outerSize(); ++outer) {
    for (Eigen::SparseMatrix<double>::InnerIterator it(matrix, outer); it; ++it) {
      if (!std::isfinite(it.value())) return false;
    }
  }
  return true;
}

double max_abs(const Eigen::SparseMatrix<double>& matrix) {
  double largest = 0.0;
  for (int outer = 0; outer < matrix.outerSize(); ++outer) {
    for (Eigen::SparseMatrix<double>::InnerIterator it(matrix, outer); it; ++it) {
      largest = std::max(largest, std::abs(it.value()));
    }
  }
  return largest;
}

// Assumes every entry is finite; call after all_finite().
bool is_symmetric(const Eigen::SparseMatrix<double>& matrix) {
  const Eigen::SparseMatrix<double> transpose = matrix.transpose();
  const Eigen::SparseMatrix<double> asymmetry = matrix - transpose;
  // Round-off from forming H as B'B or (M + M')/2 stays far below this.
  const double tolerance = 1e-12 * std::max(1.0, max_abs(matrix));
  return max_abs(asymmetry) <= tolerance;
}

// A lower bound of +inf or an upper bound of -inf is almost surely a sign
// mix-up in the caller, so it is reported rather than treated as infeasible.
std::string check_bounds(const Eigen::VectorXd& lower, const Eigen::VectorXd& upper,
                         std::string_view what) {
  for (Eigen::Index i = 0; i < lower.size(); ++i) {
    std::ostringstream message;
    if (std::isnan(lower[i]) || std::isnan(upper[i])) {
      message << what << ' ' << i << " has a NaN bound";
    } else if (lower[i] == kInfinity) {
      message << what << ' ' << i << " has lower bound +inf";
    } else if (upper[i] == -kInfinity) {
      message << what << ' ' << i << " has upper bound -inf";
    }
    if (!message.str().empty()) return message.str();
  }
  return {};
}

std::string check_sizes(const MiqpProblem& problem) {
  const Eigen::Index n = problem.gradient.size();
  const Eigen::Index m = problem.row_lower.size();
  std::ostringstream message;
  if (problem.hessian.rows() != n || problem.hessian.cols() != n) {
    message << "hessian is " << problem.hessian.rows() << 'x' << problem.hessian.cols()
            << " but there are " << n << " variables";
  } else if (problem.constraints.rows() != m || problem.constraints.cols() != n) {
    message << "constraints is " << problem.constraints.rows() << 'x' << problem.constraints.cols()
            << " but expected " << m << 'x' << n;
  } else if (problem.row_upper.size() != m) {
    message << "row_upper has " << problem.row_upper.size() << " entries, row_lower " << m;
  } else if (problem.col_lower.size() != n || problem.col_upper.size() != n) {
    message << "col_lower/col_upper have " << problem.col_lower.size() << '/'
            << problem.col_upper.size() << " entries but there are " << n << " variables";
  } else if (static_cast<Eigen::Index>(problem.kinds.size()) != n) {
    message << "kinds has " << problem.kinds.size() << " entries but there are " << n
            << " variables";
  }
  return message.str();
}

std::string check_values(const MiqpProblem& problem) {
  if (!std::isfinite(problem.constant)) return "constant is not finite";
  if (!all_finite(problem.gradient)) return "gradient has a non-finite entry";
  if (!all_finite(problem.hessian)) return "hessian has a non-finite entry";
  if (!all_finite(problem.constraints)) return "constraints has a non-finite entry";
  if (!is_symmetric(problem.hessian)) return "hessian is not symmetric";
  if (auto message = check_bounds(problem.row_lower, problem.row_upper, "row"); !message.empty()) {
    return message;
  }
  return check_bounds(problem.col_lower, problem.col_upper, "column");
}

// Distance from value to the interval [lower, upper]; infinite bounds never bind.
double interval_violation(double value, double lower, double upper) {
  return std::max({lower - value, value - upper, 0.0});
}

}  // namespace

int MiqpProblem::num_binaries() const {
  return static_cast<int>(std::count(kinds.begin(), kinds.end(), VariableKind::Binary));
}

double MiqpProblem::objective(const Eigen::VectorXd& x) const {
  if (x.size() != gradient.size() || hessian.cols() != x.size()) {
    return std::numeric_limits<double>::quiet_NaN();
  }
  return 0.5 * x.dot(hessian * x) + gradient.dot(x) + constant;
}

double MiqpProblem::max_violation(const Eigen::VectorXd& x) const {
  const Eigen::Index n = num_variables();
  if (x.size() != n || !x.allFinite() || !check_sizes(*this).empty()) return kInfinity;
  double violation = 0.0;
  const Eigen::VectorXd row_activity = constraints * x;
  for (Eigen::Index i = 0; i < row_activity.size(); ++i) {
    violation =
        std::max(violation, interval_violation(row_activity[i], row_lower[i], row_upper[i]));
  }
  for (Eigen::Index j = 0; j < n; ++j) {
    violation = std::max(violation, interval_violation(x[j], col_lower[j], col_upper[j]));
    if (kinds[static_cast<std::size_t>(j)] == VariableKind::Binary) {
      violation = std::max(violation, std::min(std::abs(x[j]), std::abs(x[j] - 1.0)));
    }
  }
  return violation;
}

std::string MiqpProblem::check() const {
  if (auto message = check_sizes(*this); !message.empty()) return message;
  return check_values(*this);
}

double relative_gap(double objective, double best_bound) {
  if (objective == best_bound) return 0.0;
  if (!std::isfinite(objective) || !std::isfinite(best_bound)) return kInfinity;
  return (objective - best_bound) / std::max(1.0, std::abs(objective));
}

std::string_view to_string(MiqpStatus status) {
  switch (status) {
    case MiqpStatus::Optimal: return "Optimal";
    case MiqpStatus::Infeasible: return "Infeasible";
    case MiqpStatus::TimeLimit: return "TimeLimit";
    case MiqpStatus::NodeLimit: return "NodeLimit";
    case MiqpStatus::WorkLimit: return "WorkLimit";
    case MiqpStatus::NumericalError: return "NumericalError";
    case MiqpStatus::InvalidProblem: return "InvalidProblem";
    case MiqpStatus::Cutoff: return "Cutoff";
  }
  return "Unknown";
}

}  // namespace lanechange::expert
