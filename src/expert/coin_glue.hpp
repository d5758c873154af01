#pragma once
// What the Bonmin reference (a Bonmin::TMINLP) and the enumeration check (an
// Ipopt::TNLP) both hand to COIN-OR for a QP with linear rows: sparse
// structure in triplets, bounds, a starting point, the objective's gradient
// and the rows. Internal to src/expert.
#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <chrono>
#include <coin/IpOptionsList.hpp>
#include <coin/IpTNLP.hpp>
#include <coin/IpTypes.hpp>
#include <string>
#include <vector>

namespace lanechange::expert::coin {

using Ipopt::Index;
using Ipopt::Number;

[[nodiscard]] double milliseconds_since(std::chrono::steady_clock::time_point start);

struct SparseTriplets {
  std::vector<Index> rows;
  std::vector<Index> cols;
  std::vector<Number> values;
  [[nodiscard]] Index size() const { return static_cast<Index>(values.size()); }
};

/// The nonzeros of `matrix`; of its lower triangle only if asked (a Hessian).
[[nodiscard]] SparseTriplets triplets_of(const Eigen::SparseMatrix<double>& matrix,
                                         bool lower_triangle_only);

/// Ipopt asks once for the structure (values == nullptr), then only for the
/// values, scaled here by `scale`.
bool write_triplets(const SparseTriplets& triplets, Number scale, Index* i_row, Index* j_col,
                    Number* values);

/// Throws std::invalid_argument naming an option that COIN-OR does not take.
void set_option(Ipopt::OptionsList& options, const std::string& name, const std::string& value);
void set_option(Ipopt::OptionsList& options, const std::string& name, double value);
void set_option(Ipopt::OptionsList& options, const std::string& name, int value);

/// A QP with linear rows as COIN-OR's callbacks see it (all references).
struct LinearRowsQp {
  const Eigen::SparseMatrix<double>& hessian;
  const Eigen::VectorXd& gradient;
  const Eigen::SparseMatrix<double>& constraints;
  const Eigen::VectorXd& col_lower;
  const Eigen::VectorXd& col_upper;
  const Eigen::VectorXd& row_lower;
  const Eigen::VectorXd& row_upper;

  void bounds(Index n, Number* x_l, Number* x_u, Index m, Number* g_l, Number* g_u) const;
  /// The origin moved into the column bounds, with zero multipliers.
  void starting_point(Index n, bool init_x, Number* x, bool init_z, Number* z_l, Number* z_u,
                      Index m, bool init_lambda, Number* lambda) const;
  void objective_gradient(Index n, const Number* x, Number* grad_f) const;
  void rows(Index n, const Number* x, Index m, Number* g) const;
};

/// The callbacks that an Ipopt::TNLP (the enumeration check) and a
/// Bonmin::TMINLP (the reference) answer alike for a QP with linear rows:
/// sizes, bounds, starting point, gradient, rows, and the constant
/// Jacobian and Hessian. The derived class names its QP and its objective.
template <class Nlp>
class LinearRowsNlp : public Nlp {
 public:
  bool get_nlp_info(Index& n, Index& m, Index& nnz_jac_g, Index& nnz_h_lag,
                    Ipopt::TNLP::IndexStyleEnum& index_style) override {
    n = static_cast<Index>(qp().gradient.size());
    m = static_cast<Index>(qp().row_lower.size());
    nnz_jac_g = jacobian_.size();
    nnz_h_lag = hessian_lower_.size();
    index_style = Ipopt::TNLP::C_STYLE;
    return true;
  }

  bool get_bounds_info(Index n, Number* x_l, Number* x_u, Index m, Number* g_l,
                       Number* g_u) override {
    qp().bounds(n, x_l, x_u, m, g_l, g_u);
    return true;
  }

  bool get_starting_point(Index n, bool init_x, Number* x, bool init_z, Number* z_l, Number* z_u,
                          Index m, bool init_lambda, Number* lambda) override {
    qp().starting_point(n, init_x, x, init_z, z_l, z_u, m, init_lambda, lambda);
    return true;
  }

  bool eval_grad_f(Index n, const Number* x, bool, Number* grad_f) override {
    qp().objective_gradient(n, x, grad_f);
    return true;
  }

  bool eval_g(Index n, const Number* x, bool, Index m, Number* g) override {
    qp().rows(n, x, m, g);
    return true;
  }

  bool eval_jac_g(Index, const Number*, bool, Index, Index, Index* i_row, Index* j_col,
                  Number* values) override {
    return write_triplets(jacobian_, 1.0, i_row, j_col, values);
  }

  // The rows are linear, so the Lagrangian's Hessian is the objective's.
  bool eval_h(Index, const Number*, bool, Number obj_factor, Index, const Number*, bool, Index,
              Index* i_row, Index* j_col, Number* values) override {
    return write_triplets(hessian_lower_, obj_factor, i_row, j_col, values);
  }

 protected:
  LinearRowsNlp(const Eigen::SparseMatrix<double>& hessian,
                const Eigen::SparseMatrix<double>& constraints)
      : hessian_lower_(triplets_of(hessian, true)), jacobian_(triplets_of(constraints, false)) {}

  [[nodiscard]] virtual LinearRowsQp qp() const = 0;
  [[nodiscard]] const SparseTriplets& hessian_lower() const { return hessian_lower_; }

 private:
  SparseTriplets hessian_lower_;
  SparseTriplets jacobian_;
};

}  // namespace lanechange::expert::coin
