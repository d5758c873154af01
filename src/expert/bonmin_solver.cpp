#include "lanechange/expert/bonmin_solver.hpp"

#include <signal.h>

#include <Eigen/SparseCholesky>
#include <algorithm>
#include <chrono>
#include <climits>
#include <cmath>
#include <coin/BonBonminSetup.hpp>
#include <coin/BonCbc.hpp>
#include <coin/BonTMINLP.hpp>
#include <coin/BonTNLPSolver.hpp>
#include <coin/CoinError.hpp>
#include <coin/IpException.hpp>
#include <csignal>
#include <exception>
#include <memory>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "expert/coin_glue.hpp"

// Defined in libbonmin (BonCbc.cpp). Bonmin's SIGINT handler sets it, and while it is
// set every later NLP is reported infeasible, so each solve clears it first.
extern bool BonminAbortAll;  // NOLINT(readability-identifier-naming)

namespace lanechange::expert {
namespace {

using Clock = std::chrono::steady_clock;
using coin::milliseconds_since;
using coin::set_option;
using Ipopt::Index;
using Ipopt::Number;

struct ColumnBounds {
  Eigen::VectorXd lower;
  Eigen::VectorXd upper;
};

// Bonmin requires binaries' bounds inside [0, 1], and Ipopt rejects crossed bounds as
// an invalid problem, so bounds are tightened here and crossing means infeasible.
std::optional<ColumnBounds> effective_column_bounds(const MiqpProblem& problem,
                                                    double integer_tolerance) {
  ColumnBounds bounds{problem.col_lower, problem.col_upper};
  for (Eigen::Index j = 0; j < problem.num_variables(); ++j) {
    if (problem.kinds[static_cast<std::size_t>(j)] == VariableKind::Binary) {
      bounds.lower[j] = std::max(0.0, std::ceil(bounds.lower[j] - integer_tolerance));
      bounds.upper[j] = std::min(1.0, std::floor(bounds.upper[j] + integer_tolerance));
    }
    if (bounds.lower[j] > bounds.upper[j]) return std::nullopt;
  }
  return bounds;
}

// Bonmin frees an invalid pointer when it is handed a problem without variables.
void solve_without_variables(const MiqpProblem& problem, MiqpResult& result) {
  const bool feasible =
      (problem.row_lower.array() <= 0.0).all() && (problem.row_upper.array() >= 0.0).all();
  result.status = feasible ? MiqpStatus::Optimal : MiqpStatus::Infeasible;
  result.objective = feasible ? problem.constant : kInfinity;
  result.best_bound = result.objective;
}

bool rows_cross(const MiqpProblem& problem) {
  return (problem.row_lower.array() > problem.row_upper.array()).any();
}

class MiqpTminlp final : public coin::LinearRowsNlp<Bonmin::TMINLP> {
 public:
  MiqpTminlp(const MiqpProblem& problem, ColumnBounds bounds)
      : LinearRowsNlp(problem.hessian, problem.constraints),
        problem_(problem),
        bounds_(std::move(bounds)),
        rows_(problem.constraints) {}

  [[nodiscard]] SolverReturn final_status() const { return final_status_; }

  bool get_variables_types(Index n, VariableType* var_types) override {
    for (Index j = 0; j < n; ++j) {
      const bool binary = problem_.kinds[static_cast<std::size_t>(j)] == VariableKind::Binary;
      var_types[j] = binary ? BINARY : CONTINUOUS;
    }
    return true;
  }

  bool get_variables_linearity(Index n, Ipopt::TNLP::LinearityType* var_types) override {
    std::fill_n(var_types, n, Ipopt::TNLP::LINEAR);
    for (Index e = 0; e < hessian_lower().size(); ++e) {
      if (hessian_lower().values[e] == 0.0) continue;
      var_types[hessian_lower().rows[e]] = Ipopt::TNLP::NON_LINEAR;
      var_types[hessian_lower().cols[e]] = Ipopt::TNLP::NON_LINEAR;
    }
    return true;
  }

  bool get_constraints_linearity(Index m, Ipopt::TNLP::LinearityType* const_types) override {
    std::fill_n(const_types, m, Ipopt::TNLP::LINEAR);
    return true;
  }

  bool eval_f(Index n, const Number* x, bool, Number& obj_value) override {
    obj_value = problem_.objective(Eigen::Map<const Eigen::VectorXd>(x, n));
    return true;
  }

  // Used by outer approximation to linearise one row at a time.
  bool eval_gi(Index n, const Number* x, bool, Index i, Number& gi) override {
    gi = rows_.row(i).dot(Eigen::Map<const Eigen::VectorXd>(x, n));
    return true;
  }

  bool eval_grad_gi(Index, const Number*, bool, Index i, Index& nele_grad_gi, Index* j_col,
                    Number* values) override {
    nele_grad_gi = 0;
    for (RowMajorMatrix::InnerIterator it(rows_, i); it; ++it, ++nele_grad_gi) {
      if (j_col != nullptr) j_col[nele_grad_gi] = static_cast<Index>(it.col());
      if (values != nullptr) values[nele_grad_gi] = it.value();
    }
    return true;
  }

  void finalize_solution(SolverReturn status, Index, const Number*, Number) override {
    final_status_ = status;
  }

  [[nodiscard]] const BranchingInfo* branchingInfo() const override { return nullptr; }
  [[nodiscard]] const SosInfo* sosConstraints() const override { return nullptr; }

  bool hasLinearObjective() override {
    return std::all_of(hessian_lower().values.begin(), hessian_lower().values.end(),
                       [](double value) { return value == 0.0; });
  }

 private:
  using RowMajorMatrix = Eigen::SparseMatrix<double, Eigen::RowMajor>;

  [[nodiscard]] coin::LinearRowsQp qp() const override {
    return {problem_.hessian, problem_.gradient,  problem_.constraints, bounds_.lower,
            bounds_.upper,    problem_.row_lower, problem_.row_upper};
  }

  const MiqpProblem& problem_;
  ColumnBounds bounds_;
  RowMajorMatrix rows_;
  SolverReturn final_status_ = MINLP_ERROR;
};

void silence(Ipopt::OptionsList& options) {
  for (const char* log_level :
       {"bonmin.bb_log_level", "bonmin.nlp_log_level", "bonmin.nlp_log_at_root",
        "bonmin.lp_log_level", "bonmin.milp_log_level", "bonmin.oa_log_level",
        "bonmin.oa_cuts_log_level", "bonmin.fp_log_level", "print_level"}) {
    set_option(options, log_level, 0);
  }
  set_option(options, "sb", "yes");  // Ipopt's banner
}

void set_limits(Ipopt::OptionsList& options, const MiqpSettings& settings) {
  set_option(options, "bonmin.time_limit", std::clamp(settings.time_limit_s, 0.0, 1e10));
  set_option(options, "bonmin.node_limit",
             static_cast<int>(std::clamp(settings.node_limit, 0L, long{INT_MAX})));
  set_option(options, "bonmin.allowable_gap", settings.absolute_gap);
  set_option(options, "bonmin.allowable_fraction_gap", settings.relative_gap);
  // Cbc prunes nodes that cannot beat the incumbent by cutoff_decr (default 1e-5),
  // which would let the answer be that far from optimal.
  set_option(options, "bonmin.cutoff_decr", settings.absolute_gap);
  set_option(options, "bonmin.integer_tolerance", settings.integer_tolerance);
}

// Bonmin 1.8 runs an NLP feasibility pump at the root by default. It is only a
// heuristic, and on an infeasible problem it solves ~200 NLPs before giving up, which
// tripled the time of our tests without changing any answer.
void drop_heuristics(Ipopt::OptionsList& options) {
  set_option(options, "bonmin.heuristic_feasibility_pump", "no");
}

void choose_branching(Ipopt::OptionsList& options) {
  // Bonmin 1.8's default branching (strong branching with pseudo-costs) trips
  // an assertion in Osi (OsiSimpleInteger::createBranch: upper > lower) on
  // some infeasible lane-change MIQPs, which aborts the process. The choice
  // of branching variable does not change the answer of a branch and bound.
  set_option(options, "bonmin.number_strong_branch", 0);
  set_option(options, "bonmin.variable_selection", "most-fractional");
}

// Ipopt's defaults stop at a scaled error of 1e-8 and relax every bound by 1e-8
// relative, which leaves visible violations on big-M rows; the reference needs better.
void set_nlp_accuracy(Ipopt::OptionsList& options, const MiqpSettings& settings) {
  set_option(options, "tol", 1e-10);
  set_option(options, "constr_viol_tol", settings.feasibility_tolerance);
  set_option(options, "bound_relax_factor", 0.0);
  set_option(options, "honor_original_bounds", "yes");
}

void configure(Bonmin::BonminSetup& setup, const MiqpSettings& settings,
               BonminAlgorithm algorithm) {
  // Marks the options as read, so that a stray bonmin.opt in the working directory
  // cannot override ours.
  setup.readOptionsString("");
  Ipopt::OptionsList& options = *setup.options();
  set_option(options, "bonmin.algorithm",
             algorithm == BonminAlgorithm::BranchAndBound ? "B-BB" : "B-OA");
  set_limits(options, settings);
  drop_heuristics(options);
  choose_branching(options);
  set_nlp_accuracy(options, settings);
  if (!settings.verbose) silence(options);
}

double finite_or_infinite(double value) {
  constexpr double kBonminInfinity = 1e100;  // Bonmin reports "no bound" as +-1e200 or DBL_MAX
  if (value >= kBonminInfinity) return kInfinity;
  if (value <= -kBonminInfinity) return -kInfinity;
  return value;
}

MiqpStatus status_of(Bonmin::TMINLP::SolverReturn status, const Bonmin::Bab& bab) {
  switch (status) {
    case Bonmin::TMINLP::SUCCESS:
      return bab.bestSolution() != nullptr ? MiqpStatus::Optimal : MiqpStatus::NumericalError;
    case Bonmin::TMINLP::INFEASIBLE: return MiqpStatus::Infeasible;
    case Bonmin::TMINLP::LIMIT_EXCEEDED:
      return bab.model().isNodeLimitReached() ? MiqpStatus::NodeLimit : MiqpStatus::TimeLimit;
    default: return MiqpStatus::NumericalError;
  }
}

std::string message_of(Bonmin::TMINLP::SolverReturn status) {
  switch (status) {
    case Bonmin::TMINLP::CONTINUOUS_UNBOUNDED: return "the continuous relaxation is unbounded";
    case Bonmin::TMINLP::USER_INTERRUPT: return "Bonmin was interrupted";
    case Bonmin::TMINLP::MINLP_ERROR: return "Bonmin reported an error";
    default: return {};
  }
}

void fill_result(const MiqpProblem& problem, const MiqpTminlp& tminlp, Bonmin::Bab& bab,
                 MiqpResult& result) {
  result.status = status_of(tminlp.final_status(), bab);
  result.message = message_of(tminlp.final_status());
  result.nodes = bab.numNodes();
  if (bab.bestSolution() != nullptr) {
    result.x = Eigen::Map<const Eigen::VectorXd>(bab.bestSolution(), problem.num_variables());
    result.objective = problem.objective(result.x);
  }
  result.best_bound =
      result.status == MiqpStatus::Infeasible ? kInfinity : finite_or_infinite(bab.bestBound());
}

// Bonmin's Bab installs its own SIGINT handler (a second Ctrl-C calls exit(0)) and never
// restores the caller's. This puts the caller's handler back and passes on an interrupt
// that Bonmin swallowed.
class SigintGuard {
 public:
  SigintGuard() {
    sigaction(SIGINT, nullptr, &callers_action_);
    BonminAbortAll = false;
  }
  ~SigintGuard() {
    sigaction(SIGINT, &callers_action_, nullptr);
    if (BonminAbortAll) {
      BonminAbortAll = false;
      std::raise(SIGINT);
    }
  }
  SigintGuard(const SigintGuard&) = delete;
  SigintGuard& operator=(const SigintGuard&) = delete;

 private:
  struct sigaction callers_action_ {};
};

// The caller holds lock_coin_or_libraries().
void run_bonmin(const MiqpProblem& problem, ColumnBounds bounds, const MiqpSettings& settings,
                BonminAlgorithm algorithm, MiqpResult& result) {
  const SigintGuard sigint_guard;
  Ipopt::SmartPtr<MiqpTminlp> tminlp = new MiqpTminlp(problem, std::move(bounds));
  Bonmin::BonminSetup setup;
  configure(setup, settings, algorithm);
  setup.initialize(GetRawPtr(tminlp));
  Bonmin::Bab bab;
  // Cbc would otherwise measure the time limit in process CPU seconds.
  bab.model().setUseElapsedTime(true);
  bab(setup);
  fill_result(problem, *tminlp, bab, result);
}

std::string describe_current_exception() {
  try {
    throw;
  } catch (Bonmin::TNLPSolver::UnsolvedError* error) {  // Bonmin throws these by pointer
    const std::unique_ptr<Bonmin::TNLPSolver::UnsolvedError> owned(error);
    return "Ipopt failed on a node relaxation with status " + std::to_string(error->errorNum());
  } catch (const CoinError& error) {
    return "COIN-OR error in " + error.className() + "::" + error.methodName() + ": " +
           error.message();
  } catch (const Ipopt::IpoptException& error) {
    return "Ipopt exception: " + error.Message();
  } catch (const std::exception& error) {
    return error.what();
  } catch (int code) {
    return "Bonmin threw error code " + std::to_string(code);
  } catch (...) {
    return "unknown exception from Bonmin";
  }
}

// Waits for the library lock, which is also held while exceptions are handled since they
// own pieces of Bonmin's state. The wait counts against the time limit.
void run_bonmin_when_free(const MiqpProblem& problem, ColumnBounds bounds,
                          const MiqpSettings& settings, BonminAlgorithm algorithm,
                          Clock::time_point start, MiqpResult& result) {
  const auto lock = lock_coin_or_libraries();
  MiqpSettings remaining = settings;
  remaining.time_limit_s -= milliseconds_since(start) / 1e3;
  if (remaining.time_limit_s <= 0.0) {
    result.status = MiqpStatus::TimeLimit;
    result.message = "the time limit passed while waiting for another thread's solve";
    return;
  }
  try {
    run_bonmin(problem, std::move(bounds), remaining, algorithm, result);
  } catch (...) {
    result.status = MiqpStatus::NumericalError;
    result.message = describe_current_exception();
  }
}

// Only the columns that stay variable: all of them, or the continuous ones.
Eigen::SparseMatrix<double> hessian_block(const MiqpProblem& problem, bool binaries_fixed) {
  std::vector<int> block_index(problem.kinds.size(), -1);
  int size = 0;
  for (std::size_t j = 0; j < problem.kinds.size(); ++j) {
    if (!binaries_fixed || problem.kinds[j] == VariableKind::Continuous) block_index[j] = size++;
  }
  std::vector<Eigen::Triplet<double>> entries;
  const coin::SparseTriplets all = coin::triplets_of(problem.hessian, false);
  for (Index e = 0; e < all.size(); ++e) {
    const int row = block_index[static_cast<std::size_t>(all.rows[e])];
    const int col = block_index[static_cast<std::size_t>(all.cols[e])];
    if (row >= 0 && col >= 0) entries.emplace_back(row, col, all.values[e]);
  }
  Eigen::SparseMatrix<double> block(size, size);
  block.setFromTriplets(entries.begin(), entries.end());
  return block;
}

}  // namespace

std::string check_convexity(const MiqpProblem& problem, bool binaries_fixed) {
  Eigen::SparseMatrix<double> block = hessian_block(problem, binaries_fixed);
  if (block.nonZeros() == 0) return {};
  const double largest = block.coeffs().cwiseAbs().maxCoeff();
  // Round-off in a positive semidefinite H (say B'B) stays orders of magnitude below this.
  const double shift = 1e-8 * std::max(1.0, largest);
  Eigen::SparseMatrix<double> identity(block.rows(), block.cols());
  identity.setIdentity();
  block += shift * identity;
  const Eigen::SimplicialLLT<Eigen::SparseMatrix<double>> cholesky(block);
  if (cholesky.info() == Eigen::Success) return {};
  return binaries_fixed ? "hessian is not positive semidefinite over the continuous variables"
                        : "hessian is not positive semidefinite, so Bonmin's relaxations with "
                          "binaries in [0, 1] are nonconvex";
}

std::unique_lock<std::mutex> lock_coin_or_libraries() {
  static std::mutex coin_or_mutex;
  return std::unique_lock(coin_or_mutex);
}

BonminSolver::BonminSolver(BonminAlgorithm algorithm) : algorithm_(algorithm) {}

std::string_view BonminSolver::name() const {
  return algorithm_ == BonminAlgorithm::BranchAndBound ? "bonmin-B-BB" : "bonmin-B-OA";
}

MiqpResult BonminSolver::solve(const MiqpProblem& problem, const MiqpSettings& settings) const {
  const Clock::time_point start = Clock::now();
  MiqpResult result;
  std::string problem_error = problem.check();
  if (problem_error.empty()) problem_error = check_convexity(problem, /*binaries_fixed=*/false);
  if (!problem_error.empty()) {
    result.status = MiqpStatus::InvalidProblem;
    result.message = std::move(problem_error);
  } else if (auto bounds = effective_column_bounds(problem, settings.integer_tolerance);
             !bounds || rows_cross(problem)) {
    result.status = MiqpStatus::Infeasible;
    result.best_bound = kInfinity;
    result.message = "a lower bound exceeds its upper bound";
  } else if (problem.num_variables() == 0) {
    solve_without_variables(problem, result);
  } else {
    run_bonmin_when_free(problem, std::move(*bounds), settings, algorithm_, start, result);
  }
  result.solve_ms = milliseconds_since(start);
  return result;
}

}  // namespace lanechange::expert
