#include "baselines/mpc_problem.hpp"

#include <algorithm>
#include <cmath>

namespace lanechange::baselines {

namespace {

constexpr Number kInfinity = 2e19;  // Ipopt's default nlp_upper_bound_inf is 1e19
constexpr Index kX = 0;
constexpr Index kY = 1;
constexpr Index kV = 2;
constexpr Index kTheta = 3;
constexpr Index kStateSize = 4;

// The variables: node k's state at 4k..4k+3, then step k's (a, omega).
struct Layout {
  int steps = 0;
  [[nodiscard]] Index state(int k, Index component) const { return kStateSize * k + component; }
  [[nodiscard]] Index accel(int k) const { return kStateSize * (steps + 1) + 2 * k; }
  [[nodiscard]] Index omega(int k) const { return accel(k) + 1; }
  [[nodiscard]] Index size() const { return accel(steps); }
};

// The Hessian's lower triangle, in a fixed order: six entries per node
// (x x, y y, theta x, theta y, theta v, theta theta), then per step
// (a a, omega omega, a_{k+1} a_k; the last step has no neighbour).
struct HessianLayout {
  int steps = 0;
  enum NodeEntry : Index { kXX, kYY, kThetaX, kThetaY, kThetaV, kThetaTheta, kPerNode };
  [[nodiscard]] Index node(int k, NodeEntry e) const { return kPerNode * k + e; }
  [[nodiscard]] Index accel(int k) const { return kPerNode * (steps + 1) + 3 * k; }
  [[nodiscard]] Index omega(int k) const { return accel(k) + 1; }
  [[nodiscard]] Index jerk(int k) const { return accel(k) + 2; }
  [[nodiscard]] Index size() const { return accel(steps) - 1; }
};

constexpr Index kDynamicsJacobian = 18;  // nonzeros of a step's four rows
constexpr Index kPairJacobian = 3;       // x, y, theta of the node

// The squared distance of an ego circle (offset d along the heading) from a
// fixed centre, with its derivatives in (x, y, theta).
struct PairDistance {
  double dx, dy, value, d_theta;
};

PairDistance pair_distance(const Number* node, double offset, const CircleCentre& c) {
  const double s = std::sin(node[kTheta]);
  const double co = std::cos(node[kTheta]);
  const double dx = node[kX] + offset * co - c.x;
  const double dy = node[kY] + offset * s - c.y;
  return {dx, dy, dx * dx + dy * dy, 2.0 * offset * (dy * co - dx * s)};
}

}  // namespace

double clearance_violation(const MpcProblemData& data, const MpcPlan& plan,
                           const std::vector<std::vector<CircleCentre>>& centres) {
  double worst = 0.0;
  for (std::size_t k = 1; k < centres.size() && k < plan.states.size(); ++k) {
    const EgoState& z = plan.states[k];
    const Number node[] = {z.x, z.y, z.v, z.theta};
    for (const CircleCentre& c : centres[k]) {
      for (const double offset : data.ego_offsets) {
        worst = std::max(worst, c.clearance - std::sqrt(pair_distance(node, offset, c).value));
      }
    }
  }
  return worst;
}

Index MpcNlp::variables() const { return Layout{data_.steps}.size(); }

Index MpcNlp::pair_count() const {
  Index pairs = 0;
  for (const auto& node : data_.obstacles) pairs += static_cast<Index>(node.size());
  return pairs * static_cast<Index>(data_.ego_offsets.size());
}

Index MpcNlp::rows() const { return kStateSize * data_.steps + terminal_rows() + pair_count(); }

void MpcNlp::update(MpcProblemData data, MpcPlan guess) {
  data_ = std::move(data);
  data_.obstacles.resize(static_cast<std::size_t>(data_.steps) + 1);
  guess_ = std::move(guess);
  solution_ = guess_;
}

std::vector<Number> MpcNlp::pack(const MpcPlan& plan) const {
  const Layout at{data_.steps};
  std::vector<Number> x(static_cast<std::size_t>(at.size()));
  for (int k = 0; k <= data_.steps; ++k) {
    const EgoState& z = plan.states[static_cast<std::size_t>(k)];
    x[at.state(k, kX)] = z.x;
    x[at.state(k, kY)] = z.y;
    x[at.state(k, kV)] = z.v;
    x[at.state(k, kTheta)] = z.theta;
  }
  for (int k = 0; k < data_.steps; ++k) {
    x[at.accel(k)] = plan.controls[static_cast<std::size_t>(k)].a;
    x[at.omega(k)] = plan.controls[static_cast<std::size_t>(k)].omega;
  }
  return x;
}

MpcPlan MpcNlp::unpack(const Number* x) const {
  const Layout at{data_.steps};
  MpcPlan plan;
  for (int k = 0; k <= data_.steps; ++k) {
    const double a = k < data_.steps ? x[at.accel(k)] : 0.0;
    plan.states.push_back(
        {x[at.state(k, kX)], x[at.state(k, kY)], x[at.state(k, kV)], x[at.state(k, kTheta)], a});
  }
  for (int k = 0; k < data_.steps; ++k) plan.controls.push_back({x[at.accel(k)], x[at.omega(k)]});
  return plan;
}

bool MpcNlp::get_nlp_info(Index& n, Index& m, Index& nnz_jac_g, Index& nnz_h_lag,
                          IndexStyleEnum& index_style) {
  n = variables();
  m = rows();
  nnz_jac_g =
      kDynamicsJacobian * data_.steps + (data_.terminal_gap ? 3 : 0) + kPairJacobian * pair_count();
  nnz_h_lag = HessianLayout{data_.steps}.size();
  index_style = C_STYLE;
  return true;
}

bool MpcNlp::get_bounds_info(Index n, Number* x_l, Number* x_u, Index m, Number* g_l, Number* g_u) {
  const Layout at{data_.steps};
  std::fill(x_l, x_l + n, -kInfinity);
  std::fill(x_u, x_u + n, kInfinity);
  for (int k = 1; k <= data_.steps; ++k) {
    x_l[at.state(k, kY)] = data_.y_lower;
    x_u[at.state(k, kY)] = data_.y_upper;
    x_l[at.state(k, kV)] = data_.v.lo;
    x_u[at.state(k, kV)] = data_.v.hi;
    // The heading stays within a quarter turn, as the expert's.
    x_l[at.state(k, kTheta)] = -M_PI / 2;
    x_u[at.state(k, kTheta)] = M_PI / 2;
  }
  const EgoState& z0 = data_.initial;
  const double initial[] = {z0.x, z0.y, z0.v, z0.theta};
  for (Index c = 0; c < kStateSize; ++c) x_l[c] = x_u[c] = initial[c];
  for (int k = 0; k < data_.steps; ++k) {
    x_l[at.accel(k)] = data_.a.lo;
    x_u[at.accel(k)] = data_.a.hi;
    x_l[at.omega(k)] = data_.omega.lo;
    x_u[at.omega(k)] = data_.omega.hi;
  }
  Index row = kStateSize * data_.steps;
  std::fill(g_l, g_l + row, 0.0);
  std::fill(g_u, g_u + row, 0.0);
  if (data_.terminal_gap) {
    x_l[at.state(data_.steps, kY)] = x_u[at.state(data_.steps, kY)] = data_.lateral_reference;
    g_l[row] = data_.gap_rear;
    g_u[row++] = kInfinity;
    g_l[row] = -kInfinity;
    g_u[row++] = data_.gap_front;
  }
  // One row per pair of an ego circle and a car circle, in eval_g's order.
  std::fill(g_u + row, g_u + m, kInfinity);
  for (int k = 1; k <= data_.steps; ++k) {
    for (const CircleCentre& c : data_.obstacles[static_cast<std::size_t>(k)]) {
      for (std::size_t e = 0; e < data_.ego_offsets.size(); ++e) {
        g_l[row++] = c.clearance * c.clearance;
      }
    }
  }
  return true;
}

bool MpcNlp::get_starting_point(Index n, bool init_x, Number* x, bool init_z, Number* /*z_l*/,
                                Number* /*z_u*/, Index /*m*/, bool init_lambda,
                                Number* /*lambda*/) {
  if (init_z || init_lambda || !init_x) return false;
  const std::vector<Number> start = pack(guess_);
  std::copy(start.begin(), start.begin() + n, x);
  return true;
}

bool MpcNlp::eval_f(Index /*n*/, const Number* x, bool /*new_x*/, Number& obj_value) {
  const Layout at{data_.steps};
  const MpcProblemData& d = data_;
  double total = 0.0;
  double previous = d.previous_accel;
  for (int k = 0; k < d.steps; ++k) {
    const double a = x[at.accel(k)];
    const double omega = x[at.omega(k)];
    const double dy = x[at.state(k, kY)] - d.lateral_reference;
    total += d.accel_weight * a * a + d.yaw_rate_weight * omega * omega +
             d.jerk_weight * (a - previous) * (a - previous) + d.lateral_weight * dy * dy;
    previous = a;
  }
  obj_value = total;
  return true;
}

bool MpcNlp::eval_grad_f(Index n, const Number* x, bool /*new_x*/, Number* grad_f) {
  const Layout at{data_.steps};
  const MpcProblemData& d = data_;
  std::fill(grad_f, grad_f + n, 0.0);
  double previous = d.previous_accel;
  for (int k = 0; k < d.steps; ++k) {
    const double a = x[at.accel(k)];
    grad_f[at.accel(k)] += 2.0 * d.accel_weight * a + 2.0 * d.jerk_weight * (a - previous);
    if (k > 0) grad_f[at.accel(k - 1)] -= 2.0 * d.jerk_weight * (a - previous);
    grad_f[at.omega(k)] = 2.0 * d.yaw_rate_weight * x[at.omega(k)];
    grad_f[at.state(k, kY)] = 2.0 * d.lateral_weight * (x[at.state(k, kY)] - d.lateral_reference);
    previous = a;
  }
  return true;
}

bool MpcNlp::eval_g(Index /*n*/, const Number* x, bool /*new_x*/, Index /*m*/, Number* g) {
  const Layout at{data_.steps};
  const double h = 0.5 * data_.dt;
  Index row = 0;
  for (int k = 0; k < data_.steps; ++k) {
    const Number* z = x + at.state(k, 0);
    const Number* next = x + at.state(k + 1, 0);
    g[row++] =
        next[kX] - z[kX] - h * (z[kV] * std::cos(z[kTheta]) + next[kV] * std::cos(next[kTheta]));
    g[row++] =
        next[kY] - z[kY] - h * (z[kV] * std::sin(z[kTheta]) + next[kV] * std::sin(next[kTheta]));
    g[row++] = next[kV] - z[kV] - data_.dt * x[at.accel(k)];
    g[row++] = next[kTheta] - z[kTheta] - data_.dt * x[at.omega(k)];
  }
  if (data_.terminal_gap) {
    const Number* end = x + at.state(data_.steps, 0);
    g[row++] = end[kX];
    g[row++] = end[kX] + data_.target_headway * end[kV];
  }
  for (int k = 1; k <= data_.steps; ++k) {
    for (const CircleCentre& c : data_.obstacles[static_cast<std::size_t>(k)]) {
      for (const double offset : data_.ego_offsets) {
        g[row++] = pair_distance(x + at.state(k, 0), offset, c).value;
      }
    }
  }
  return true;
}

bool MpcNlp::eval_jac_g(Index /*n*/, const Number* x, bool /*new_x*/, Index /*m*/,
                        Index /*nele_jac*/, Index* i_row, Index* j_col, Number* values) {
  const Layout at{data_.steps};
  const double h = 0.5 * data_.dt;
  Index e = 0;
  Index row = 0;
  // Writes the structure on the first call (values == nullptr), then values.
  auto put = [&](Index r, Index col, double value) {
    if (values == nullptr) {
      i_row[e] = r;
      j_col[e] = col;
    } else {
      values[e] = value;
    }
    ++e;
  };
  for (int k = 0; k < data_.steps; ++k) {
    const Index z = at.state(k, 0);
    const Index next = at.state(k + 1, 0);
    for (const Index node : {z, next}) {
      const double v = values != nullptr ? x[node + kV] : 0.0;
      const double s = values != nullptr ? std::sin(x[node + kTheta]) : 0.0;
      const double c = values != nullptr ? std::cos(x[node + kTheta]) : 0.0;
      put(row, node + kX, node == z ? -1.0 : 1.0);
      put(row, node + kV, -h * c);
      put(row, node + kTheta, h * v * s);
      put(row + 1, node + kY, node == z ? -1.0 : 1.0);
      put(row + 1, node + kV, -h * s);
      put(row + 1, node + kTheta, -h * v * c);
      put(row + 2, node + kV, node == z ? -1.0 : 1.0);
      put(row + 3, node + kTheta, node == z ? -1.0 : 1.0);
    }
    put(row + 2, at.accel(k), -data_.dt);
    put(row + 3, at.omega(k), -data_.dt);
    row += kStateSize;
  }
  if (data_.terminal_gap) {
    const Index end = at.state(data_.steps, 0);
    put(row, end + kX, 1.0);
    put(row + 1, end + kX, 1.0);
    put(row + 1, end + kV, data_.target_headway);
    row += 2;
  }
  for (int k = 1; k <= data_.steps; ++k) {
    const Index node = at.state(k, 0);
    for (const CircleCentre& c : data_.obstacles[static_cast<std::size_t>(k)]) {
      for (const double offset : data_.ego_offsets) {
        const PairDistance p =
            values != nullptr ? pair_distance(x + node, offset, c) : PairDistance{};
        put(row, node + kX, 2.0 * p.dx);
        put(row, node + kY, 2.0 * p.dy);
        put(row, node + kTheta, p.d_theta);
        ++row;
      }
    }
  }
  return true;
}

bool MpcNlp::eval_h(Index /*n*/, const Number* x, bool /*new_x*/, Number obj_factor, Index /*m*/,
                    const Number* lambda, bool /*new_lambda*/, Index nele_hess, Index* i_row,
                    Index* j_col, Number* values) {
  const Layout at{data_.steps};
  const HessianLayout hl{data_.steps};
  using E = HessianLayout::NodeEntry;
  const int n_steps = data_.steps;
  if (values == nullptr) {
    for (int k = 0; k <= n_steps; ++k) {
      const Index base = at.state(k, 0);
      const std::pair<Index, Index> entries[] = {{kX, kX},     {kY, kY},     {kTheta, kX},
                                                 {kTheta, kY}, {kTheta, kV}, {kTheta, kTheta}};
      for (Index e = 0; e < E::kPerNode; ++e) {
        i_row[hl.node(k, static_cast<E>(e))] = base + entries[e].first;
        j_col[hl.node(k, static_cast<E>(e))] = base + entries[e].second;
      }
    }
    for (int k = 0; k < n_steps; ++k) {
      i_row[hl.accel(k)] = j_col[hl.accel(k)] = at.accel(k);
      i_row[hl.omega(k)] = j_col[hl.omega(k)] = at.omega(k);
      if (k + 1 < n_steps) {
        i_row[hl.jerk(k)] = at.accel(k + 1);
        j_col[hl.jerk(k)] = at.accel(k);
      }
    }
    return true;
  }
  std::fill(values, values + nele_hess, 0.0);
  const MpcProblemData& d = data_;
  for (int k = 0; k < n_steps; ++k) {
    const double jerk_terms = k + 1 < n_steps ? 2.0 : 1.0;
    values[hl.accel(k)] = obj_factor * (2.0 * d.accel_weight + 2.0 * d.jerk_weight * jerk_terms);
    values[hl.omega(k)] = obj_factor * 2.0 * d.yaw_rate_weight;
    if (k + 1 < n_steps) values[hl.jerk(k)] = -obj_factor * 2.0 * d.jerk_weight;
    values[hl.node(k, E::kYY)] = obj_factor * 2.0 * d.lateral_weight;
  }
  // The dynamics rows: -h v cos(theta) and -h v sin(theta) at both ends.
  const double h = 0.5 * d.dt;
  for (int k = 0; k < n_steps; ++k) {
    const double lx = lambda[kStateSize * k + kX];
    const double ly = lambda[kStateSize * k + kY];
    for (const int node : {k, k + 1}) {
      const double v = x[at.state(node, kV)];
      const double s = std::sin(x[at.state(node, kTheta)]);
      const double c = std::cos(x[at.state(node, kTheta)]);
      values[hl.node(node, E::kThetaV)] += lx * h * s - ly * h * c;
      values[hl.node(node, E::kThetaTheta)] += lx * h * v * c + ly * h * v * s;
    }
  }
  Index row = kStateSize * n_steps + terminal_rows();
  for (int k = 1; k <= n_steps; ++k) {
    const Number* node = x + at.state(k, 0);
    const double s = std::sin(node[kTheta]);
    const double c = std::cos(node[kTheta]);
    for (const CircleCentre& centre : d.obstacles[static_cast<std::size_t>(k)]) {
      for (const double offset : d.ego_offsets) {
        const double mu = lambda[row++];
        const PairDistance p = pair_distance(node, offset, centre);
        values[hl.node(k, E::kXX)] += 2.0 * mu;
        values[hl.node(k, E::kYY)] += 2.0 * mu;
        values[hl.node(k, E::kThetaX)] -= 2.0 * mu * offset * s;
        values[hl.node(k, E::kThetaY)] += 2.0 * mu * offset * c;
        values[hl.node(k, E::kThetaTheta)] +=
            2.0 * mu * (offset * offset - offset * (p.dx * c + p.dy * s));
      }
    }
  }
  return true;
}

void MpcNlp::finalize_solution(Ipopt::SolverReturn /*status*/, Index /*n*/, const Number* x,
                               const Number* /*z_L*/, const Number* /*z_U*/, Index /*m*/,
                               const Number* /*g*/, const Number* /*lambda*/, Number obj_value,
                               const Ipopt::IpoptData* /*ip_data*/,
                               Ipopt::IpoptCalculatedQuantities* /*ip_cq*/) {
  solution_ = unpack(x);
  objective_ = obj_value;
}

bool MpcNlp::intermediate_callback(Ipopt::AlgorithmMode /*mode*/, Index /*iter*/,
                                   Number /*obj_value*/, Number /*inf_pr*/, Number /*inf_du*/,
                                   Number /*mu*/, Number /*d_norm*/, Number /*regularization_size*/,
                                   Number /*alpha_du*/, Number /*alpha_pr*/, Index /*ls_trials*/,
                                   const Ipopt::IpoptData* /*ip_data*/,
                                   Ipopt::IpoptCalculatedQuantities* /*ip_cq*/) {
  return std::chrono::steady_clock::now() < deadline_;
}

}  // namespace lanechange::baselines
