#pragma once
// A convex QP with the structure of an optimal-control problem, solved by a
// primal-dual interior-point method whose Newton steps are Riccati
// recursions (the approach of HPIPM). Stage k = 0..N has the augmented state
// s_k in R^5 ([x, y, v, theta, a_{k-1}], so that the jerk is a stage cost) and
// the control u_k in R^2 (none at stage N):
//
//   minimize   sum_k 0.5 [s;u]' H_k [s;u] + h_k' [s;u]
//   subject to s_0 fixed,  s_{k+1} = A_k s_k + B_k u_k + c_k,
//              rows g' [s_k; u_k] <= d at each stage, each hard or soft.
//
// A soft row may be violated by sigma >= 0 at the price softness_weight *
// sigma (an exact L1 penalty): when the rows can all hold, the solution has
// sigma = 0 and is the solution of the hard problem; a solution that needs
// sigma > 0 shows that the hard problem is infeasible. Making every row but
// the control bounds soft gives every QP an interior, so the method needs no
// phase one and infeasibility shows up as a number rather than a failure.
//
// The workspace is sized by setup() and reused: solve() allocates nothing.
#include <Eigen/Core>
#include <limits>
#include <vector>

namespace lanechange::expert {

inline constexpr int kQpStates = 5;
inline constexpr int kQpControls = 2;
inline constexpr int kQpStage = kQpStates + kQpControls;

using QpStateVector = Eigen::Matrix<double, kQpStates, 1>;
using QpStageVector = Eigen::Matrix<double, kQpStage, 1>;
using QpStageMatrix = Eigen::Matrix<double, kQpStage, kQpStage>;

struct QpRow {
  QpStageVector g = QpStageVector::Zero();
  double d = 0.0;
  bool soft = false;
};

struct QpStage {
  Eigen::Matrix<double, kQpStates, kQpStates> A = Eigen::Matrix<double, 5, 5>::Identity();
  Eigen::Matrix<double, kQpStates, kQpControls> B = Eigen::Matrix<double, 5, 2>::Zero();
  QpStateVector c = QpStateVector::Zero();
  QpStageMatrix H = QpStageMatrix::Zero();
  /// Optional: a diagonal D with H - diag(0, D) positive semidefinite (the
  /// part of the cost that is curvature in the controls alone). Zero is
  /// always valid; more makes the dual bound behind objective_cutoff tighter.
  Eigen::Vector2d control_curvature = Eigen::Vector2d::Zero();
  QpStageVector h = QpStageVector::Zero();
  std::vector<QpRow> rows;
};

struct StructuredQp {
  std::vector<QpStage> stages;  ///< N + 1; the dynamics of the last are unused
  QpStateVector initial_state = QpStateVector::Zero();
  /// An optional equality g' [s_N; u_N] = d on the last stage (the terminal
  /// lateral position). Written as two opposed inequalities it would leave
  /// the method no interior; as an equality it costs one extra back-substitution.
  bool has_terminal_equality = false;
  QpStageVector terminal_g = QpStageVector::Zero();
  double terminal_d = 0.0;
  double softness_weight = 1e6;
  [[nodiscard]] int steps() const { return static_cast<int>(stages.size()) - 1; }
};

/// How the Riccati recursion forms the next cost-to-go matrix P from a
/// stage's factored control block.
enum class RiccatiForm {
  /// P as the Schur complement of the 2 x 2 control block, inverted in
  /// closed form with a Cholesky factor's two (floored) pivots.
  /// An iteration where rounding leaves a later control block indefinite
  /// (barrier weights of 1e12 and more) is factored again in SquareRoot form.
  Schur,
  /// P = L22 L22' from a Cholesky factor of the whole stage matrix: positive
  /// semidefinite by construction, at seven pivots per stage.
  SquareRoot,
};

struct QpSettings {
  int max_iterations = 60;
  RiccatiForm riccati = RiccatiForm::Schur;
  double tolerance = 1e-10;        ///< on the mean complementarity product
  double primal_tolerance = 1e-8;  ///< on the rows and the terminal equality (m)
  /// On the stationarity of the controls. Looser than the rest: with barrier
  /// weights of 1e12 and more near the end, the Newton solves carry errors of
  /// about 1e-5 there, while mu and the rows are already exact.
  double dual_tolerance = 1e-3;
  double softness_tolerance = 1e-6;  ///< a larger sigma means the hard problem is infeasible
  double stalled_softness = 1e-2;    ///< the same, for a solve stopped by the iteration limit
  /// Stop with status Cutoff as soon as a proven lower bound on the optimum
  /// (of the stage costs, as QpResult::objective) reaches this value: a branch
  /// and bound discards such a node anyway, and most of them are clear after
  /// a few iterations.
  double objective_cutoff = std::numeric_limits<double>::infinity();
  /// Stop with status Coarse at the first iterate whose objective is below
  /// this, with mu and the rows within coarse_tolerance and no row needing
  /// slack: enough for a branch and bound to pick where to branch, not to
  /// take the point as a solution.
  double coarse_below = -std::numeric_limits<double>::infinity();
  double coarse_tolerance = 1e-3;
  /// Where the method starts each row's complementarity product. About the
  /// size of the products that the rows' distances give this problem family
  /// (metres and m/s); 1 took a fifth more iterations, 1e4 no fewer.
  double initial_complementarity = 1e3;
  /// Use the sparsity of the lane-change dynamics where a stage has it
  /// (KinematicDynamics): the same steps in about a fifth of the dense
  /// products' flops. Off: every stage as dense matrices (the tests compare).
  bool kinematic_sparsity = true;
  /// Start from the workspace's last optimal solution (multipliers and
  /// slacks, each at least warm_start_floor off its bound) when this problem
  /// has its rows, stage for stage: a successive linearization's next round.
  bool warm_start = false;
  double warm_start_floor = 1e-1;
};

enum class QpStatus {
  Optimal,
  Infeasible,
  Cutoff,  ///< the optimum is at least QpSettings::objective_cutoff (or there is none)
  Coarse,  ///< stopped early at a point below QpSettings::coarse_below (see there)
  IterationLimit,
  NumericalError
};

struct QpResult {
  QpStatus status = QpStatus::NumericalError;
  int iterations = 0;
  double max_softness = 0.0;  ///< largest sigma at the solution
  double objective = 0.0;     ///< of the stage costs, without the softness price
  double lower_bound = -std::numeric_limits<double>::infinity();  ///< the last proven one
};

/// The nonzeros of a stage's dynamics in the lane-change QPs: x and y move
/// with v and theta, v and theta integrate the controls (a, omega), and the
/// last state component remembers the acceleration. A = diag(1, 1, 1, 1, 0)
/// plus the four x/y couplings; B has the seven entries below.
struct KinematicDynamics {
  double x_v = 0.0, x_theta = 0.0, y_v = 0.0, y_theta = 0.0;  ///< A(0..1, 2..3)
  double x_a = 0.0, x_omega = 0.0, y_a = 0.0, y_omega = 0.0;  ///< B(0..1, 0..1)
  double v_a = 0.0, theta_omega = 0.0, memory_a = 0.0;        ///< B(2, 0), B(3, 1), B(4, 0)
};

/// True, with the nonzeros in `out`, when A and B have exactly that pattern.
[[nodiscard]] bool kinematic_form(const Eigen::Matrix<double, kQpStates, kQpStates>& A,
                                  const Eigen::Matrix<double, kQpStates, kQpControls>& B,
                                  KinematicDynamics& out);

/// Per-stage vectors of the interior-point method; sized once for a problem shape.
class QpWorkspace {
 public:
  void setup(const StructuredQp& qp);
  /// Room for problems of up to `rows` rows, so that setup() allocates
  /// nothing for them (a search whose nodes add and drop rows).
  void reserve(std::size_t rows);
  /// The solution: states s_0..s_N and controls u_0..u_{N-1} in one vector per stage.
  [[nodiscard]] const std::vector<QpStageVector>& solution() const { return w_; }
  /// A starting guess for the controls (rolled out through the dynamics).
  void set_initial_controls(const std::vector<Eigen::Vector2d>& controls);
  /// The next problems start `stages` stages later than the last one solved
  /// here (a re-plan some steps on): a warm start (QpSettings::warm_start)
  /// takes each stage's multipliers from the stage of the last solution
  /// that now lies there.
  void advance(int stages);

 private:
  friend struct InteriorPointMethod;
  void mark_control_boxes(const StructuredQp& qp);
  /// Lines the last solution's rows up with `qp`'s stages (see advance).
  void carry_solution(const StructuredQp& qp);
  std::vector<int> row_offset_;
  std::vector<KinematicDynamics> kinematic_;  ///< per stage, when is_kinematic_
  std::vector<char> is_kinematic_;            ///< per stage, found by each solve
  std::vector<int> single_index_;             ///< per row: its only nonzero, or -1
  /// A row as the method's passes read it, packed per solve: most rows
  /// bound one component, and their passes need no more than this.
  struct PackedRow {
    const QpStageVector* g = nullptr;  ///< the row's, in the problem being solved
    double d = 0.0;
    double coefficient = 0.0;  ///< g[single], where single >= 0
    int single = -1;           ///< the only nonzero of g, or -1
    int stage = 0;
    bool soft = false;
  };
  std::vector<PackedRow> packed_;
  std::vector<bool> control_box_;  ///< per row: a hard bound on one control
  std::vector<Eigen::Vector2d> control_lower_, control_upper_;  ///< per stage, from those rows
  std::vector<QpStageVector> w_, dw_, grad_, grad_base_, dw_unit_;
  double terminal_multiplier_ = 0.0;
  double terminal_step_ = 0.0;
  std::vector<QpStageMatrix> hess_;
  std::vector<Eigen::Matrix<double, kQpControls, kQpStates>> gain_;
  std::vector<Eigen::Vector2d> feedforward_, unit_feedforward_, initial_controls_;
  std::vector<Eigen::Matrix2d> rbar_inverse_;
  std::vector<Eigen::Matrix<double, kQpControls, kQpStates>> sbar_;
  std::vector<Eigen::Matrix<double, kQpStates, 1>> costate_;
  std::vector<double> t_, lambda_, sigma_, lambda_soft_;
  bool has_solution_ = false;         ///< t_ .. lambda_soft_ hold an optimal solution of these rows
  std::vector<char> warm_stage_;      ///< per stage: its rows hold that solution's values
  std::vector<int> next_row_offset_;  ///< carry_solution's scratch
  std::vector<double> carried_t_, carried_lambda_, carried_sigma_, carried_lambda_soft_;  ///< also
  int stages_since_solution_ = 0;  ///< advance()'s stages since that solution
  std::vector<double> dt_, dlambda_, dsigma_, dlambda_soft_;
  std::vector<double> weight_, offset_, soft_q_;
  std::vector<double> dt_aff_, dlambda_aff_, dsigma_aff_, dlambda_soft_aff_;
  std::vector<double> a_, inverse_t_, inverse_sigma_, inverse_a_plus_b_;  ///< per iteration
  std::vector<double> residual_;  ///< per row, g'w + t - d (- sigma), at the iteration's point
};

/// Solves from the workspace's initial controls (zero unless set).
QpResult solve_structured_qp(const StructuredQp& qp, QpWorkspace& ws, const QpSettings& settings);

}  // namespace lanechange::expert
