#pragma once
// Seeded random scenarios (distribution in docs/scenarios.md). Scenario i of
// a seed is drawn from its own sub-seed, so it is the same whichever worker,
// thread or rank draws it and in whatever order.
#include <array>
#include <cstdint>
#include <optional>

#include "lanechange/config.hpp"
#include "lanechange/scenario.hpp"

namespace lanechange {

/// A small, portable generator (splitmix64). std::uniform_real_distribution is
/// not the same across standard libraries; this is.
class Rng {
 public:
  explicit Rng(std::uint64_t seed) : state_(seed) {}
  std::uint64_t next();
  /// Uniform in [lo, hi).
  double uniform(double lo, double hi);
  double uniform(const Interval& range) { return uniform(range.lo, range.hi); }

 private:
  std::uint64_t state_;
};

/// The behaviors the sampler draws, in the order of its draw (a replayed car
/// needs a record, which only an imported scene has).
inline constexpr std::array<Behavior, 3> kSampledBehaviors = {
    Behavior::ConstantSpeed, Behavior::ConstantAccel, Behavior::Idm};

/// The sub-seed of scenario `index` under `seed`.
[[nodiscard]] std::uint64_t scenario_seed(std::uint64_t seed, std::uint64_t index);

class ScenarioSampler {
 public:
  ScenarioSampler(Config config, std::uint64_t seed);
  /// Scenario `index`. With no behavior given, it is drawn too (uniformly).
  /// The paper's three cars, or dense traffic where sampler.target_lane_cars
  /// asks for it.
  [[nodiscard]] Scenario sample(std::uint64_t index,
                                std::optional<Behavior> behavior = std::nullopt) const;

 private:
  [[nodiscard]] Scenario three_cars(Rng& rng, Behavior behavior) const;
  [[nodiscard]] Scenario dense(Rng& rng, Behavior behavior) const;

  Config config_;
  std::uint64_t seed_;
};

}  // namespace lanechange
