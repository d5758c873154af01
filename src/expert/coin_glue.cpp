#include "expert/coin_glue.hpp"

#include <algorithm>
#include <stdexcept>

namespace lanechange::expert::coin {

double milliseconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start)
      .count();
}

SparseTriplets triplets_of(const Eigen::SparseMatrix<double>& matrix, bool lower_triangle_only) {
  SparseTriplets triplets;
  for (int outer = 0; outer < matrix.outerSize(); ++outer) {
    for (Eigen::SparseMatrix<double>::InnerIterator it(matrix, outer); it; ++it) {
      if (lower_triangle_only && it.row() < it.col()) continue;
      triplets.rows.push_back(static_cast<Index>(it.row()));
      triplets.cols.push_back(static_cast<Index>(it.col()));
      triplets.values.push_back(it.value());
    }
  }
  return triplets;
}

bool write_triplets(const SparseTriplets& triplets, Number scale, Index* i_row, Index* j_col,
                    Number* values) {
  if (values == nullptr) {
    std::copy(triplets.rows.begin(), triplets.rows.end(), i_row);
    std::copy(triplets.cols.begin(), triplets.cols.end(), j_col);
  } else {
    for (Index e = 0; e < triplets.size(); ++e) values[e] = scale * triplets.values[e];
  }
  return true;
}

void set_option(Ipopt::OptionsList& options, const std::string& name, const std::string& value) {
  if (!options.SetStringValue(name, value)) throw std::invalid_argument("COIN-OR option " + name);
}
void set_option(Ipopt::OptionsList& options, const std::string& name, double value) {
  if (!options.SetNumericValue(name, value)) throw std::invalid_argument("COIN-OR option " + name);
}
void set_option(Ipopt::OptionsList& options, const std::string& name, int value) {
  if (!options.SetIntegerValue(name, value)) throw std::invalid_argument("COIN-OR option " + name);
}

void LinearRowsQp::bounds(Index n, Number* x_l, Number* x_u, Index m, Number* g_l,
                          Number* g_u) const {
  Eigen::Map<Eigen::VectorXd>(x_l, n) = col_lower;
  Eigen::Map<Eigen::VectorXd>(x_u, n) = col_upper;
  Eigen::Map<Eigen::VectorXd>(g_l, m) = row_lower;
  Eigen::Map<Eigen::VectorXd>(g_u, m) = row_upper;
}

void LinearRowsQp::starting_point(Index n, bool init_x, Number* x, bool init_z, Number* z_l,
                                  Number* z_u, Index m, bool init_lambda, Number* lambda) const {
  if (init_x) {
    Eigen::Map<Eigen::VectorXd>(x, n) =
        Eigen::VectorXd::Zero(n).cwiseMax(col_lower).cwiseMin(col_upper);
  }
  if (init_z) {
    std::fill_n(z_l, n, 0.0);
    std::fill_n(z_u, n, 0.0);
  }
  if (init_lambda) std::fill_n(lambda, m, 0.0);
}

void LinearRowsQp::objective_gradient(Index n, const Number* x, Number* grad_f) const {
  Eigen::Map<Eigen::VectorXd>(grad_f, n) =
      hessian * Eigen::Map<const Eigen::VectorXd>(x, n) + gradient;
}

void LinearRowsQp::rows(Index n, const Number* x, Index m, Number* g) const {
  Eigen::Map<Eigen::VectorXd>(g, m) = constraints * Eigen::Map<const Eigen::VectorXd>(x, n);
}

}  // namespace lanechange::expert::coin
