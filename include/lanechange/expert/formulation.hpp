#pragma once
// The expert's problem for one round of successive linearization, in
// stage-wise form (states z_k = [x, y, v, theta], controls u_k = [a, omega]):
//
//   minimize   sum_k w_a a_k^2 + sum_k w_w omega_k^2 + sum_k w_j (a_{k+1} - a_k)^2
//              + sum_k w_y,k (y_k - y_ref)^2 + w_x (x_N - x_ref)^2
//   subject to z_0 = the ego's state,
//              z_{k+1} = A_k z_k + B_k u_k + c_k   (trapezoid, linearized)
//              bounds on z_k (k >= 1) and u_k; y_N = y_ref if fixed
//              at every node with lane logic, z_k satisfies the rows of at
//              least one of its lane modes (the disjunction of Eq. 1).
//
// Both back-ends solve exactly this: the reference through to_miqp (big-M,
// one binary per node and mode), our structured solver directly.
#include <Eigen/Core>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "lanechange/config.hpp"
#include "lanechange/expert/miqp.hpp"
#include "lanechange/scenario.hpp"
#include "lanechange/spare.hpp"
#include "lanechange/traffic.hpp"

namespace lanechange::expert {

using State = Eigen::Vector4d;    ///< [x, y, v, theta]
using Control = Eigen::Vector2d;  ///< [a, omega]
enum StateIndex { kX = 0, kY = 1, kV = 2, kTheta = 3 };
enum ControlIndex { kA = 0, kOmega = 1 };

/// A trajectory of the discrete model: steps + 1 states and steps controls.
struct Iterate {
  std::vector<State> states;
  std::vector<Control> controls;
};

struct StageDynamics {
  Eigen::Matrix4d A;
  Eigen::Matrix<double, 4, 2> B;
  Eigen::Vector4d c;
};

/// The row g' z_k <= upper.
struct HalfSpace {
  Eigen::Vector4d g;
  double upper = 0.0;
};

enum class LaneOccupancy { EgoLane, BothLanes, TargetLane };
[[nodiscard]] std::string_view to_string(LaneOccupancy occupancy);

struct LaneMode {
  LaneOccupancy occupancy = LaneOccupancy::EgoLane;
  std::vector<HalfSpace> rows;
};

struct LaneChangeQp {
  int steps = 0;
  double dt = 0.0;
  State initial_state = State::Zero();
  std::vector<StageDynamics> dynamics;  ///< steps entries
  double accel_weight = 0.0;            ///< on each a_k^2
  double yaw_rate_weight = 0.0;         ///< on each omega_k^2
  double jerk_weight = 0.0;             ///< on each (a_{k+1} - a_k)^2
  std::vector<double> lateral_weight;   ///< steps + 1 entries, on (y_k - y_ref)^2
  double lateral_reference = 0.0;
  double terminal_x_weight = 0.0;
  double terminal_x_reference = 0.0;
  std::vector<State> state_lower;  ///< steps + 1 entries; entry 0 is unused
  std::vector<State> state_upper;
  Control control_lower = Control::Zero();
  Control control_upper = Control::Zero();
  bool terminal_lateral_fixed = true;
  /// Above 0: |omega_k| <= this * v_k at every stage (expert.min_turn_radius).
  double yaw_rate_per_speed = 0.0;
  /// steps + 1 entries; an empty list puts no lane logic on that node.
  std::vector<std::vector<LaneMode>> node_modes;

  /// The objective of a trajectory (states and controls as in Iterate).
  [[nodiscard]] double objective(const Iterate& path) const;
  /// The part of objective() that no state or control changes (the squared
  /// references of the lateral and terminal-x terms).
  [[nodiscard]] double objective_constant() const;
  /// Largest violation of dynamics, bounds and lane logic (0 when feasible).
  [[nodiscard]] double max_violation(const Iterate& path) const;
  /// The mode of node k that path satisfies best (smallest largest violation)
  /// among those with their bit set in `allowed`; -1 if none is.
  [[nodiscard]] int best_mode(const Iterate& path, int node, unsigned allowed = ~0U) const;
};

/// Where a lane rule puts `occupancy` among a node's modes (the index
/// LaneChangeSolution::modes uses), or -1 when the rule has no such mode
/// (either_or has no both-lanes mode).
[[nodiscard]] int lane_mode_index(LaneRule rule, LaneOccupancy occupancy);

/// A gap of the target lane, as a split of its cars: the ego ends ahead of
/// every car in `behind` and behind every car in `ahead`. Each of them keeps
/// its Eq. 1 distance at every node where the ego is in the target lane, so
/// the plan stays exact even where the prediction lets cars pass each other.
struct Gap {
  std::vector<CarIndex> behind;  ///< nearest last
  std::vector<CarIndex> ahead;   ///< nearest first
  /// The cars that frame the gap (none where the gap is open that way).
  [[nodiscard]] std::optional<CarIndex> car_behind() const;
  [[nodiscard]] std::optional<CarIndex> car_ahead() const;
  bool operator==(const Gap&) const = default;
};
/// Eq. 1's one gap: between the scene's follower and target (open where the
/// scene has no car in that role).
[[nodiscard]] Gap paper_gap(const Scenario& scenario);
/// The same into `out`, whose lists keep their memory.
void paper_gap(const Scenario& scenario, Gap& out);
/// The gaps config.expert.gap allows, from the back of the target lane:
/// the paper's alone (fixed), or one per place between, ahead of and behind
/// the target-lane cars as they stand at t = 0 (best).
[[nodiscard]] std::vector<Gap> target_lane_gaps(const Scenario& scenario, GapChoice choice);
/// The same into `out`, whose gaps keep their lists' memory.
/// With `spare`, gaps dropped for a smaller scene wait there with their memory.
void target_lane_gaps(const Scenario& scenario, GapChoice choice, std::vector<Gap>& out,
                      Spare<Gap>* spare = nullptr);
/// Where a plan into `gap` aims at prediction node `node`: behind the gap's
/// car ahead by its safe distance (expert.aim_behind_target; else at it), at
/// that car's speed and acceleration; ahead of the car behind where the gap
/// is open in front; at the ego's pace on an empty target lane.
struct GapAim {
  double x = 0.0, v = 0.0, a = 0.0;
};
[[nodiscard]] GapAim aim_into(const Scenario& scenario, const Config& config,
                              const TrafficPrediction& prediction, const Gap& gap, int node);
/// Half the width the footprint lane rules give the ego's body: its own half
/// width plus expert.line_clearance.
[[nodiscard]] double footprint_half_width(const Scenario& scenario, const ExpertSettings& expert);

/// "follower-target", "none-follower", ...: the ids of the framing cars,
/// back first.
[[nodiscard]] std::string describe(const Scenario& scenario, const Gap& gap);

/// Builds the round's problem around `point` (its speeds and headings are the
/// linearization point) with the cars predicted in `prediction`, the target
/// lane's rows those of `gap`.
[[nodiscard]] LaneChangeQp build_lane_change_qp(const Scenario& scenario, const Config& config,
                                                const Iterate& point,
                                                const TrafficPrediction& prediction,
                                                const Gap& gap);
/// The same into `qp`, in place: its lists keep their memory, so a build of a
/// problem no larger than the last one allocates nothing.
void build_lane_change_qp(const Scenario& scenario, const Config& config, const Iterate& point,
                          const TrafficPrediction& prediction, const Gap& gap, LaneChangeQp& qp);
/// The same through Eq. 1's gap (paper_gap).
[[nodiscard]] LaneChangeQp build_lane_change_qp(const Scenario& scenario, const Config& config,
                                                const Iterate& point,
                                                const TrafficPrediction& prediction);

/// Where each variable of the MIQP form sits.
struct MiqpLayout {
  int steps = 0;
  std::vector<int> mode_offset;  ///< first binary of node k (steps + 2 entries, prefix sums)
  [[nodiscard]] int state(int node, int component) const { return component * (steps + 1) + node; }
  [[nodiscard]] int control(int step, int component) const {
    return 4 * (steps + 1) + component * steps + step;
  }
  [[nodiscard]] int mode(int node, int m) const { return mode_offset[node] + m; }
  [[nodiscard]] int size() const { return mode_offset.back(); }
};

/// The same problem as a general MIQP: one binary per (node, mode), their sum
/// at each node equal to 1, and each mode's rows relaxed by a big-M when its
/// binary is 0. `big_m` caps the relaxation; each row gets the smallest M that
/// is valid over the variable bounds.
[[nodiscard]] MiqpProblem to_miqp(const LaneChangeQp& qp, double big_m, MiqpLayout& layout);

/// The trajectory held in an MIQP solution vector.
[[nodiscard]] Iterate iterate_from_miqp(const Eigen::VectorXd& x, const MiqpLayout& layout);

}  // namespace lanechange::expert
