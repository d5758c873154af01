#include "lanechange/sampler.hpp"

#include <algorithm>

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

ScenarioSampler::ScenarioSampler(Config config, std::uint64_t seed)
    : config_(std::move(config)), seed_(seed) {
  config_.validate();
}

Scenario ScenarioSampler::sample(std::uint64_t index, std::optional<Behavior> behavior) const {
  Rng rng(scenario_seed(seed_, index));
  const SamplerSettings& p = config_.sampler;
  Scenario s = three_car_scenario(config_);
  // Draw every number, used or not, so that a scenario's cars do not depend on its behavior.
  const int behavior_draw = static_cast<int>(rng.uniform(0.0, 3.0));
  s.set_behavior(behavior.value_or(static_cast<Behavior>(behavior_draw)));
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
  validate_scenario(s);
  return s;
}

}  // namespace lanechange
