#pragma once
// The other cars: constant speed, constant acceleration (stopping at 0, and
// at traffic_max_speed when speeding up, if the config sets one) or the
// Intelligent Driver Model. The same step
// serves a planner's prediction and the closed-loop simulation.
#include <vector>

#include "lanechange/config.hpp"
#include "lanechange/scenario.hpp"

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

class TrafficModel {
 public:
  TrafficModel(const Scenario& scenario, const Config& config);

  /// Advances every car by dt, each by its own behavior. An IDM car follows
  /// the nearest car ahead in its lane, the ego included once its body is in
  /// that lane. A car's `a` is the acceleration applied during the step.
  void step(double dt, const EgoFootprint& ego);

  [[nodiscard]] const CarState& car(CarIndex which) const { return cars_[which]; }
  [[nodiscard]] const std::vector<CarState>& cars() const { return cars_; }
  [[nodiscard]] std::size_t car_count() const { return cars_.size(); }
  [[nodiscard]] double time() const { return time_; }

 private:
  [[nodiscard]] double idm_accel_of(CarIndex which, const EgoFootprint& ego) const;
  void advance_idm(CarState& car, double dt) const;

  double lane_width_;
  VehicleSize vehicle_;  ///< the ego's body
  IdmParameters idm_;
  double speed_cap_;  ///< +infinity without a cap
  TrafficIntegration integration_;
  // Per car, in the scene's order; sized once.
  std::vector<Behavior> behavior_;
  std::vector<double> lane_center_;
  std::vector<double> length_;
  std::vector<CarState> cars_;
  std::vector<double> accel_;  ///< this step's IDM accelerations, before any car moves
  double time_ = 0.0;
};

/// One car over a time grid: node k is at time k * dt.
struct CarTrack {
  std::vector<double> x;
  std::vector<double> v;
  std::vector<double> a;  ///< applied from node k to k + 1; the last repeats
};

/// Every car of a scene over the same grid, in the scene's order.
struct TrafficPrediction {
  double dt = 0.0;
  std::vector<CarTrack> cars;
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

}  // namespace lanechange
