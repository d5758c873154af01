#include "lanechange/sampler.hpp"

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

namespace lanechange {

std::uint64_t Rng::next() {
  std::uint64_t z = (state_ += 0x9E3779B97F4A7C15ULL);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
  return z ^ (z >> 31);
}

double Rng::uniform(double lo, double hi) {
  constexpr double kUnit = 1.0 / 9007199254740992.0;  // 2^-53
  return lo + (hi - lo) * static_cast<double>(next() >> 11) * kUnit;
}

std::uint64_t scenario_seed(std::uint64_t seed, std::uint64_t index) {
  Rng mixer(seed ^ (index * 0xD1B54A32D192ED03ULL));
  mixer.next();
  return mixer.next();
}

namespace {

// The largest speed by which a car may close in on the car ahead and still
// match its speed within their bumper gap, braking at `brake` after a step
// of `dt`: dv dt + dv^2 / (2 brake) = gap.
double resolvable_closing(double gap, double brake, double dt) {
  return brake * (std::sqrt(dt * dt + 2.0 * std::max(gap, 0.0) / brake) - dt);
}

// A platoon car (cars first.. of `s`, back to front) faster than the car ahead
// keeps no more speed than braking at traffic.max_decel, less the car ahead's
// own braking, can still take off within their gap: a scene starts with no
// collision that no driver could avoid.
void keep_platoon_avoidable(Scenario& s, std::size_t first, const Config& config) {
  if (!config.traffic.max_decel) return;
  const double own_braking =
      s.behavior == Behavior::ConstantAccel ? std::max(0.0, -config.sampler.accel.lo) : 0.0;
  const double brake = *config.traffic.max_decel - own_braking;
  if (brake <= 0.0) return;
  const double dt = s.horizon / s.steps;
  for (std::size_t i = s.cars.size() - 1; i > first; --i) {
    const CarState& ahead = s.cars[i].state;
    CarState& behind = s.cars[i - 1].state;
    const double gap = ahead.x - behind.x - s.vehicle.length;
    behind.v = std::min(behind.v, ahead.v + resolvable_closing(gap, brake, dt));
  }
}

}  // namespace

ScenarioSampler::ScenarioSampler(Config config, std::uint64_t seed)
    : config_(std::move(config)), seed_(seed) {
  config_.validate();
}

Scenario ScenarioSampler::sample(std::uint64_t index, std::optional<Behavior> behavior) const {
  Rng rng(scenario_seed(seed_, index));
  // Draw every number, used or not, so that a scenario's cars do not depend on its behavior.
  const auto behavior_draw =
      static_cast<std::size_t>(rng.uniform(0.0, static_cast<double>(kSampledBehaviors.size())));
  const Behavior b = behavior.value_or(kSampledBehaviors.at(behavior_draw));
  Scenario s = config_.sampler.target_lane_cars.hi > 0 ? dense(rng, b) : three_cars(rng, b);
  validate_scenario(s);
  return s;
}

Scenario ScenarioSampler::three_cars(Rng& rng, Behavior behavior) const {
  const SamplerSettings& p = config_.sampler;
  Scenario s = three_car_scenario(config_);
  s.set_behavior(behavior);
  s.leader().v = rng.uniform(p.leader_speed);
  s.follower().v = rng.uniform(p.follower_speed);
  s.target().v = rng.uniform(p.target_speed);
  s.ego.v = s.leader().v * rng.uniform(p.ego_speed_ratio);
  const double headway = rng.uniform(p.leader_headway);
  s.leader().x = s.ego.x + std::max(headway * s.ego.v, s.vehicle.length + 1.0);
  s.follower().x = s.ego.x + rng.uniform(p.follower_offset);
  s.target().x = s.follower().x + s.vehicle.length + rng.uniform(p.gap_length);
  const double a_leader = rng.uniform(p.accel);
  const double a_follower = rng.uniform(p.accel);
  const double a_target = rng.uniform(p.accel);
  if (s.behavior == Behavior::ConstantAccel) {
    s.leader().a = a_leader;
    s.follower().a = a_follower;
    s.target().a = a_target;
  }
  return s;
}

// A leader and a car behind in the ego lane, and a platoon of the drawn size
// in the target lane whose bumper gaps are drawn as the paper's one gap is;
// the ego stands anywhere along the platoon. Roles go to the nearest cars.
Scenario ScenarioSampler::dense(Rng& rng, Behavior behavior) const {
  const SamplerSettings& p = config_.sampler;
  Scenario s = default_scenario(config_);
  s.behavior = behavior;
  const double length = s.vehicle.length;
  auto add = [&s, &rng, &p, behavior](std::string id, Lane lane, double x, double v) {
    const double a = rng.uniform(p.accel);
    s.cars.push_back({std::move(id),
                      lane,
                      {x, v, behavior == Behavior::ConstantAccel ? a : 0.0},
                      behavior,
                      std::nullopt,
                      std::nullopt});
  };
  const double leader_v = rng.uniform(p.leader_speed);
  s.ego.v = leader_v * rng.uniform(p.ego_speed_ratio);
  add("leader", Lane::Ego,
      s.ego.x + std::max(rng.uniform(p.leader_headway) * s.ego.v, length + 1.0), leader_v);
  // The car behind drives about as fast as the ego, and at least as far back
  // as it follows the ego without braking (Krauss's safe speed at its own):
  // a scene does not start with the ego forcing it to brake.
  const double rear_v = s.ego.v * rng.uniform(p.ego_speed_ratio);
  const TrafficSettings& t = config_.traffic;
  const double calm_gap = t.min_gap + s.ego.v * t.reaction_time +
                          std::max(0.0, rear_v - s.ego.v) *
                              ((s.ego.v + rear_v) / (2.0 * t.follow_decel) + t.reaction_time);
  const double rear_gap = std::max({rng.uniform(p.rear_headway) * rear_v, calm_gap, 1.0});
  add("rear", Lane::Ego, s.ego.x - length - rear_gap, rear_v);
  const auto count =
      static_cast<int>(std::floor(rng.uniform(p.target_lane_cars.lo, p.target_lane_cars.hi + 1.0)));
  std::vector<double> gaps;
  double span = 0.0;
  for (int i = 0; i < count; ++i) {
    gaps.push_back(i == 0 ? 0.0 : length + rng.uniform(p.gap_length));
    span += gaps.back();
  }
  double x = s.ego.x - rng.uniform(0.0, 1.0) * span;
  for (int i = 0; i < count; ++i) {
    x += gaps[static_cast<std::size_t>(i)];
    std::string id = "t";  // appended: GCC 12 misreads "t" + to_string (-Wrestrict)
    id += std::to_string(i);
    add(std::move(id), Lane::Target, x, rng.uniform(p.target_speed));
  }
  keep_platoon_avoidable(s, s.cars.size() - static_cast<std::size_t>(count), config_);
  for (const Role role : kRoles) s.roles[static_cast<std::size_t>(role)] = nearest_in_role(s, role);
  return s;
}

}  // namespace lanechange
