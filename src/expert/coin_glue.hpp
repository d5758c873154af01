#pragma once
// What the Bonmin reference (a Bonmin::TMINLP) and the enumeration check (an
// Ipopt::TNLP) both hand to COIN-OR for a QP with linear rows: sparse
// structure in triplets, bounds, a starting point, the objective's gradient
// and the rows. Internal to src/expert.
#include <Eigen/Core>
#include <Eigen/SparseCore>
#include <chrono>
#include <coin/IpOptionsList.hpp>
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

}  // namespace lanechange::expert::coin
