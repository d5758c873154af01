#include "lanechange/traffic.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace lanechange {

namespace {

// IDM's (v / v0)^delta. Traffic steps call it for every car, and delta is 4
// in nearly every use: two squarings cost a fraction of std::pow.
double speed_ratio_power(double ratio, double exponent) {
  if (exponent == 4.0) {
    const double squared = ratio * ratio;
    return squared * squared;
  }
  return std::pow(ratio, exponent);
}

}  // namespace

double idm_acceleration(const IdmParameters& p, double v, double gap, double leader_speed) {
  const double free_road = 1.0 - speed_ratio_power(v / p.desired_speed, p.exponent);
  if (!std::isfinite(gap)) return p.max_accel * free_road;
  // A car that touches its leader brakes as hard as the model can; a tiny
  // floor keeps the ratio finite.
  const double safe_gap = std::max(gap, 1e-3);
  const double dynamic =
      v * p.time_headway +
      v * (v - leader_speed) / (2.0 * std::sqrt(p.max_accel * p.comfortable_decel));
  const double desired_gap = p.min_gap + std::max(0.0, dynamic);
  const double ratio = desired_gap / safe_gap;
  return p.max_accel * (free_road - ratio * ratio);
}

void advance_constant_accel(CarState& car, double dt, double cap) {
  const double bound = car.a > 0 ? cap : 0.0;
  const bool moving_towards_bound = car.a > 0 ? car.v < bound : (car.a < 0 && car.v > bound);
  if (!moving_towards_bound) {
    car.v = std::max(car.v, 0.0);
    car.x += car.v * dt;
    return;
  }
  const double time_to_bound = (bound - car.v) / car.a;
  if (time_to_bound >= dt) {
    car.x += car.v * dt + 0.5 * car.a * dt * dt;
    car.v += car.a * dt;
    return;
  }
  car.x += car.v * time_to_bound + 0.5 * car.a * time_to_bound * time_to_bound;
  car.x += bound * (dt - time_to_bound);
  car.v = bound;
}

bool body_in_lane(double y, double ego_width, double lane_center, double lane_width) {
  return std::abs(y - lane_center) < 0.5 * (lane_width + ego_width);
}

double krauss_safe_speed(double gap, double speed, double leader_speed, double reaction_time,
                         double decel) {
  return leader_speed + (gap - leader_speed * reaction_time) /
                            ((leader_speed + speed) / (2.0 * decel) + reaction_time);
}

namespace {

// IDM's acceleration is a_max (free - (s*/s)^2): at least -decel where
// s >= s* / sqrt(free + decel / a_max). s* is taken on its closing-in branch,
// linear in the leader's speed; where it is larger, Eq. 1 asks more anyway.
SafeGapLine idm_gap_braking_at_most(double decel, double speed, double leader_speed,
                                    const IdmParameters& p) {
  const double interaction = speed / (2.0 * std::sqrt(p.max_accel * p.comfortable_decel));
  const double desired_gap =
      p.min_gap + speed * p.time_headway + interaction * (speed - leader_speed);
  const double room =
      1.0 - speed_ratio_power(speed / p.desired_speed, p.exponent) + decel / p.max_accel;
  const double scale = room > 0.0 ? 1.0 / std::sqrt(room) : 1.0;
  return {desired_gap * scale, -interaction * scale};
}

// Krauss's safe speed is at least speed - decel dt where
// gap >= v_l tau + (speed - decel dt - v_l) ((v_l + speed) / (2 b) + tau).
SafeGapLine krauss_gap_braking_at_most(double decel, double speed, double leader_speed, double dt,
                                       const TrafficSettings& t) {
  const double lowest_speed = speed - decel * dt;
  const double b = t.follow_decel;
  const double gap =
      t.min_gap + leader_speed * t.reaction_time +
      (lowest_speed - leader_speed) * ((leader_speed + speed) / (2.0 * b) + t.reaction_time);
  return {gap, -(2.0 * leader_speed + decel * dt) / (2.0 * b)};
}

}  // namespace

std::optional<SafeGapLine> gap_braking_at_most(double decel, Behavior behavior, double speed,
                                               double leader_speed, double dt,
                                               const IdmParameters& idm,
                                               const TrafficSettings& traffic) {
  if (predicted_behavior(behavior, traffic) == Behavior::Idm)
    return idm_gap_braking_at_most(decel, speed, leader_speed, idm);
  if (!traffic.followers_react) return std::nullopt;
  return krauss_gap_braking_at_most(decel, speed, leader_speed, dt, traffic);
}

Behavior predicted_behavior(Behavior behavior, const TrafficSettings& traffic) {
  return behavior == Behavior::Replay ? traffic.replay_prediction : behavior;
}

Scenario planning_view(const Scenario& scenario, const TrafficSettings& traffic) {
  Scenario view = scenario;
  view.behavior = predicted_behavior(view.behavior, traffic);
  for (OtherCar& car : view.cars) {
    car.behavior = predicted_behavior(car.behavior, traffic);
    car.record.reset();
  }
  return view;
}

bool traffic_reacts(const Scenario& scenario, const Config& config) {
  if (config.traffic.followers_react && scenario.car_count() > 0) return true;
  return std::any_of(scenario.cars.begin(), scenario.cars.end(), [&](const OtherCar& car) {
    return predicted_behavior(car.behavior, config.traffic) == Behavior::Idm;
  });
}

TrafficModel::TrafficModel(const Scenario& scenario, const Config& config, Records records) {
  reset(scenario, config, records);
}

void TrafficModel::reset(const Scenario& scenario, const Config& config, Records records) {
  lane_width_ = scenario.lane_width;
  vehicle_ = scenario.vehicle;
  idm_ = scenario.idm;
  speed_cap_ = config.traffic_max_speed.value_or(std::numeric_limits<double>::infinity());
  integration_ = config.traffic_integration;
  settings_ = config.traffic;
  max_decel_ = config.traffic.max_decel.value_or(std::numeric_limits<double>::infinity());
  const std::size_t n = scenario.car_count();
  accel_.assign(n, 0.0);
  follows_.assign(n, 0);
  followed_ego_.assign(n, 0);
  order_.resize(n);
  rank_.resize(n);
  behavior_.clear();
  lane_center_.clear();
  length_.clear();
  width_.clear();
  behavior_accel_.clear();
  cars_.clear();
  records_.assign(n, std::nullopt);
  longest_ = 0.0;
  time_ = 0.0;
  for (CarIndex i = 0; i < n; ++i) {
    const OtherCar& car = scenario.cars[i];
    if (records == Records::Replay && car.behavior == Behavior::Replay && car.record) {
      behavior_.push_back(Behavior::Replay);
      records_[i] = *car.record;
    } else {
      behavior_.push_back(predicted_behavior(car.behavior, config.traffic));
    }
    lane_center_.push_back(scenario.lane_center(i));
    length_.push_back(scenario.size_of(i).length);
    width_.push_back(scenario.size_of(i).width);
    cars_.push_back(scenario.car(i));
    if (behavior_.back() == Behavior::ConstantSpeed) cars_.back().a = 0.0;
    behavior_accel_.push_back(cars_.back().a);
    longest_ = std::max(longest_, length_.back());
    order_[i] = i;
  }
}

CarState TrafficModel::observed(CarIndex which) const {
  CarState car = cars_[which];
  if (behavior_[which] == Behavior::ConstantAccel) car.a = behavior_accel_[which];
  return car;
}

// Cars keep their order in a lane from one step to the next, so an
// insertion sort finds the new order in one pass.
void TrafficModel::sort_by_lane_and_position() {
  const auto before = [&](CarIndex a, CarIndex b) {
    if (lane_center_[a] != lane_center_[b]) return lane_center_[a] < lane_center_[b];
    return cars_[a].x < cars_[b].x;
  };
  for (std::size_t i = 1; i < order_.size(); ++i) {
    const CarIndex car = order_[i];
    std::size_t j = i;
    for (; j > 0 && before(car, order_[j - 1]); --j) order_[j] = order_[j - 1];
    order_[j] = car;
  }
  for (std::size_t i = 0; i < order_.size(); ++i) rank_[order_[i]] = i;
}

// The cars after `which` in order_ are those at or ahead of it in its lane.
// The nearest by bumper gap wins (the lowest index among equals, as a scan
// in the scene's order finds it); a car whose gap, with the longest body of
// the scene, cannot beat the best ends the search, and so do all after it.
TrafficModel::Ahead TrafficModel::ahead_of(CarIndex which, const EgoFootprint& ego) const {
  const CarState& me = cars_[which];
  const double my_lane = lane_center_[which];
  Ahead out{std::numeric_limits<double>::infinity(), me.v, false};
  CarIndex best = cars_.size();
  for (std::size_t p = rank_[which] + 1; p < order_.size(); ++p) {
    const CarIndex other = order_[p];
    const CarState& car = cars_[other];
    if (lane_center_[other] != my_lane) break;
    if (car.x - me.x - 0.5 * (length_[which] + longest_) > out.gap) break;
    if (car.x <= me.x) continue;
    const double g = car.x - me.x - 0.5 * (length_[which] + length_[other]);
    if (g < out.gap || (g == out.gap && other < best)) {
      out = {g, car.v, false};
      best = other;
    }
  }
  // Overlapping: the ego's body reaches into the band of the car's own width.
  const double band = settings_.sees_ego == SeesEgo::InLane ? lane_width_ : width_[which];
  if (body_in_lane(ego.y, vehicle_.width, my_lane, band)) {
    const double g = ego.x - me.x - 0.5 * (length_[which] + vehicle_.length);
    if (ego.x > me.x && g < out.gap) out = {g, ego.v, true};
  }
  return out;
}

double TrafficModel::acceleration_of(CarIndex which, const EgoFootprint& ego, double dt) {
  follows_[which] = 0;
  followed_ego_[which] = 0;
  const CarState& me = cars_[which];
  // step() takes a replayed car's whole state, its a included, from its record.
  if (behavior_[which] == Behavior::Replay) return 0.0;
  const Ahead ahead = ahead_of(which, ego);
  const bool has_ahead = std::isfinite(ahead.gap);
  if (behavior_[which] == Behavior::Idm) {
    followed_ego_[which] = has_ahead && ahead.is_ego ? 1 : 0;
    return std::max(idm_acceleration(idm_, me.v, ahead.gap, ahead.speed), -max_decel_);
  }
  if (!settings_.followers_react || !has_ahead) return behavior_accel_[which];
  // Where its behavior stays within Krauss's safe speed, a car keeps it.
  CarState by_behavior = me;
  by_behavior.a = behavior_accel_[which];
  advance_constant_accel(by_behavior, dt, speed_cap_);
  const double safe = krauss_safe_speed(ahead.gap - settings_.min_gap, me.v, ahead.speed,
                                        settings_.reaction_time, settings_.follow_decel);
  if (safe >= by_behavior.v) return behavior_accel_[which];
  follows_[which] = 1;
  followed_ego_[which] = ahead.is_ego ? 1 : 0;
  return std::max((std::max(safe, 0.0) - me.v) / dt, -max_decel_);
}

// Ballistic update with a stop instead of reversing (Treiber and Kesting).
void TrafficModel::advance_ballistic(CarState& c, double dt) const {
  if (integration_ == TrafficIntegration::Euler) {
    c.v = std::max(0.0, c.v + c.a * dt);
    c.x += c.v * dt;
  } else if (c.v + c.a * dt < 0.0) {
    c.x += c.v * c.v / (2.0 * std::max(-c.a, 1e-9));
    c.v = 0.0;
  } else {
    c.x += c.v * dt + 0.5 * c.a * dt * dt;
    c.v += c.a * dt;
  }
}

void TrafficModel::step(double dt, const EgoFootprint& ego) {
  // Every car reacts to the others where they are now, before any moves.
  sort_by_lane_and_position();
  for (CarIndex i = 0; i < cars_.size(); ++i) accel_[i] = acceleration_of(i, ego, dt);
  for (CarIndex i = 0; i < cars_.size(); ++i) {
    cars_[i].a = accel_[i];
    if (behavior_[i] == Behavior::Replay) {
      cars_[i] = records_[i]->at(time_ + dt);
    } else if (behavior_[i] == Behavior::Idm || follows_[i] != 0) {
      advance_ballistic(cars_[i], dt);
    } else {
      advance_constant_accel(cars_[i], dt, speed_cap_);
    }
  }
  time_ += dt;
}

TrafficPrediction predict_traffic(const Scenario& scenario, const Config& config, int steps,
                                  double dt, const std::vector<EgoFootprint>* ego_path) {
  TrafficModel model;
  TrafficPrediction out;
  predict_traffic(scenario, config, steps, dt, ego_path, model, out);
  return out;
}

void predict_traffic(const Scenario& scenario, const Config& config, int steps, double dt,
                     const std::vector<EgoFootprint>* ego_path, TrafficModel& model,
                     TrafficPrediction& out) {
  model.reset(scenario, config);
  out.dt = dt;
  resize_keeping(out.cars, scenario.car_count(), out.spare);
  for (auto& track : out.cars) {
    for (auto* series : {&track.x, &track.v, &track.a}) {
      series->clear();
      series->reserve(steps + 1);
    }
    track.present.clear();
  }
  auto record = [&] {
    for (CarIndex i = 0; i < out.cars.size(); ++i) {
      out.cars[i].x.push_back(model.car(i).x);
      out.cars[i].v.push_back(model.car(i).v);
    }
  };
  record();
  for (int k = 0; k < steps; ++k) {
    EgoFootprint ego{scenario.ego.x + scenario.ego.v * k * dt, scenario.ego.y, scenario.ego.v};
    if (ego_path != nullptr && k < static_cast<int>(ego_path->size())) ego = (*ego_path)[k];
    model.step(dt, ego);
    for (CarIndex i = 0; i < out.cars.size(); ++i) out.cars[i].a.push_back(model.car(i).a);
    record();
  }
  for (auto& track : out.cars) track.a.push_back(track.a.empty() ? 0.0 : track.a.back());
}

}  // namespace lanechange
