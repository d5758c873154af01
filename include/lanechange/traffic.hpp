#pragma once
// The other cars: constant speed, constant acceleration (stopping at 0, and
// at traffic_max_speed when speeding up, if the config sets one) or the
// Intelligent Driver Model. The same step
// serves a planner's prediction and the closed-loop simulation.
#include <array>
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

  /// Advances the three cars by dt. Under IDM each car follows the nearest
  /// car ahead in its lane, the ego included once its body is in that lane.
  /// The returned accelerations are those applied during the step.
  void step(double dt, const EgoFootprint& ego);

  [[nodiscard]] const CarState& car(Car which) const { return cars_[index(which)]; }
  [[nodiscard]] double time() const { return time_; }

 private:
  static constexpr std::size_t index(Car c) { return static_cast<std::size_t>(c); }
  [[nodiscard]] double idm_accel_of(Car which, const EgoFootprint& ego) const;

  Behavior behavior_;
  double lane_width_;
  VehicleSize vehicle_;  ///< the ego's body
  IdmParameters idm_;
  double speed_cap_;  ///< +infinity without a cap
  TrafficIntegration integration_;
  std::array<double, 3> length_;  ///< each car's
  std::array<CarState, 3> cars_;
  double time_ = 0.0;
};

/// One car over a time grid: node k is at time k * dt.
struct CarTrack {
  std::vector<double> x;
  std::vector<double> v;
  std::vector<double> a;  ///< applied from node k to k + 1; the last repeats
};

struct TrafficPrediction {
  double dt = 0.0;
  std::array<CarTrack, 3> cars;
  [[nodiscard]] const CarTrack& car(Car which) const {
    return cars[static_cast<std::size_t>(which)];
  }
  [[nodiscard]] int nodes() const { return static_cast<int>(cars[0].x.size()); }
};

/// Predicts `steps` steps of dt. Under IDM, `ego_path` (node positions, at
/// least steps + 1 of them) lets the cars react to the ego's planned motion;
/// without it the ego is taken to hold its initial lateral position at its
/// initial speed.
[[nodiscard]] TrafficPrediction predict_traffic(
    const Scenario& scenario, const Config& config, int steps, double dt,
    const std::vector<EgoFootprint>* ego_path = nullptr);

}  // namespace lanechange
