#pragma once
// The nonlinear program of the MPC baseline (docs/baselines.md, "mpc") as an
// Ipopt TNLP with exact sparse derivatives. Direct multiple shooting over the
// planner's trapezoidal unicycle (step_trapezoidal): every node's state is a
// variable, tied to the next by four equality rows. Internal to src/baselines.
#include <chrono>
#include <coin/IpTNLP.hpp>
#include <vector>

#include "lanechange/ego.hpp"

namespace lanechange::baselines {

using Ipopt::Index;
using Ipopt::Number;

/// One circle of another car at one node: where it is (the cars stay in
/// their lanes, so y is the lane centre).
struct CircleCentre {
  double x = 0.0;
  double y = 0.0;
  /// The least distance of an ego circle's centre from this one: both
  /// radii and the margin (a truck's circles are wider than a car's).
  double clearance = 0.0;
};

/// A plan over `steps` steps: states at steps + 1 nodes, controls per step.
struct MpcPlan {
  std::vector<EgoState> states;
  std::vector<EgoControl> controls;
};

/// What one solve is about. Everything an update may change.
struct MpcProblemData {
  int steps = 0;
  double dt = 0.0;
  EgoState initial;                ///< node 0 is fixed here
  double previous_accel = 0.0;     ///< the last applied a: the first jerk term starts from it
  double accel_weight = 0.0;       ///< on a_k^2 (already times dt)
  double yaw_rate_weight = 0.0;    ///< on omega_k^2 (already times dt)
  double jerk_weight = 0.0;        ///< on (a_{k+1} - a_k)^2
  double lateral_weight = 0.0;     ///< on (y_k - lateral_reference)^2, k < steps (times dt)
  double lateral_reference = 0.0;  ///< the target-lane centre w
  double y_lower = 0.0;            ///< road edges, as the expert's lateral bounds
  double y_upper = 0.0;
  Interval v;
  Interval a;
  Interval omega;
  /// Offsets of the ego's circle centres along its heading, from its centre.
  std::vector<double> ego_offsets;
  double ego_radius = 0.0;  ///< of each of the ego's circles
  /// obstacles[k]: the other cars' circle centres at node k (k = 0 unused).
  std::vector<std::vector<CircleCentre>> obstacles;
  /// The circles left out of the rows (too far from the starting point to
  /// matter), kept to check the solution against.
  std::vector<std::vector<CircleCentre>> pruned;
  /// The terminal set: y_N = w, and x_N between the follower's and target's
  /// safe distances (x_N >= gap_rear; x_N + target_headway v_N <= gap_front).
  bool terminal_gap = false;
  double gap_rear = 0.0;
  double gap_front = 0.0;
  double target_headway = 0.0;
};

/// The largest violation, over the nodes 1..N of `plan`, of the clearance
/// from the circles `centres` (0 when clear).
[[nodiscard]] double clearance_violation(const MpcProblemData& data, const MpcPlan& plan,
                                         const std::vector<std::vector<CircleCentre>>& centres);

class MpcNlp final : public Ipopt::TNLP {
 public:
  /// New data and a starting point (its sizes must match data.steps).
  void update(MpcProblemData data, MpcPlan guess);
  /// Stops the solve (as a user stop) once this much wall time has passed.
  void set_deadline(std::chrono::steady_clock::time_point deadline) { deadline_ = deadline; }
  [[nodiscard]] const MpcPlan& solution() const { return solution_; }
  [[nodiscard]] double objective() const { return objective_; }
  [[nodiscard]] const MpcProblemData& data() const { return data_; }
  [[nodiscard]] Index variables() const;
  [[nodiscard]] Index rows() const;
  /// The plan's variables in the NLP's order, and back.
  [[nodiscard]] std::vector<Number> pack(const MpcPlan& plan) const;
  [[nodiscard]] MpcPlan unpack(const Number* x) const;

  bool get_nlp_info(Index& n, Index& m, Index& nnz_jac_g, Index& nnz_h_lag,
                    IndexStyleEnum& index_style) override;
  bool get_bounds_info(Index n, Number* x_l, Number* x_u, Index m, Number* g_l,
                       Number* g_u) override;
  bool get_starting_point(Index n, bool init_x, Number* x, bool init_z, Number* z_l, Number* z_u,
                          Index m, bool init_lambda, Number* lambda) override;
  bool eval_f(Index n, const Number* x, bool new_x, Number& obj_value) override;
  bool eval_grad_f(Index n, const Number* x, bool new_x, Number* grad_f) override;
  bool eval_g(Index n, const Number* x, bool new_x, Index m, Number* g) override;
  bool eval_jac_g(Index n, const Number* x, bool new_x, Index m, Index nele_jac, Index* i_row,
                  Index* j_col, Number* values) override;
  bool eval_h(Index n, const Number* x, bool new_x, Number obj_factor, Index m,
              const Number* lambda, bool new_lambda, Index nele_hess, Index* i_row, Index* j_col,
              Number* values) override;
  void finalize_solution(Ipopt::SolverReturn status, Index n, const Number* x, const Number* z_L,
                         const Number* z_U, Index m, const Number* g, const Number* lambda,
                         Number obj_value, const Ipopt::IpoptData* ip_data,
                         Ipopt::IpoptCalculatedQuantities* ip_cq) override;
  bool intermediate_callback(Ipopt::AlgorithmMode mode, Index iter, Number obj_value, Number inf_pr,
                             Number inf_du, Number mu, Number d_norm, Number regularization_size,
                             Number alpha_du, Number alpha_pr, Index ls_trials,
                             const Ipopt::IpoptData* ip_data,
                             Ipopt::IpoptCalculatedQuantities* ip_cq) override;

 private:
  [[nodiscard]] Index pair_count() const;
  [[nodiscard]] Index terminal_rows() const { return data_.terminal_gap ? 2 : 0; }

  MpcProblemData data_;
  MpcPlan guess_;
  MpcPlan solution_;
  double objective_ = 0.0;
  std::chrono::steady_clock::time_point deadline_ = std::chrono::steady_clock::time_point::max();
};

}  // namespace lanechange::baselines
