// Checks the reference MIQP solvers against each other and against hand-made problems.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <future>
#include <limits>
#include <random>
#include <vector>

#include "lanechange/expert/bonmin_solver.hpp"
#include "lanechange/expert/enumeration_solver.hpp"
#include "lanechange/expert/miqp.hpp"

// LeakSanitizer reads this hook in sanitizer builds; elsewhere it is never called.
// When a node or time limit stops Bonmin's B-BB, Cbc 2.10.8 never frees the node it was
// working on (its CbcNode, node info, branching object and Ipopt warm start: 0.5-5 KB
// per stopped solve). Only allocations made directly in those library functions are
// suppressed; the limit tests below would otherwise fail under the sanitize preset.
extern "C" const char* __lsan_default_suppressions() {
  return "leak:CbcModel::branchAndBound\n"
         "leak:CbcNode::chooseBranch\n"
         "leak:CbcFullNodeInfo::CbcFullNodeInfo\n"
         "leak:Bonmin::CbcNlpStrategy::fullNodeInfo\n"
         "leak:Bonmin::IpoptSolver::getEmptyWarmStart\n"
         "leak:OsiSimpleInteger::createBranch\n";
}

namespace lanechange::expert {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

double relative_difference(double a, double b) {
  return std::abs(a - b) / std::max({1.0, std::abs(a), std::abs(b)});
}

// Accumulates rows one at a time; the variables are fixed up front.
class ProblemBuilder {
 public:
  explicit ProblemBuilder(int num_variables) : n_(num_variables) {
    problem_.hessian.resize(n_, n_);
    problem_.gradient = Eigen::VectorXd::Zero(n_);
    problem_.col_lower = Eigen::VectorXd::Constant(n_, -kInfinity);
    problem_.col_upper = Eigen::VectorXd::Constant(n_, kInfinity);
    problem_.kinds.assign(static_cast<std::size_t>(n_), VariableKind::Continuous);
  }

  ProblemBuilder& binary(int j) {
    problem_.kinds[static_cast<std::size_t>(j)] = VariableKind::Binary;
    return bounds(j, 0.0, 1.0);
  }
  ProblemBuilder& bounds(int j, double lower, double upper) {
    problem_.col_lower[j] = lower;
    problem_.col_upper[j] = upper;
    return *this;
  }
  ProblemBuilder& objective(const Eigen::MatrixXd& hessian, const Eigen::VectorXd& gradient,
                            double constant) {
    problem_.hessian = hessian.sparseView();
    problem_.gradient = gradient;
    problem_.constant = constant;
    return *this;
  }
  ProblemBuilder& row(const Eigen::VectorXd& coefficients, double lower, double upper) {
    rows_.push_back(coefficients);
    lower_.push_back(lower);
    upper_.push_back(upper);
    return *this;
  }

  [[nodiscard]] MiqpProblem build() const {
    MiqpProblem problem = problem_;
    const auto m = static_cast<Eigen::Index>(rows_.size());
    Eigen::MatrixXd dense(m, n_);
    for (Eigen::Index i = 0; i < m; ++i) dense.row(i) = rows_[static_cast<std::size_t>(i)];
    problem.constraints = dense.sparseView();
    problem.row_lower = Eigen::Map<const Eigen::VectorXd>(lower_.data(), m);
    problem.row_upper = Eigen::Map<const Eigen::VectorXd>(upper_.data(), m);
    return problem;
  }

 private:
  int n_;
  MiqpProblem problem_;
  std::vector<Eigen::VectorXd> rows_;
  std::vector<double> lower_;
  std::vector<double> upper_;
};

Eigen::VectorXd unit(int n, std::initializer_list<std::pair<int, double>> entries) {
  Eigen::VectorXd v = Eigen::VectorXd::Zero(n);
  for (const auto& [index, value] : entries) v[index] = value;
  return v;
}

// Choose one of three lanes (x is the lateral position, b_k selects lane k):
//   minimize (x - 4)^2 + 0.5 b3   s.t.  b1 + b2 + b3 = 1,  lane_k holds x when b_k = 1.
// Lanes [0,1], [2,3], [5,6]: lane 2 at x = 3 costs 1, lane 3 at x = 5 costs 1.5,
// lane 1 at x = 1 costs 9. The relaxation (x = 4 with mixed b) is far lower.
MiqpProblem lane_choice_problem() {
  constexpr double kBigM = 20.0;
  constexpr int kN = 4;  // x, b1, b2, b3
  const double lane_lower[] = {0.0, 2.0, 5.0};
  const double lane_upper[] = {1.0, 3.0, 6.0};
  ProblemBuilder builder(kN);
  builder.bounds(0, -10.0, 10.0).binary(1).binary(2).binary(3);
  builder.objective(unit(kN, {{0, 2.0}}).asDiagonal(), unit(kN, {{0, -8.0}, {3, 0.5}}), 16.0);
  builder.row(unit(kN, {{1, 1.0}, {2, 1.0}, {3, 1.0}}), 1.0, 1.0);
  for (int lane = 0; lane < 3; ++lane) {
    // x >= lower - M (1 - b)  and  x <= upper + M (1 - b)
    builder.row(unit(kN, {{0, 1.0}, {lane + 1, -kBigM}}), lane_lower[lane] - kBigM, kInfinity);
    builder.row(unit(kN, {{0, 1.0}, {lane + 1, kBigM}}), -kInfinity, lane_upper[lane] + kBigM);
  }
  return builder.build();
}

// Random convex MIQP: a strictly convex quadratic in a few box-bounded continuous
// variables x (coupled to the binaries), where each binary b_k picks a side of a
// disjunction "a_k'x <= r_k  or  a_k'x >= s_k" through big-M rows. Some instances tie
// three binaries with "exactly one"; every fifth is made infeasible by a row that
// forbids both sides of one disjunction, while its continuous relaxation stays feasible.
struct RandomInstance {
  MiqpProblem problem;
  bool infeasible_by_construction = false;
};

/// num_binaries = 0 draws it from 4..10.
RandomInstance random_big_m_instance(std::uint32_t seed, int num_binaries = 0) {
  constexpr double kBox = 10.0;
  constexpr double kBigM = 60.0;  // |a'x| <= 40 and |r|, |s| <= 6 on the box
  std::mt19937 rng(seed);
  auto uniform = [&rng](double lo, double hi) {
    return std::uniform_real_distribution<double>(lo, hi)(rng);
  };
  const int drawn_binaries = std::uniform_int_distribution<int>(4, 10)(rng);
  if (num_binaries == 0) num_binaries = drawn_binaries;
  const int num_continuous = std::uniform_int_distribution<int>(2, 4)(rng);
  const int n = num_continuous + num_binaries;

  const Eigen::MatrixXd factor =
      Eigen::MatrixXd::NullaryExpr(num_continuous + 1, n, [&] { return uniform(-1.0, 1.0); });
  Eigen::MatrixXd hessian = factor.transpose() * factor;
  hessian.topLeftCorner(num_continuous, num_continuous).diagonal().array() += 0.5;
  hessian = (0.5 * (hessian + hessian.transpose())).eval();
  const Eigen::VectorXd gradient =
      Eigen::VectorXd::NullaryExpr(n, [&] { return uniform(-5.0, 5.0); });

  ProblemBuilder builder(n);
  builder.objective(hessian, gradient, uniform(-2.0, 2.0));
  for (int j = 0; j < num_continuous; ++j) builder.bounds(j, -kBox, kBox);
  for (int k = 0; k < num_binaries; ++k) builder.binary(num_continuous + k);

  RandomInstance instance;
  instance.infeasible_by_construction = seed % 5 == 4;
  for (int k = 0; k < num_binaries; ++k) {
    Eigen::VectorXd direction = Eigen::VectorXd::Zero(n);
    direction.head(num_continuous) =
        Eigen::VectorXd::NullaryExpr(num_continuous, [&] { return uniform(-1.0, 1.0); });
    const double r = uniform(-3.0, 3.0);
    const double s = r + uniform(0.5, 3.0);
    Eigen::VectorXd with_binary = direction;
    with_binary[num_continuous + k] = -kBigM;
    builder.row(with_binary, -kInfinity, r);         // binds when b_k = 0
    builder.row(with_binary, s - kBigM, kInfinity);  // binds when b_k = 1
    if (k == 0 && instance.infeasible_by_construction) {
      const double quarter = 0.25 * (s - r);
      builder.row(direction, r + quarter, s - quarter);
    }
  }
  if (seed % 3 == 0) {
    Eigen::VectorXd first_three = Eigen::VectorXd::Zero(n);
    first_three.segment(num_continuous, 3).setOnes();
    builder.row(first_three, 1.0, 1.0);
  }
  instance.problem = builder.build();
  return instance;
}

MiqpSettings quiet_settings() { return MiqpSettings{.time_limit_s = 60.0}; }

void expect_optimal_point(const MiqpProblem& problem, const MiqpResult& result,
                          double expected_objective) {
  ASSERT_EQ(result.status, MiqpStatus::Optimal) << result.message;
  ASSERT_EQ(result.x.size(), problem.num_variables());
  EXPECT_LE(problem.max_violation(result.x), 1e-7);
  EXPECT_NEAR(result.objective, problem.objective(result.x), 1e-12);
  EXPECT_LE(relative_difference(result.objective, expected_objective), 1e-8)
      << result.objective << " vs " << expected_objective;
}

// --- MiqpProblem basics -----------------------------------------------------------

TEST(MiqpProblem, ObjectiveAndViolationAtHandPickedPoints) {
  const MiqpProblem problem = lane_choice_problem();
  EXPECT_TRUE(problem.check().empty()) << problem.check();
  EXPECT_EQ(problem.num_variables(), 4);
  EXPECT_EQ(problem.num_rows(), 7);
  EXPECT_EQ(problem.num_binaries(), 3);

  const Eigen::Vector4d lane_two(3.0, 0.0, 1.0, 0.0);
  EXPECT_DOUBLE_EQ(problem.objective(lane_two), 1.0);
  EXPECT_DOUBLE_EQ(problem.max_violation(lane_two), 0.0);

  const Eigen::Vector4d outside_lane(3.5, 0.0, 1.0, 0.0);  // lane 2 ends at 3
  EXPECT_DOUBLE_EQ(problem.max_violation(outside_lane), 0.5);
  const Eigen::Vector4d two_lanes(3.0, 0.0, 1.0, 1.0);  // b1 + b2 + b3 = 2, and lane 3 starts at 5
  EXPECT_DOUBLE_EQ(problem.max_violation(two_lanes), 2.0);
  const Eigen::Vector4d fractional(3.0, 0.0, 0.75, 0.25);  // integrality only
  EXPECT_DOUBLE_EQ(problem.max_violation(fractional), 0.25);
  const Eigen::Vector4d beyond_box(11.0, 0.0, 0.0, 1.0);  // x <= 10 and lane 3 ends at 6
  EXPECT_DOUBLE_EQ(problem.max_violation(beyond_box), 5.0);
}

TEST(MiqpProblem, MalformedPointsAreNeverFeasible) {
  const MiqpProblem problem = lane_choice_problem();
  EXPECT_EQ(problem.max_violation(Eigen::Vector3d::Zero()), kInfinity);
  EXPECT_EQ(problem.max_violation(Eigen::Vector4d(kNaN, 0.0, 1.0, 0.0)), kInfinity);
  EXPECT_TRUE(std::isnan(problem.objective(Eigen::Vector3d::Zero())));
}

TEST(MiqpProblem, CheckSaysWhatIsWrong) {
  const MiqpProblem valid = lane_choice_problem();

  MiqpProblem nan_gradient = valid;
  nan_gradient.gradient[2] = kNaN;
  EXPECT_NE(nan_gradient.check().find("gradient"), std::string::npos);

  MiqpProblem short_kinds = valid;
  short_kinds.kinds.pop_back();
  EXPECT_NE(short_kinds.check().find("kinds"), std::string::npos);

  MiqpProblem asymmetric = valid;
  asymmetric.hessian.coeffRef(0, 3) = 1.0;
  EXPECT_NE(asymmetric.check().find("symmetric"), std::string::npos);

  MiqpProblem inverted_infinity = valid;
  inverted_infinity.row_upper[1] = -kInfinity;
  EXPECT_NE(inverted_infinity.check().find("row 1"), std::string::npos);

  MiqpProblem infinite_coefficient = valid;
  infinite_coefficient.constraints.coeffRef(0, 1) = kInfinity;
  EXPECT_NE(infinite_coefficient.check().find("constraints"), std::string::npos);
}

TEST(MiqpStatus, HasReadableNames) {
  EXPECT_EQ(to_string(MiqpStatus::Optimal), "Optimal");
  EXPECT_EQ(to_string(MiqpStatus::InvalidProblem), "InvalidProblem");
}

// --- Hand-made problems -------------------------------------------------------------

TEST(BonminSolver, FindsTheKnownOptimumOfTheLaneChoice) {
  const MiqpProblem problem = lane_choice_problem();
  for (const BonminAlgorithm algorithm :
       {BonminAlgorithm::BranchAndBound, BonminAlgorithm::OuterApproximation}) {
    const BonminSolver solver(algorithm);
    SCOPED_TRACE(std::string(solver.name()));
    const MiqpResult result = solver.solve(problem, quiet_settings());
    expect_optimal_point(problem, result, 1.0);
    EXPECT_NEAR(result.x[0], 3.0, 1e-7);
    EXPECT_EQ(result.x.tail(3), Eigen::Vector3d(0.0, 1.0, 0.0));
    EXPECT_LE(result.best_bound, result.objective + 1e-9);
  }
}

TEST(EnumerationSolver, FindsTheKnownOptimumOfTheLaneChoice) {
  const MiqpProblem problem = lane_choice_problem();
  const MiqpResult result = EnumerationSolver().solve(problem, quiet_settings());
  expect_optimal_point(problem, result, 1.0);
  EXPECT_EQ(result.nodes, 8);
}

TEST(BonminSolver, ReportsAnInfeasibleProblemWhoseRelaxationIsFeasible) {
  // Every lane ends by x = 6, but x >= 7 is required; with fractional b it fits.
  MiqpProblem problem = lane_choice_problem();
  problem.col_lower[0] = 7.0;
  for (const BonminAlgorithm algorithm :
       {BonminAlgorithm::BranchAndBound, BonminAlgorithm::OuterApproximation}) {
    const BonminSolver solver(algorithm);
    const MiqpResult result = solver.solve(problem, quiet_settings());
    EXPECT_EQ(result.status, MiqpStatus::Infeasible) << solver.name() << ": " << result.message;
    EXPECT_FALSE(result.has_solution());
  }
  EXPECT_EQ(EnumerationSolver().solve(problem, quiet_settings()).status, MiqpStatus::Infeasible);
}

TEST(BonminSolver, ReportsCrossedBoundsAsInfeasible) {
  MiqpProblem problem = lane_choice_problem();
  problem.col_lower[2] = 0.5;  // a binary that can be neither 0 nor 1
  problem.col_upper[2] = 0.6;
  EXPECT_EQ(BonminSolver().solve(problem, quiet_settings()).status, MiqpStatus::Infeasible);
  EXPECT_EQ(EnumerationSolver().solve(problem, quiet_settings()).status, MiqpStatus::Infeasible);
}

TEST(BonminSolver, RefusesNaNDataWithoutSolving) {
  MiqpProblem problem = lane_choice_problem();
  problem.hessian.coeffRef(0, 0) = kNaN;
  const BonminSolver bonmin;
  const EnumerationSolver enumeration;
  for (const MiqpSolver* solver :
       {static_cast<const MiqpSolver*>(&bonmin), static_cast<const MiqpSolver*>(&enumeration)}) {
    const MiqpResult result = solver->solve(problem, quiet_settings());
    EXPECT_EQ(result.status, MiqpStatus::InvalidProblem) << solver->name();
    EXPECT_NE(result.message.find("hessian"), std::string::npos) << result.message;
    EXPECT_FALSE(result.has_solution());
  }
}

TEST(BonminSolver, RefusesANonconvexObjective) {
  // x * b is convex once b is fixed but not over b in [0, 1], which B-BB relaxes to.
  ProblemBuilder builder(2);
  builder.bounds(0, -1.0, 1.0).binary(1);
  Eigen::Matrix2d hessian;
  hessian << 2.0, 3.0, 3.0, 0.0;
  builder.objective(hessian, Eigen::Vector2d(0.0, 1.0), 0.0);
  const MiqpProblem problem = builder.build();
  const MiqpResult bonmin = BonminSolver().solve(problem, quiet_settings());
  EXPECT_EQ(bonmin.status, MiqpStatus::InvalidProblem);
  EXPECT_NE(bonmin.message.find("positive semidefinite"), std::string::npos) << bonmin.message;
  // b = 1: x^2 + 3x + 1 is smallest at x = -1, value -1; b = 0 gives 0.
  expect_optimal_point(problem, EnumerationSolver().solve(problem, quiet_settings()), -1.0);

  MiqpProblem saddle = problem;
  saddle.hessian.coeffRef(0, 0) = -1.0;
  EXPECT_EQ(EnumerationSolver().solve(saddle, quiet_settings()).status, MiqpStatus::InvalidProblem);
}

TEST(BonminSolver, SolvesAProblemWithoutVariables) {
  ProblemBuilder builder(0);
  builder.objective(Eigen::MatrixXd(0, 0), Eigen::VectorXd(0), 2.5);
  builder.row(Eigen::VectorXd(0), -1.0, 1.0);
  const MiqpResult result = BonminSolver().solve(builder.build(), quiet_settings());
  EXPECT_EQ(result.status, MiqpStatus::Optimal);
  EXPECT_EQ(result.objective, 2.5);
}

TEST(BonminSolver, SolvesAProblemWithoutBinaries) {
  // minimize (x - 1)^2 + (y - 2)^2  s.t.  x + y <= 2: optimum at (0.5, 1.5), value 0.5.
  ProblemBuilder builder(2);
  builder.objective(2.0 * Eigen::Matrix2d::Identity(), Eigen::Vector2d(-2.0, -4.0), 5.0);
  builder.row(Eigen::Vector2d(1.0, 1.0), -kInfinity, 2.0);
  const MiqpProblem problem = builder.build();
  expect_optimal_point(problem, BonminSolver().solve(problem, quiet_settings()), 0.5);
  expect_optimal_point(problem, EnumerationSolver().solve(problem, quiet_settings()), 0.5);
}

TEST(EnumerationSolver, RefusesTooManyBinaries) {
  const int n = EnumerationSolver::kMaxBinaries + 1;
  ProblemBuilder builder(n);
  for (int j = 0; j < n; ++j) builder.binary(j);
  builder.objective(Eigen::MatrixXd::Identity(n, n), Eigen::VectorXd::Zero(n), 0.0);
  const MiqpResult result = EnumerationSolver().solve(builder.build(), quiet_settings());
  EXPECT_EQ(result.status, MiqpStatus::InvalidProblem);
  EXPECT_NE(result.message.find("binaries"), std::string::npos) << result.message;
}

TEST(SolveWithFixedBinaries, SolvesTheQpOfOneLane) {
  const MiqpProblem problem = lane_choice_problem();
  const MiqpResult lane_three =
      solve_with_fixed_binaries(problem, Eigen::Vector4d(0.0, 0.0, 0.0, 0.97), quiet_settings());
  expect_optimal_point(problem, lane_three, 1.5);
  const MiqpResult two_lanes =
      solve_with_fixed_binaries(problem, Eigen::Vector4d(0.0, 1.0, 1.0, 0.0), quiet_settings());
  EXPECT_EQ(two_lanes.status, MiqpStatus::Infeasible);
}

// --- Limits ------------------------------------------------------------------------

TEST(BonminSolver, StopsAtTheNodeLimit) {
  const MiqpProblem problem = random_big_m_instance(7).problem;
  MiqpSettings settings = quiet_settings();
  settings.node_limit = 1;
  const MiqpResult result = BonminSolver().solve(problem, settings);
  EXPECT_EQ(result.status, MiqpStatus::NodeLimit) << result.message;
  if (result.has_solution()) {
    EXPECT_LE(problem.max_violation(result.x), 1e-7);
  }
}

TEST(BonminSolver, StopsAtTheTimeLimit) {
  // Fifty binaries take B-BB about 50 s and B-OA about 15 s on a 2-core machine.
  const MiqpProblem problem = random_big_m_instance(1, 50).problem;
  MiqpSettings settings = quiet_settings();
  settings.time_limit_s = 0.5;
  for (const BonminAlgorithm algorithm :
       {BonminAlgorithm::BranchAndBound, BonminAlgorithm::OuterApproximation}) {
    const BonminSolver solver(algorithm);
    const MiqpResult result = solver.solve(problem, settings);
    EXPECT_EQ(result.status, MiqpStatus::TimeLimit) << solver.name() << ": " << result.message;
    // Stopped, not solved: far below the full solve's time, with room for a
    // loaded machine under the sanitizers (a 2-core run sharing its cores with
    // a build took 7.4 s; Bonmin checks its clock between nodes).
    EXPECT_LT(result.solve_ms, 20000.0) << solver.name();
    if (result.has_solution()) {
      EXPECT_LE(problem.max_violation(result.x), 1e-7);
    }
  }
}

TEST(EnumerationSolver, StopsAtTheNodeLimit) {
  MiqpSettings settings = quiet_settings();
  settings.node_limit = 3;
  const MiqpResult result = EnumerationSolver().solve(lane_choice_problem(), settings);
  EXPECT_EQ(result.status, MiqpStatus::NodeLimit);
  EXPECT_EQ(result.nodes, 3);
}

// --- Bonmin against brute force ----------------------------------------------------

struct Agreement {
  double solve_ms = 0.0;
  double worst_relative_difference = 0.0;
};

void expect_agreement(const MiqpProblem& problem, const MiqpResult& truth, const MiqpSolver& solver,
                      Agreement& agreement) {
  const MiqpResult result = solver.solve(problem, quiet_settings());
  agreement.solve_ms += result.solve_ms;
  EXPECT_EQ(result.status, truth.status) << solver.name() << ": " << result.message;
  if (truth.status != MiqpStatus::Optimal || result.status != MiqpStatus::Optimal) return;
  const double difference = relative_difference(result.objective, truth.objective);
  agreement.worst_relative_difference = std::max(agreement.worst_relative_difference, difference);
  EXPECT_LE(difference, 1e-6) << solver.name() << " " << result.objective << " vs enumeration "
                              << truth.objective;
  EXPECT_LE(problem.max_violation(result.x), 1e-7) << solver.name();
  EXPECT_LE(result.best_bound, result.objective + 1e-6 * std::max(1.0, std::abs(result.objective)))
      << solver.name();
}

TEST(BonminSolver, AgreesWithEnumerationOnRandomBigMProblems) {
  const EnumerationSolver enumeration;
  const BonminSolver branch_and_bound(BonminAlgorithm::BranchAndBound);
  const BonminSolver outer_approximation(BonminAlgorithm::OuterApproximation);
  Agreement enumeration_total;
  Agreement branch_and_bound_total;
  Agreement outer_approximation_total;
  int optimal = 0;
  int infeasible = 0;
  for (std::uint32_t seed = 1; seed <= 30; ++seed) {
    const RandomInstance instance = random_big_m_instance(seed);
    const MiqpProblem& problem = instance.problem;
    SCOPED_TRACE("seed " + std::to_string(seed) + ", " + std::to_string(problem.num_binaries()) +
                 " binaries");
    const MiqpResult truth = enumeration.solve(problem, quiet_settings());
    enumeration_total.solve_ms += truth.solve_ms;
    ASSERT_TRUE(truth.status == MiqpStatus::Optimal || truth.status == MiqpStatus::Infeasible)
        << to_string(truth.status) << ": " << truth.message;
    if (instance.infeasible_by_construction) {
      EXPECT_EQ(truth.status, MiqpStatus::Infeasible);
    }
    if (truth.status == MiqpStatus::Optimal) {
      ++optimal;
      EXPECT_LE(problem.max_violation(truth.x), 1e-7);
    } else {
      ++infeasible;
    }
    expect_agreement(problem, truth, branch_and_bound, branch_and_bound_total);
    expect_agreement(problem, truth, outer_approximation, outer_approximation_total);
  }
  std::printf(
      "%d optimal, %d infeasible. Enumeration %.0f ms; B-BB %.0f ms, worst relative objective "
      "difference %.1e; B-OA %.0f ms, %.1e\n",
      optimal, infeasible, enumeration_total.solve_ms, branch_and_bound_total.solve_ms,
      branch_and_bound_total.worst_relative_difference, outer_approximation_total.solve_ms,
      outer_approximation_total.worst_relative_difference);
  EXPECT_GE(infeasible, 6);
  EXPECT_GE(optimal, 15);
}

// --- Threads -------------------------------------------------------------------------

TEST(BonminSolver, GivesTheSameAnswersFromSeveralThreads) {
  const BonminSolver solver;
  const std::vector<std::uint32_t> seeds = {2, 3, 5, 6};
  std::vector<MiqpResult> sequential;
  for (const std::uint32_t seed : seeds) {
    sequential.push_back(solver.solve(random_big_m_instance(seed).problem, quiet_settings()));
  }
  std::vector<std::future<MiqpResult>> concurrent;
  for (const std::uint32_t seed : seeds) {
    concurrent.push_back(std::async(std::launch::async, [&solver, seed] {
      return solver.solve(random_big_m_instance(seed).problem, quiet_settings());
    }));
  }
  for (std::size_t i = 0; i < seeds.size(); ++i) {
    const MiqpResult result = concurrent[i].get();
    EXPECT_EQ(result.status, sequential[i].status);
    EXPECT_EQ(result.objective, sequential[i].objective);
  }
}

}  // namespace
}  // namespace lanechange::expert
