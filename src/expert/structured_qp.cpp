#include "lanechange/expert/structured_qp.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <utility>

namespace lanechange::expert {

using StateMatrix = Eigen::Matrix<double, kQpStates, kQpStates>;
using GainMatrix = Eigen::Matrix<double, kQpControls, kQpStates>;

bool kinematic_form(const Eigen::Matrix<double, kQpStates, kQpStates>& A,
                    const Eigen::Matrix<double, kQpStates, kQpControls>& B,
                    KinematicDynamics& out) {
  Eigen::Matrix<double, kQpStates, kQpStates> rest_a = A;
  rest_a.block<2, 2>(0, 2).setZero();
  Eigen::Matrix<double, kQpStates, kQpStates> identity_but_memory =
      Eigen::Matrix<double, kQpStates, kQpStates>::Identity();
  identity_but_memory(4, 4) = 0.0;
  if (rest_a != identity_but_memory) return false;
  Eigen::Matrix<double, kQpStates, kQpControls> rest_b = B;
  rest_b.topRows<2>().setZero();
  rest_b(2, 0) = rest_b(3, 1) = rest_b(4, 0) = 0.0;
  if (!rest_b.isZero(0.0)) return false;
  out = {A(0, 2), A(0, 3), A(1, 2), A(1, 3), B(0, 0), B(0, 1),
         B(1, 0), B(1, 1), B(2, 0), B(3, 1), B(4, 0)};
  return true;
}

void QpWorkspace::advance(int stages) { stages_since_solution_ += stages; }

void QpWorkspace::carry_solution(const StructuredQp& qp) {
  const int stages = qp.steps() + 1;
  const int old_stages = static_cast<int>(row_offset_.size()) - 1;
  std::vector<int>& offset = next_row_offset_;  // a member: setup runs per node of a search
  offset.assign(static_cast<std::size_t>(stages) + 1, 0);
  for (int k = 0; k < stages; ++k)
    offset[k + 1] = offset[k] + static_cast<int>(qp.stages[k].rows.size());
  const bool in_place = stages_since_solution_ == 0 && offset == row_offset_;
  warm_stage_.assign(stages, in_place ? 1 : 0);
  bool any = in_place;
  if (has_solution_ && old_stages > 0 && !in_place) {
    // Stage k of this problem lies where stage k + shift of the last one
    // did (the last stage repeats past its end, as a shifted plan's does).
    // A stage's multipliers fit only row for row: a stage whose row count
    // changed starts centred.
    // Members, so that a re-plan allocates nothing once they have grown:
    // after the swaps below they hold the last solution's arrays.
    std::vector<double>& t = carried_t_;
    std::vector<double>& lambda = carried_lambda_;
    std::vector<double>& sigma = carried_sigma_;
    std::vector<double>& lambda_soft = carried_lambda_soft_;
    for (auto* v : {&t, &lambda, &sigma, &lambda_soft}) v->assign(offset.back(), 0.0);
    for (int k = 0; k < stages; ++k) {
      const int from = std::min(k + stages_since_solution_, old_stages - 1);
      const int count = offset[k + 1] - offset[k];
      if (row_offset_[from + 1] - row_offset_[from] != count) continue;
      warm_stage_[k] = 1;
      any = true;
      for (int j = 0; j < count; ++j) {
        const int i = offset[k] + j;
        const int old = row_offset_[from] + j;
        t[i] = t_[old];
        lambda[i] = lambda_[old];
        sigma[i] = sigma_[old];
        lambda_soft[i] = lambda_soft_[old];
      }
    }
    t_.swap(t);
    lambda_.swap(lambda);
    sigma_.swap(sigma);
    lambda_soft_.swap(lambda_soft);
  }
  has_solution_ = has_solution_ && any;
  stages_since_solution_ = 0;
  row_offset_.swap(offset);
}

void QpWorkspace::setup(const StructuredQp& qp) {
  const int stages = qp.steps() + 1;
  carry_solution(qp);
  const std::size_t rows = row_offset_.back();
  single_index_.assign(rows, -1);
  for (int k = 0; k < stages; ++k) {
    for (std::size_t j = 0; j < qp.stages[k].rows.size(); ++j) {
      const QpStageVector& g = qp.stages[k].rows[j].g;
      int nonzeros = 0;
      int last = -1;
      for (int i = 0; i < kQpStage; ++i) {
        if (g[i] != 0.0) {
          ++nonzeros;
          last = i;
        }
      }
      if (nonzeros == 1) single_index_[row_offset_[k] + j] = last;
    }
  }
  mark_control_boxes(qp);
  packed_.assign(rows, PackedRow{});
  for (auto* v : {&w_, &dw_, &grad_, &grad_base_, &dw_unit_})
    v->assign(stages, QpStageVector::Zero());
  hess_.assign(stages, QpStageMatrix::Zero());
  gain_.assign(stages, GainMatrix::Zero());
  kinematic_.assign(stages, KinematicDynamics{});
  is_kinematic_.assign(stages, 0);
  sbar_.assign(stages, GainMatrix::Zero());
  rbar_inverse_.assign(stages, Eigen::Matrix2d::Zero());
  costate_.assign(stages + 1, QpStateVector::Zero());
  feedforward_.assign(stages, Eigen::Vector2d::Zero());
  unit_feedforward_.assign(stages, Eigen::Vector2d::Zero());
  if (initial_controls_.size() != static_cast<std::size_t>(stages)) {
    initial_controls_.assign(stages, Eigen::Vector2d::Zero());
  }
  if (!has_solution_) {
    for (auto* v : {&t_, &lambda_, &sigma_, &lambda_soft_}) v->assign(rows, 0.0);
  }
  // carry_solution swaps these with their carried copies: each pair grows
  // together, so that no later swap brings a smaller one back.
  for (auto [own, carried] :
       {std::pair{&t_, &carried_t_}, std::pair{&lambda_, &carried_lambda_},
        std::pair{&sigma_, &carried_sigma_}, std::pair{&lambda_soft_, &carried_lambda_soft_}}) {
    carried->reserve(own->capacity());
    own->reserve(carried->capacity());
  }
  for (auto* v : {&dt_, &dlambda_, &dsigma_, &dlambda_soft_, &weight_, &offset_, &soft_q_, &dt_aff_,
                  &dlambda_aff_, &dsigma_aff_, &dlambda_soft_aff_, &a_, &inverse_t_,
                  &inverse_sigma_, &inverse_a_plus_b_, &residual_}) {
    v->assign(rows, 0.0);
  }
}

void QpWorkspace::reserve(std::size_t rows) {
  single_index_.reserve(rows);
  control_box_.reserve(rows);
  packed_.reserve(rows);
  for (auto* v : {&t_,
                  &lambda_,
                  &sigma_,
                  &lambda_soft_,
                  &carried_t_,
                  &carried_lambda_,
                  &carried_sigma_,
                  &carried_lambda_soft_,
                  &dt_,
                  &dlambda_,
                  &dsigma_,
                  &dlambda_soft_,
                  &weight_,
                  &offset_,
                  &soft_q_,
                  &dt_aff_,
                  &dlambda_aff_,
                  &dsigma_aff_,
                  &dlambda_soft_aff_,
                  &a_,
                  &inverse_t_,
                  &inverse_sigma_,
                  &inverse_a_plus_b_,
                  &residual_}) {
    v->reserve(rows);
  }
}

void QpWorkspace::mark_control_boxes(const StructuredQp& qp) {
  const int stages = qp.steps() + 1;
  constexpr double kNone = std::numeric_limits<double>::infinity();
  control_box_.assign(row_offset_.back(), false);
  control_lower_.assign(stages, Eigen::Vector2d::Constant(-kNone));
  control_upper_.assign(stages, Eigen::Vector2d::Constant(kNone));
  for (int k = 0; k < stages; ++k) {
    for (std::size_t j = 0; j < qp.stages[k].rows.size(); ++j) {
      const QpRow& row = qp.stages[k].rows[j];
      const int i = row_offset_[k] + static_cast<int>(j);
      const int index = single_index_[i];
      if (row.soft || index < kQpStates) continue;
      control_box_[i] = true;
      const int c = index - kQpStates;
      const double limit = row.d / row.g[index];
      if (row.g[index] > 0.0) control_upper_[k][c] = std::min(control_upper_[k][c], limit);
      if (row.g[index] < 0.0) control_lower_[k][c] = std::max(control_lower_[k][c], limit);
    }
  }
}

void QpWorkspace::set_initial_controls(const std::vector<Eigen::Vector2d>& controls) {
  initial_controls_.assign(controls.begin(), controls.end());
  initial_controls_.resize(controls.size() + 1, Eigen::Vector2d::Zero());
}

// Cholesky factor L (lower) of M's leading Size x Size block, with each
// pivot raised by floor * (1 + |M_ii|); false if a pivot is still not
// positive. Written out for the fixed stage size: Eigen's LLT runs its blocked
// path, made for large matrices, and took an eighth of the solve time on 7 x 7
// ones.
constexpr double kFirstPivotFloor = 1e-12;

template <int Size, class Factor>
bool floored_cholesky(const QpStageMatrix& M, double floor, Factor& L) {
  for (int j = 0; j < Size; ++j) {
    double pivot = M(j, j) + floor * (1.0 + std::abs(M(j, j)));
    for (int k = 0; k < j; ++k) pivot -= L(j, k) * L(j, k);
    if (!(pivot > 0.0)) return false;
    const double diagonal = std::sqrt(pivot);
    const double inverse = 1.0 / diagonal;
    L(j, j) = diagonal;
    for (int i = j + 1; i < Size; ++i) {
      double entry = M(i, j);
      for (int k = 0; k < j; ++k) entry -= L(i, k) * L(j, k);
      L(i, j) = entry * inverse;
    }
    for (int i = 0; i < j; ++i) L(i, j) = 0.0;
  }
  return true;
}

// min of g d + 0.5 q d^2 over lo <= v + d <= hi (q >= 0): the most that one
// control can still lower a convex function with that slope and curvature.
double least_change(double g, double q, double v, double lo, double hi) {
  if (g == 0.0) return 0.0;
  const double room = g > 0.0 ? lo - v : hi - v;  // towards descent
  if (!std::isfinite(room))
    return q > 0.0 ? -0.5 * g * g / q : -std::numeric_limits<double>::infinity();
  const double d = q > 0.0 ? (g > 0.0 ? std::max(-g / q, room) : std::min(-g / q, room)) : room;
  return g * d + 0.5 * q * d * d;
}

// The steps of the method, over the workspace's vectors. Rows are
//   hard: g'w + t = d,            t >= 0, lambda >= 0, lambda t = mu
//   soft: g'w - sigma + t = d,    also sigma >= 0, rho - lambda - lambda_soft = 0,
//                                 lambda_soft sigma = mu
// and each Newton step eliminates t, sigma and the multipliers row by row,
// leaving an LQ problem in w that the Riccati recursion solves.
constexpr double kInfinityResidual = 1e300;

struct InteriorPointMethod {
  const StructuredQp& qp;
  QpWorkspace& ws;
  const QpSettings& settings;
  int n = qp.steps();
  int total_rows = ws.row_offset_.back();

  // One flat loop over the rows as initialize() packed them
  // (QpWorkspace::PackedRow): a loop per stage over the problem's 72-byte
  // rows takes about 10% more per plan (bench_expert).
  template <class F>
  void for_each_row(F&& f) {
    for (int i = 0; i < total_rows; ++i) f(ws.packed_[i].stage, ws.packed_[i], i);
  }

  void initialize() {
    for (int k = 0; k <= n; ++k) {
      const auto& rows = qp.stages[k].rows;
      for (std::size_t j = 0; j < rows.size(); ++j) {
        const int i = ws.row_offset_[k] + static_cast<int>(j);
        const int single = ws.single_index_[i];
        ws.packed_[i] = {&rows[j].g, rows[j].d, single >= 0 ? rows[j].g[single] : 0.0,
                         single,     k,         rows[j].soft};
      }
    }
    for (int k = 0; k < n; ++k) {
      const QpStage& st = qp.stages[k];
      ws.is_kinematic_[k] =
          settings.kinematic_sparsity && kinematic_form(st.A, st.B, ws.kinematic_[k]) ? 1 : 0;
    }
    ws.w_[0].head<kQpStates>() = qp.initial_state;
    ws.terminal_multiplier_ = 0.0;
    for (int k = 0; k <= n; ++k) {
      if (k < n) ws.w_[k].tail<kQpControls>() = ws.initial_controls_[k];
      if (k == n) ws.w_[k].tail<kQpControls>().setZero();
      if (k < n) {
        const QpStage& st = qp.stages[k];
        ws.w_[k + 1].head<kQpStates>() = times_a(k, ws.w_[k].head<kQpStates>()) +
                                         times_b(k, ws.w_[k].tail<kQpControls>()) + st.c;
      }
    }
    // A warm start takes the stages whose rows the last solution has
    // (QpWorkspace::carry_solution). The others start centred, at the warm
    // rows' mean complementarity: centred at the cold start's, one stage
    // would hold the whole method back to a cold start's pace.
    const bool warm = settings.warm_start && ws.has_solution_;
    double products = 0.0;
    int warm_rows = 0;
    if (warm) {
      for_each_row([&](int k, const QpWorkspace::PackedRow& row, int i) {
        if (ws.warm_stage_[k] == 0) return;
        warm_row(row, i, row.d - row_dot(row, ws.w_[k]));
        products += ws.lambda_[i] * ws.t_[i];
        ++warm_rows;
      });
    }
    const double mu0 = warm_rows > 0 ? products / warm_rows : settings.initial_complementarity;
    for_each_row([&](int k, const QpWorkspace::PackedRow& row, int i) {
      if (warm && ws.warm_stage_[k] != 0) return;
      centred_row(row, i, row.d - row_dot(row, ws.w_[k]), mu0);
    });
  }

  // The row starts centred, with lambda t (and a soft row's lambda_soft
  // sigma) at mu0 (settings.initial_complementarity cold), its slacks at least 1 from
  // their bounds, and a soft row on rho = lambda + lambda_soft (a residual
  // there would swamp the Newton step with forces of the size of rho). A
  // start with lambda = 1 everywhere and a violated soft row's t at 1e-2
  // took steps of 1e-4 for the first five to eight iterations, until the
  // products had evened out.
  void centred_row(const QpWorkspace::PackedRow& row, int i, double room, double mu0) {
    if (!row.soft) {
      ws.t_[i] = std::max(room, 1.0);
      ws.lambda_[i] = mu0 / ws.t_[i];
      return;
    }
    const double violation = std::max(-room, 0.0);
    ws.lambda_[i] = std::min(mu0 / std::max(room + violation, 1.0), 0.5 * qp.softness_weight);
    ws.lambda_soft_[i] = qp.softness_weight - ws.lambda_[i];
    ws.sigma_[i] = violation + mu0 / ws.lambda_soft_[i];
    ws.t_[i] = std::max(room + ws.sigma_[i], 1.0);
  }

  // The last solution's multipliers and slacks, each pushed at least
  // warm_start_floor off its bound: a point that close to the boundary
  // would block the first steps.
  void warm_row(const QpWorkspace::PackedRow& row, int i, double room) {
    const double floor = settings.warm_start_floor;
    if (!row.soft) {
      ws.t_[i] = std::max(room, floor);
      ws.lambda_[i] = std::max(ws.lambda_[i], floor);
      return;
    }
    ws.lambda_[i] = std::clamp(ws.lambda_[i], floor, qp.softness_weight - floor);
    ws.lambda_soft_[i] = qp.softness_weight - ws.lambda_[i];
    ws.sigma_[i] = std::max(-room, 0.0) + floor * floor / ws.lambda_soft_[i];
    ws.t_[i] = std::max(room + ws.sigma_[i], floor);
  }

  // g' v for a row, cheap for the bound rows that have one nonzero.
  [[nodiscard]] static double row_dot(const QpWorkspace::PackedRow& row, const QpStageVector& v) {
    return row.single >= 0 ? row.coefficient * v[row.single] : row.g->dot(v);
  }

  static void add_row_times(const QpWorkspace::PackedRow& row, double scale, QpStageVector& out) {
    if (row.single >= 0) {
      out[row.single] += row.coefficient * scale;
    } else {
      out += *row.g * scale;
    }
  }

  [[nodiscard]] double primal_residual(const QpWorkspace::PackedRow& row, int k, int i) const {
    const double r = row_dot(row, ws.w_[k]) + ws.t_[i] - row.d;
    return row.soft ? r - ws.sigma_[i] : r;
  }

  struct Measures {
    double mu = 0.0;         ///< mean complementarity product
    double primal = 0.0;     ///< largest row and terminal residual
    double objective = 0.0;  ///< of the stage costs at the iterate
  };

  // One pass over the rows for the iteration's measures and the gradient of
  // the Lagrangian without the dynamics, H w + h + sum g lambda (the predictor
  // and the corrector start from it).
  [[nodiscard]] Measures measure_and_gradient() {
    Measures m;
    // The objective comes with the gradient: 0.5 w'Hw + h'w = 0.5 w'(Hw + h) + 0.5 h'w.
    for (int k = 0; k <= n; ++k) {
      ws.grad_base_[k] = qp.stages[k].H * ws.w_[k] + qp.stages[k].h;
      m.objective += 0.5 * (ws.w_[k].dot(ws.grad_base_[k]) + qp.stages[k].h.dot(ws.w_[k]));
    }
    if (qp.has_terminal_equality) ws.grad_base_[n] += qp.terminal_g * ws.terminal_multiplier_;
    m.primal =
        qp.has_terminal_equality ? std::abs(qp.terminal_g.dot(ws.w_[n]) - qp.terminal_d) : 0.0;
    double sum = 0.0;
    int count = 0;
    for_each_row([&](int k, const QpWorkspace::PackedRow& row, int i) {
      add_row_times(row, ws.lambda_[i], ws.grad_base_[k]);
      sum += ws.lambda_[i] * ws.t_[i];
      ++count;
      ws.residual_[i] = primal_residual(row, k, i);
      m.primal = std::max(m.primal, std::abs(ws.residual_[i]));
      if (row.soft) {
        sum += ws.lambda_soft_[i] * ws.sigma_[i];
        ++count;
        m.primal =
            std::max(m.primal, std::abs(qp.softness_weight - ws.lambda_[i] - ws.lambda_soft_[i]) /
                                   qp.softness_weight);
      }
    });
    m.mu = count > 0 ? sum / count : 0.0;
    return m;
  }

  // The costates that make the state part of stationarity hold; what is
  // left over in the control part is the dual residual.
  // Needs measure_and_gradient() first.
  [[nodiscard]] double dual_residual() {
    auto& nu = ws.costate_;
    nu[n] = -ws.grad_base_[n].head<kQpStates>();
    double worst = 0.0;
    for (int k = n - 1; k >= 0; --k) {
      const Eigen::Vector2d r = ws.grad_base_[k].tail<kQpControls>() - b_times(k, nu[k + 1]);
      worst = std::max(worst, r.cwiseAbs().maxCoeff());
      nu[k] = -ws.grad_base_[k].head<kQpStates>() + a_times(k, nu[k + 1]);
    }
    return worst;
  }

  // A lower bound on the optimum from the current multipliers. Every row
  // but the hard control bounds is dualized (soft rows with lambda capped at
  // the softness price, so the slack drops out); what is left is a convex
  // function L of the controls over their box, with curvature at least the
  // stages' control_curvature D. So for any u in the box
  //   L(u) >= L(v) + g'(u - v) + 0.5 (u - v)' D (u - v),   g = dL/du at v,
  // and the right side splits into one-dimensional minimizations. g comes
  // from one adjoint pass; near a solution it is the dual residual and the
  // bound closes on the optimum, and a node far above the cutoff shows it
  // long before the method converges.
  // Needs measure_and_gradient() first; `f` is objective() at this iterate.
  [[nodiscard]] double dual_bound(double f) {
    // From the Lagrangian's gradient, which holds every row: take out the
    // rows that stay constraints, and the part of a soft row's multiplier
    // above the price.
    auto& gradient = ws.grad_;  // scratch: the Newton steps overwrite it
    gradient = ws.grad_base_;
    double lagrangian = f;
    if (qp.has_terminal_equality) {
      lagrangian += ws.terminal_multiplier_ * (qp.terminal_g.dot(ws.w_[n]) - qp.terminal_d);
    }
    for_each_row([&](int k, const QpWorkspace::PackedRow& row, int i) {
      if (ws.control_box_[i]) {
        add_row_times(row, -ws.lambda_[i], gradient[k]);
        return;
      }
      const double lambda = row.soft ? std::min(ws.lambda_[i], qp.softness_weight) : ws.lambda_[i];
      if (lambda != ws.lambda_[i]) add_row_times(row, lambda - ws.lambda_[i], gradient[k]);
      lagrangian += lambda * (row_dot(row, ws.w_[k]) - row.d);
    });
    QpStateVector adjoint = gradient[n].head<kQpStates>();
    double bound = lagrangian;
    for (int k = n - 1; k >= 0; --k) {
      const QpStage& st = qp.stages[k];
      const Eigen::Vector2d slope = gradient[k].tail<kQpControls>() + b_times(k, adjoint);
      for (int c = 0; c < kQpControls; ++c) {
        bound += least_change(slope[c], st.control_curvature[c], ws.w_[k][kQpStates + c],
                              ws.control_lower_[k][c], ws.control_upper_[k][c]);
      }
      adjoint = gradient[k].head<kQpStates>() + a_times(k, adjoint);
    }
    return std::isnan(bound) ? -kInfinityResidual : bound;
  }

  // Row weights of the eliminated Newton system (the same for predictor and
  // corrector), and the quotients that the two Newton steps share: divisions
  // were a large part of the per-row work.
  void row_weights() {
    for (int k = 0; k <= n; ++k) ws.hess_[k] = qp.stages[k].H;
    for_each_row([&](int k, const QpWorkspace::PackedRow& row, int i) {
      ws.inverse_t_[i] = 1.0 / ws.t_[i];
      const double a = ws.lambda_[i] * ws.inverse_t_[i];
      ws.a_[i] = a;
      double weight = a;
      if (row.soft) {
        ws.inverse_sigma_[i] = 1.0 / ws.sigma_[i];
        const double b = ws.lambda_soft_[i] * ws.inverse_sigma_[i];
        ws.inverse_a_plus_b_[i] = 1.0 / (a + b);
        weight = a * b * ws.inverse_a_plus_b_[i];
      }
      ws.weight_[i] = weight;
      if (row.single >= 0) {
        ws.hess_[k](row.single, row.single) += weight * row.coefficient * row.coefficient;
      } else {
        ws.hess_[k].noalias() += weight * *row.g * row.g->transpose();
      }
    });
  }

  // Right-hand sides for complementarity targets c4 (lambda t) and c5
  // (lambda_soft sigma), given per row by the callables.
  template <class C4, class C5>
  void newton_gradient(C4&& c4_of, C5&& c5_of) {
    for (int k = 0; k <= n; ++k) ws.grad_[k] = ws.grad_base_[k];
    for_each_row([&](int k, const QpWorkspace::PackedRow& row, int i) {
      const double r1 = ws.residual_[i];
      const double a = ws.a_[i];
      double e = c4_of(i) * ws.inverse_t_[i] + a * r1;
      if (row.soft) {
        const double r3 = qp.softness_weight - ws.lambda_[i] - ws.lambda_soft_[i];
        const double q = e + c5_of(i) * ws.inverse_sigma_[i] - r3;
        ws.soft_q_[i] = q;
        e -= a * q * ws.inverse_a_plus_b_[i];
      }
      ws.offset_[i] = e;
      add_row_times(row, e, ws.grad_[k]);
    });
  }

  // Riccati backward pass. Each stage matrix
  //   M = [R S; S' Q] + [B A]' P [B A]   (controls first)
  // gives the gain K = -R~^-1 S~ from its control block, and the next P.
  // The Schur form takes P = Q~ + S~' K, the Schur complement of that 2 x 2
  // block (inverted in closed form); the square-root form factors all of M and takes
  // P = L22 L22', positive semidefinite by construction. The Schur form can
  // lose that to cancellation once the barrier weights grow large, which
  // shows as an indefinite control block further back: that iteration is
  // then factored again in square-root form.
  [[nodiscard]] bool factorize() {
    if (settings.riccati == RiccatiForm::Schur && riccati_pass(RiccatiForm::Schur)) return true;
    return riccati_pass(RiccatiForm::SquareRoot);
  }

  [[nodiscard]] bool riccati_pass(RiccatiForm form) {
    StateMatrix P = ws.hess_[n].topLeftCorner<kQpStates, kQpStates>();
    P = 0.5 * (P + P.transpose());
    QpStageMatrix M;
    for (int k = n - 1; k >= 0; --k) {
      stage_matrix(k, P, M);
      const bool factored =
          form == RiccatiForm::Schur ? schur_step(k, M, P) : square_root_step(k, M, P);
      if (!factored) return false;
    }
    return true;
  }

  void stage_matrix(int k, const StateMatrix& P, QpStageMatrix& M) const {
    if (ws.is_kinematic_[k] != 0) {
      kinematic_stage_matrix(k, P, M);
      return;
    }
    const QpStage& st = qp.stages[k];
    const auto& H = ws.hess_[k];
    const Eigen::Matrix<double, kQpStates, kQpControls> PB = P * st.B;
    const StateMatrix PA = P * st.A;
    M.topLeftCorner<kQpControls, kQpControls>() =
        H.bottomRightCorner<kQpControls, kQpControls>() + st.B.transpose() * PB;
    M.topRightCorner<kQpControls, kQpStates>() =
        H.bottomLeftCorner<kQpControls, kQpStates>() + PB.transpose() * st.A;
    M.bottomLeftCorner<kQpStates, kQpControls>() =
        M.topRightCorner<kQpControls, kQpStates>().transpose();
    M.bottomRightCorner<kQpStates, kQpStates>() =
        H.topLeftCorner<kQpStates, kQpStates>() + st.A.transpose() * PA;
  }

  // M of a kinematic stage, from the nonzeros alone (see KinematicDynamics).
  void kinematic_stage_matrix(int k, const StateMatrix& P, QpStageMatrix& M) const {
    const KinematicDynamics& d = ws.kinematic_[k];
    const auto& H = ws.hess_[k];
    Eigen::Matrix<double, kQpStates, kQpControls> PB;
    PB.col(0) = d.x_a * P.col(0) + d.y_a * P.col(1) + d.v_a * P.col(2) + d.memory_a * P.col(4);
    PB.col(1) = d.x_omega * P.col(0) + d.y_omega * P.col(1) + d.theta_omega * P.col(3);
    StateMatrix PA;
    PA.col(0) = P.col(0);
    PA.col(1) = P.col(1);
    PA.col(2) = P.col(2) + d.x_v * P.col(0) + d.y_v * P.col(1);
    PA.col(3) = P.col(3) + d.x_theta * P.col(0) + d.y_theta * P.col(1);
    PA.col(4).setZero();
    for (int c = 0; c < kQpControls; ++c) {
      M.block<kQpControls, 1>(0, c) =
          H.block<kQpControls, 1>(kQpStates, kQpStates + c) + b_times(k, PB.col(c));
      M.block<1, kQpStates>(c, kQpControls) =
          H.block<1, kQpStates>(kQpStates + c, 0) + a_times(k, PB.col(c)).transpose();
    }
    M.bottomLeftCorner<kQpStates, kQpControls>() =
        M.topRightCorner<kQpControls, kQpStates>().transpose();
    for (int j = 0; j < kQpStates; ++j) {
      M.block<kQpStates, 1>(kQpControls, kQpControls + j) =
          H.block<kQpStates, 1>(0, j) + a_times(k, PA.col(j));
    }
  }

  // Products with a stage's A and B, their transposes, sparse where the
  // stage is kinematic.
  [[nodiscard]] QpStateVector times_a(int k, const QpStateVector& v) const {
    if (ws.is_kinematic_[k] == 0) return qp.stages[k].A * v;
    const KinematicDynamics& d = ws.kinematic_[k];
    QpStateVector out;
    out << v[0] + d.x_v * v[2] + d.x_theta * v[3], v[1] + d.y_v * v[2] + d.y_theta * v[3], v[2],
        v[3], 0.0;
    return out;
  }
  [[nodiscard]] QpStateVector times_b(int k, const Eigen::Vector2d& u) const {
    if (ws.is_kinematic_[k] == 0) return qp.stages[k].B * u;
    const KinematicDynamics& d = ws.kinematic_[k];
    QpStateVector out;
    out << d.x_a * u[0] + d.x_omega * u[1], d.y_a * u[0] + d.y_omega * u[1], d.v_a * u[0],
        d.theta_omega * u[1], d.memory_a * u[0];
    return out;
  }
  [[nodiscard]] QpStateVector a_times(int k, const QpStateVector& v) const {
    if (ws.is_kinematic_[k] == 0) return qp.stages[k].A.transpose() * v;
    const KinematicDynamics& d = ws.kinematic_[k];
    QpStateVector out;
    out << v[0], v[1], v[2] + d.x_v * v[0] + d.y_v * v[1],
        v[3] + d.x_theta * v[0] + d.y_theta * v[1], 0.0;
    return out;
  }
  [[nodiscard]] Eigen::Vector2d b_times(int k, const QpStateVector& v) const {
    if (ws.is_kinematic_[k] == 0) return qp.stages[k].B.transpose() * v;
    const KinematicDynamics& d = ws.kinematic_[k];
    return {d.x_a * v[0] + d.y_a * v[1] + d.v_a * v[2] + d.memory_a * v[4],
            d.x_omega * v[0] + d.y_omega * v[1] + d.theta_omega * v[3]};
  }

  // The stage's gain from L11; returns L11^-1.
  Eigen::Matrix2d store_gain(int k, const QpStageMatrix& M, const Eigen::Matrix2d& L11) {
    Eigen::Matrix2d L11_inverse;
    L11_inverse << 1.0 / L11(0, 0), 0.0, -L11(1, 0) / (L11(0, 0) * L11(1, 1)), 1.0 / L11(1, 1);
    ws.rbar_inverse_[k] = L11_inverse.transpose() * L11_inverse;
    ws.sbar_[k] = M.topRightCorner<kQpControls, kQpStates>();
    ws.gain_[k] = -ws.rbar_inverse_[k] * ws.sbar_[k];
    return L11_inverse;
  }

  // The control block's inverse in closed form, with the pivots the
  // floored Cholesky factor would have (floor on each diagonal entry): one
  // division on the stage's chain where the factor took two roots and three.
  bool schur_step(int k, const QpStageMatrix& M, StateMatrix& P) {
    const double a = M(0, 0) + kFirstPivotFloor * (1.0 + std::abs(M(0, 0)));
    const double c = M(1, 1) + kFirstPivotFloor * (1.0 + std::abs(M(1, 1)));
    const double b = M(1, 0);
    const double determinant = a * c - b * b;
    if (!(a > 0.0) || !(determinant > 0.0)) return false;
    const double inverse = 1.0 / determinant;
    Eigen::Matrix2d& r_inverse = ws.rbar_inverse_[k];
    r_inverse << c * inverse, -b * inverse, -b * inverse, a * inverse;
    ws.sbar_[k] = M.topRightCorner<kQpControls, kQpStates>();
    ws.gain_[k].noalias() = -r_inverse * ws.sbar_[k];
    P.noalias() =
        M.bottomRightCorner<kQpStates, kQpStates>() + ws.sbar_[k].transpose() * ws.gain_[k];
    P = 0.5 * (P + P.transpose()).eval();
    return true;
  }

  bool square_root_step(int k, const QpStageMatrix& M, StateMatrix& P) {
    // States without cost or rows (x in a relaxation, say) leave M
    // singular; a floor on each pivot, relative to its own size so that
    // the tiny entries are not swamped by the huge barrier weights,
    // keeps Cholesky going without changing the step measurably.
    QpStageMatrix L;
    bool factored = false;
    for (double floor = kFirstPivotFloor; floor <= 1e-2 && !factored; floor *= 100.0) {
      factored = floored_cholesky<kQpStage>(M, floor, L);
    }
    if (!factored) return false;
    store_gain(k, M, L.topLeftCorner<kQpControls, kQpControls>());
    const StateMatrix L22 = L.bottomRightCorner<kQpStates, kQpStates>();
    P.noalias() = L22 * L22.transpose();
    return true;
  }

  // The LQ solve with the stored factorization: out = K^-1 (-gradient) on
  // the space of trajectories with homogeneous dynamics and s_0 fixed. With
  // `unit`, also the response to a unit force on the terminal equality,
  // which the Schur complement of that one row needs: the two recursions are
  // independent chains, and one loop over the stages overlaps them.
  void back_substitute(const std::vector<QpStageVector>& gradient, std::vector<QpStageVector>& out,
                       std::vector<QpStageVector>* unit = nullptr) {
    QpStateVector p = gradient[n].head<kQpStates>();
    QpStateVector q = qp.terminal_g.head<kQpStates>();
    for (int k = n - 1; k >= 0; --k) {
      const Eigen::Vector2d rbar = gradient[k].tail<kQpControls>() + b_times(k, p);
      ws.feedforward_[k] = -ws.rbar_inverse_[k] * rbar;
      p = gradient[k].head<kQpStates>() + a_times(k, p) +
          ws.sbar_[k].transpose() * ws.feedforward_[k];
      if (unit != nullptr) {
        ws.unit_feedforward_[k] = -ws.rbar_inverse_[k] * b_times(k, q);
        q = a_times(k, q) + ws.sbar_[k].transpose() * ws.unit_feedforward_[k];
      }
    }
    QpStateVector ds = QpStateVector::Zero();
    QpStateVector dq = QpStateVector::Zero();
    for (int k = 0; k < n; ++k) {
      const Eigen::Vector2d du = ws.gain_[k] * ds + ws.feedforward_[k];
      out[k].head<kQpStates>() = ds;
      out[k].tail<kQpControls>() = du;
      ds = times_a(k, ds) + times_b(k, du);
      if (unit != nullptr) {
        const Eigen::Vector2d dv = ws.gain_[k] * dq + ws.unit_feedforward_[k];
        (*unit)[k].head<kQpStates>() = dq;
        (*unit)[k].tail<kQpControls>() = dv;
        dq = times_a(k, dq) + times_b(k, dv);
      }
    }
    out[n].head<kQpStates>() = ds;
    out[n].tail<kQpControls>().setZero();
    if (unit != nullptr) {
      (*unit)[n].head<kQpStates>() = dq;
      (*unit)[n].tail<kQpControls>().setZero();
    }
  }

  // The Newton step for the current gradient (newton_gradient), then the
  // eliminated row variables.
  // Returns the largest step in (0, 1] that keeps every positive variable
  // positive (in the same pass over the rows).
  // `with_unit`: the first step after a factorization, which also finds the
  // terminal equality's response.
  [[nodiscard]] double solve_step(bool with_unit = false) {
    back_substitute(ws.grad_, ws.dw_,
                    with_unit && qp.has_terminal_equality ? &ws.dw_unit_ : nullptr);
    if (qp.has_terminal_equality) {
      // dw = dw_free + step * dw_unit, with step chosen so the equality holds after a full step.
      const double residual = qp.terminal_d - qp.terminal_g.dot(ws.w_[n]);
      const double response = qp.terminal_g.dot(ws.dw_unit_[n]);
      ws.terminal_step_ = (residual - qp.terminal_g.dot(ws.dw_[n])) / response;
      for (int k = 0; k <= n; ++k) ws.dw_[k] += ws.terminal_step_ * ws.dw_unit_[k];
    }
    double alpha = 1.0;
    // Divide only where the step would cross the bound: a division per
    // row and variable was a tenth of the iteration.
    auto limit = [&alpha](double value, double change) {
      if (value + alpha * change < 0.0) alpha = std::min(alpha, -value / change);
    };
    for_each_row([&](int k, const QpWorkspace::PackedRow& row, int i) {
      const double gd = row_dot(row, ws.dw_[k]);
      const double r1 = ws.residual_[i];
      ws.dlambda_[i] = ws.weight_[i] * gd + ws.offset_[i];
      if (row.soft) {
        ws.dsigma_[i] = (ws.soft_q_[i] + ws.a_[i] * gd) * ws.inverse_a_plus_b_[i];
        ws.dt_[i] = -r1 - gd + ws.dsigma_[i];
        const double r3 = qp.softness_weight - ws.lambda_[i] - ws.lambda_soft_[i];
        ws.dlambda_soft_[i] = r3 - ws.dlambda_[i];
        limit(ws.sigma_[i], ws.dsigma_[i]);
        limit(ws.lambda_soft_[i], ws.dlambda_soft_[i]);
      } else {
        ws.dt_[i] = -r1 - gd;
      }
      limit(ws.t_[i], ws.dt_[i]);
      limit(ws.lambda_[i], ws.dlambda_[i]);
    });
    return alpha;
  }

  [[nodiscard]] double complementarity_after(double alpha) {
    double sum = 0.0;
    int count = 0;
    for_each_row([&](int, const QpWorkspace::PackedRow& row, int i) {
      sum += (ws.lambda_[i] + alpha * ws.dlambda_[i]) * (ws.t_[i] + alpha * ws.dt_[i]);
      ++count;
      if (row.soft) {
        sum += (ws.lambda_soft_[i] + alpha * ws.dlambda_soft_[i]) *
               (ws.sigma_[i] + alpha * ws.dsigma_[i]);
        ++count;
      }
    });
    return count > 0 ? sum / count : 0.0;
  }

  void take_step(double alpha) {
    for (int k = 0; k <= n; ++k) ws.w_[k] += alpha * ws.dw_[k];
    ws.terminal_multiplier_ += alpha * ws.terminal_step_;
    for_each_row([&](int, const QpWorkspace::PackedRow& row, int i) {
      ws.t_[i] += alpha * ws.dt_[i];
      ws.lambda_[i] += alpha * ws.dlambda_[i];
      if (row.soft) {
        ws.sigma_[i] += alpha * ws.dsigma_[i];
        ws.lambda_soft_[i] += alpha * ws.dlambda_soft_[i];
      }
    });
  }

  [[nodiscard]] double objective() const {
    double f = 0.0;
    for (int k = 0; k <= n; ++k) {
      f += 0.5 * ws.w_[k].dot(qp.stages[k].H * ws.w_[k]) + qp.stages[k].h.dot(ws.w_[k]);
    }
    return f;
  }

  [[nodiscard]] double max_softness() {
    double worst = 0.0;
    for_each_row([&](int, const QpWorkspace::PackedRow& row, int i) {
      if (row.soft) worst = std::max(worst, ws.sigma_[i]);
    });
    return worst;
  }

  QpResult run() {
    QpResult result;
    initialize();
    double previous_objective = kInfinityResidual;
    for (int iteration = 0; iteration < settings.max_iterations; ++iteration) {
      result.iterations = iteration;
      const auto [mu, primal, f] = measure_and_gradient();
      // The dual residual costs a pass of its own: only look once the rest is small.
      const double dual = (mu <= settings.tolerance && primal <= settings.primal_tolerance)
                              ? dual_residual()
                              : kInfinityResidual;
      // Near the end the multipliers of active rows come from Newton steps
      // scaled by barrier weights of 1e12 and more, so the dual residual can
      // stall at 1e-2 while the primal point and its objective no longer move
      // (to 1e-12): that point is the solution.
      if (settings.objective_cutoff < kInfinityResidual && iteration > 0) {
        result.lower_bound = std::max(result.lower_bound, dual_bound(f));
        if (result.lower_bound >= settings.objective_cutoff) {
          result.status = QpStatus::Cutoff;
          return result;
        }
      }
      if (f < settings.coarse_below && mu <= settings.coarse_tolerance &&
          primal <= settings.coarse_tolerance && max_softness() <= settings.coarse_tolerance) {
        result.status = QpStatus::Coarse;
        result.objective = f;
        return result;
      }
      const bool settled = std::abs(f - previous_objective) <= 1e-12 * (1.0 + std::abs(f));
      previous_objective = f;
      if (mu <= settings.tolerance && primal <= settings.primal_tolerance &&
          (dual <= settings.dual_tolerance || settled)) {
        result.status = QpStatus::Optimal;
        break;
      }
      row_weights();
      if (!factorize()) return result;
      // Predictor: the affine-scaling direction.
      newton_gradient([&](int i) { return -ws.lambda_[i] * ws.t_[i]; },
                      [&](int i) { return -ws.lambda_soft_[i] * ws.sigma_[i]; });
      const double alpha_affine = solve_step(true);
      const double mu_affine = complementarity_after(alpha_affine);
      const double centering = std::pow(mu_affine / mu, 3);
      // Kept by swapping, not copying: the corrector's solve_step writes
      // every entry it reads again (the soft ones only for soft rows).
      std::swap(ws.dt_aff_, ws.dt_);
      std::swap(ws.dlambda_aff_, ws.dlambda_);
      std::swap(ws.dsigma_aff_, ws.dsigma_);
      std::swap(ws.dlambda_soft_aff_, ws.dlambda_soft_);
      // Corrector: aim at the centred point, with Mehrotra's second-order term.
      const double target = centering * mu;
      newton_gradient(
          [&](int i) {
            return target - ws.lambda_[i] * ws.t_[i] - ws.dlambda_aff_[i] * ws.dt_aff_[i];
          },
          [&](int i) {
            return target - ws.lambda_soft_[i] * ws.sigma_[i] -
                   ws.dlambda_soft_aff_[i] * ws.dsigma_aff_[i];
          });
      const double alpha = std::min(1.0, 0.995 * solve_step());
      take_step(alpha);
      result.iterations = iteration + 1;
      result.status = QpStatus::IterationLimit;
    }
    if (result.status == QpStatus::Optimal || result.status == QpStatus::IterationLimit) {
      result.max_softness = max_softness();
      result.objective = objective();
      // A QP whose rows still need slack after the iteration limit is
      // infeasible in all but name: the penalty keeps pushing sigma to zero.
      const double limit = result.status == QpStatus::Optimal ? settings.softness_tolerance
                                                              : settings.stalled_softness;
      if (result.max_softness > limit) result.status = QpStatus::Infeasible;
    }
    for (int k = 0; k <= n; ++k) {
      if (!ws.w_[k].allFinite()) result.status = QpStatus::NumericalError;
    }
    ws.has_solution_ = result.status == QpStatus::Optimal;
    ws.stages_since_solution_ = 0;
    return result;
  }
};

QpResult solve_structured_qp(const StructuredQp& qp, QpWorkspace& ws, const QpSettings& settings) {
  return InteriorPointMethod{qp, ws, settings}.run();
}

}  // namespace lanechange::expert
