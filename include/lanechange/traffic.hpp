#pragma once
// The other cars: constant speed, constant acceleration (stopping at 0, and
// at traffic_max_speed when speeding up, if the config sets one) or the
// Intelligent Driver Model. The same step
// serves a planner's prediction and the closed-loop simulation.
#include <optional>
#include <vector>

#include "lanechange/config.hpp"
#include "lanechange/scenario.hpp"
#include "lanechange/spare.hpp"

namespace lanechange {

/// Where the ego is, as far as the other cars care.
struct EgoFootprint {
  double x = 0.0;
  double y = 0.0;
  double v = 0.0;
};

/// IDM acceleration of a car at speed v behind a leader `gap` metres away
/// (bumper to bumper) that drives at `leader_speed`. Pass gap = +infinity
/// for a free road.
[[nodiscard]] double idm_acceleration(const IdmParameters& p, double v, double gap,
                                      double leader_speed);

/// Exact motion under constant acceleration a for dt seconds. A braking car
/// stops at 0; a car speeding up holds its speed at `cap` once it gets
/// there. A car at constant speed, or already above the cap, keeps its
/// speed: a recorded car faster than the cap is not slowed by the model.
void advance_constant_accel(CarState& car, double dt, double cap);

/// True when the ego's body (width `ego_width`, centre y) reaches into the
/// lane centred at `lane_center`.
[[nodiscard]] bool body_in_lane(double y, double ego_width, double lane_center, double lane_width);

/// Krauss's safe speed (SUMO's default car): the fastest a car may drive
/// `gap` metres (bumper to bumper) behind a leader at `leader_speed` and still
/// stop behind it, braking at `decel` after `reaction_time`.
[[nodiscard]] double krauss_safe_speed(double gap, double speed, double leader_speed,
                                       double reaction_time, double decel);

/// The gap (bumper to bumper, m) a car keeps to brake no harder than some
/// deceleration, as a function of its leader's speed near one speed:
/// gap + slope * (leader speed - that speed).
struct SafeGapLine {
  double gap = 0.0;    ///< m, at the leader speed it was taken at
  double slope = 0.0;  ///< s: per m/s of leader speed
  [[nodiscard]] double at(double leader_speed, double taken_at) const {
    return gap + slope * (leader_speed - taken_at);
  }
};

/// The shortest gap behind a leader at `leader_speed` at which a car of
/// `behavior` at `speed` brakes no harder than `decel` in its next step of
/// `dt`, by the model that moves it, with its slope in the leader's speed:
/// IDM's (linear in the leader's speed wherever the car closes in; an IDM car
/// that brakes harder on a free road gets its desired gap), or the tangent of
/// Krauss's under traffic.followers_react (concave in the leader's speed, so
/// the tangent asks at least as much everywhere). None for a car that
/// ignores the cars ahead.
[[nodiscard]] std::optional<SafeGapLine> gap_braking_at_most(double decel, Behavior behavior,
                                                             double speed, double leader_speed,
                                                             double dt, const IdmParameters& idm,
                                                             const TrafficSettings& traffic);

/// The model a planner predicts a car of `behavior` by: a replayed car's is
/// traffic.replay_prediction, never its record.
[[nodiscard]] Behavior predicted_behavior(Behavior behavior, const TrafficSettings& traffic);

/// The scene as a planner may know it: every replayed car by its predicted
/// behavior, without its record.
[[nodiscard]] Scenario planning_view(const Scenario& scenario, const TrafficSettings& traffic);

/// Whether any car of the scene reacts to the ego (IDM, or any car under
/// traffic.followers_react): a prediction then depends on the ego's path.
[[nodiscard]] bool traffic_reacts(const Scenario& scenario, const Config& config);

class TrafficModel {
 public:
  /// Whether replayed cars move by their records (the simulated world) or
  /// by traffic.replay_prediction (a planner's prediction, the default).
  enum class Records { Predict, Replay };

  /// A model of no cars, to be reset() to a scene.
  TrafficModel() = default;
  TrafficModel(const Scenario& scenario, const Config& config, Records records = Records::Predict);
  /// The model of `scenario` at t = 0, as the constructor makes it; a model
  /// reset to scenes of no more cars than before allocates nothing.
  void reset(const Scenario& scenario, const Config& config, Records records = Records::Predict);

  /// Advances every car by dt, each by its own behavior; a replayed car to
  /// its record's state at the new time, whatever is ahead. An IDM car follows
  /// the nearest car ahead in its lane, the ego included once its body is in
  /// that lane; under traffic.followers_react the other cars do too where
  /// their behavior would take them past Krauss's safe speed. No car brakes
  /// harder than traffic.max_decel. A car's `a` is the acceleration applied
  /// during the step.
  void step(double dt, const EgoFootprint& ego);

  [[nodiscard]] const CarState& car(CarIndex which) const { return cars_[which]; }
  [[nodiscard]] const std::vector<CarState>& cars() const { return cars_; }
  /// A car as the planners observe it: x and v now, and the acceleration it
  /// drives by. That is a constant-acceleration car's own (the behavior's,
  /// which it keeps wherever the car ahead lets it), not the braking of a
  /// step in which it followed: predicted on, that braking would stop the
  /// car where the model has it return to its own acceleration. Any other
  /// car's is its last step's.
  [[nodiscard]] CarState observed(CarIndex which) const;
  [[nodiscard]] std::size_t car_count() const { return cars_.size(); }
  /// Whether the car's last step was set by the ego ahead of it (it followed
  /// the ego): its braking then is the ego's doing.
  [[nodiscard]] bool followed_ego(CarIndex which) const { return followed_ego_[which] != 0; }
  [[nodiscard]] double time() const { return time_; }

 private:
  /// The nearest car ahead in a car's lane, the ego included: gap (bumper to
  /// bumper, +infinity for none), its speed, and whether it is the ego.
  struct Ahead {
    double gap;
    double speed;
    bool is_ego;
  };
  [[nodiscard]] Ahead ahead_of(CarIndex which, const EgoFootprint& ego) const;
  void sort_by_lane_and_position();
  /// The acceleration of car `which` this step, from the state now.
  [[nodiscard]] double acceleration_of(CarIndex which, const EgoFootprint& ego, double dt);
  void advance_ballistic(CarState& car, double dt) const;

  double lane_width_ = 0.0;
  VehicleSize vehicle_;  ///< the ego's body
  IdmParameters idm_;
  double speed_cap_ = 0.0;  ///< +infinity without a cap
  TrafficIntegration integration_ = TrafficIntegration::Ballistic;
  TrafficSettings settings_;
  double max_decel_ = 0.0;  ///< +infinity without a limit
  // Per car, in the scene's order; sized once.
  std::vector<Behavior> behavior_;
  std::vector<double> lane_center_;
  std::vector<double> length_;
  std::vector<double> width_;
  std::vector<double> behavior_accel_;                 ///< a constant-acceleration car's own a
  std::vector<std::optional<RecordedTrack>> records_;  ///< a replayed car's, under Records::Replay
  std::vector<CarState> cars_;
  std::vector<double> accel_;  ///< this step's accelerations, before any car moves
  /// this step: 1 where a car followed (its acceleration set by) the car ahead,
  /// not its behavior alone; 0 else
  std::vector<char> follows_;
  std::vector<char> followed_ego_;  ///< as follows_, for the ego ahead
  std::vector<CarIndex> order_;     ///< the cars by lane, then by x (this step's)
  std::vector<std::size_t> rank_;   ///< per car, its place in order_
  double longest_ = 0.0;            ///< the longest car's length
  double time_ = 0.0;
};

/// One car over a time grid: node k is at time k * dt.
struct CarTrack {
  std::vector<double> x;
  std::vector<double> v;
  std::vector<double> a;  ///< applied from node k to k + 1; the last repeats
  /// Per node, whether the car is on the track's lane then (traffic that
  /// enters, leaves or changes lanes: one track per stay in a lane); empty:
  /// at every node. Where it is not, x, v and a hold its nearest stay's values.
  std::vector<char> present;
  [[nodiscard]] bool present_at(std::size_t node) const {
    return present.empty() || present[node] != 0;
  }
};

/// Every car of a scene over the same grid, in the scene's order.
struct TrafficPrediction {
  double dt = 0.0;
  std::vector<CarTrack> cars;
  Spare<CarTrack> spare;  ///< tracks a smaller prediction set aside, with their memory
  /// `*this = other`, keeping the memory of its tracks (a planner's buffers).
  void assign(const TrafficPrediction& other) {
    dt = other.dt;
    assign_keeping(cars, other.cars, spare);
  }
  [[nodiscard]] const CarTrack& car(CarIndex which) const { return cars[which]; }
  [[nodiscard]] std::size_t car_count() const { return cars.size(); }
  /// Nodes per track; 0 without cars.
  [[nodiscard]] int nodes() const { return cars.empty() ? 0 : static_cast<int>(cars[0].x.size()); }
};

/// Predicts `steps` steps of dt. Under IDM, `ego_path` (node positions, at
/// least steps + 1 of them) lets the cars react to the ego's planned motion;
/// without it the ego is taken to hold its initial lateral position at its
/// initial speed.
[[nodiscard]] TrafficPrediction predict_traffic(
    const Scenario& scenario, const Config& config, int steps, double dt,
    const std::vector<EgoFootprint>* ego_path = nullptr);
/// The same into `out`, with `model` reset to the scene: kept by a caller
/// across predictions of no more cars and steps, they allocate nothing.
void predict_traffic(const Scenario& scenario, const Config& config, int steps, double dt,
                     const std::vector<EgoFootprint>* ego_path, TrafficModel& model,
                     TrafficPrediction& out);

}  // namespace lanechange
