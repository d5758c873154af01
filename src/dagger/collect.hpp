#pragma once
// DAgger's data collection: the learner drives, the expert labels.
#include <cstdint>
#include <ostream>
#include <string>
#include <vector>

#include "data/rows.hpp"
#include "data/shard.hpp"
#include "lanechange/config.hpp"
#include "lanechange/scenario.hpp"
#include "planner/mlp_miqp_planner.hpp"

namespace lanechange::dagger::detail {

/// `config` with the step budget lifted. DAgger's labels and its scoring
/// measure what the network learnt, not the machine: under a budget a loaded
/// machine cuts the take-over's plans short and hands steps to the fallback,
/// which moved one model's take-overs by up to 0.014 per rollout between
/// scorings (docs/dagger.md).
[[nodiscard]] Config untimed(const Config& config);

/// The expert's plan from one visited state, cut to its first nodes: node 0
/// holds the observation's inputs and the control the expert applies there.
struct Query {
  data::PlanOutcome outcome;
};

/// Which states the expert labels, and how much of its plan is kept.
struct Labelling {
  int stride = 1;  ///< every stride-th step the network drives
  int nodes = 1;   ///< of each plan, from node 0; 0: the whole plan
  double time_limit_s = 60.0;
  /// Roll out on scenes the classifier refuses too; by default only where
  /// mlp-miqp would let the network drive.
  bool every_scene = false;
  /// The learner drives with mlp-miqp's check, and the labels end at the
  /// take-over (DaggerOptions::rollout).
  bool gated = false;
  /// When gated: seconds past the take-over in which the expert's recovery
  /// is labelled too (HG-DAgger); 0: the labels end at the take-over.
  double past_takeover_s = 0.0;
  /// When gated: label the failed look-ahead's states at the take-over
  /// (DaggerOptions::label_lookahead).
  bool lookahead = false;
  /// Label with the expert's own lane strategy for the scene: its plan from
  /// the scene's start gives the lane modes, and a state's label is the
  /// plan with those modes fixed (shifted to the state's step), the free
  /// search only where they leave no well-posed plan
  /// (DaggerOptions::label_strategy).
  bool fixed_strategy = false;
  /// Ross et al.'s beta: at each step the network drives, the expert's own
  /// control (its plan's first, or miqp's lane keeper where it has none)
  /// acts instead with this probability; 0: the learner alone. Not with
  /// `gated`, whose take-over already hands steps to the expert.
  double expert_share = 0.0;
  /// The coin's seed; collect_round draws one per scene from its sub-seed,
  /// so a scene's mixture is the same whatever thread rolls it out.
  std::uint64_t coin_seed = 0;
};

/// Rolls the learner's network out on `scene` (with mlp-miqp's take-over
/// when labelling.gated, when the labels stop) and asks
/// `learner`'s expert for a plan at the states `labelling` names; no queries
/// where the classifier refuses the scene, unless labelling.every_scene.
[[nodiscard]] std::vector<Query> collect_scene(const Scenario& scene,
                                               const planner::MlpMiqpPlanner& learner,
                                               const Config& config, const Labelling& labelling);

struct RoundData {
  data::ShardRange range;  ///< the shard written
  long long labelled = 0;  ///< queries answered with a well-posed plan
  long long samples = 0;   ///< rows of those plans in the samples file
  long long refused = 0;   ///< scenes the classifier refused (not rolled out)
};

/// Collects the labels of scenes [first_scene, first_scene + scenes) on
/// `jobs` threads and writes them as shard `shard` of `dir`, scenario
/// indices from `first_index`, in scene order whatever the threads did.
struct CollectJob {
  const planner::MlpMiqpPlanner& learner;
  const Config& config;
  std::uint64_t scene_seed = 0;
  long long first_scene = 0;
  long long scenes = 0;
  Labelling labelling;
  int jobs = 1;
  std::ostream* progress = nullptr;  ///< one line every few seconds (none if null)
};
[[nodiscard]] RoundData collect_round(const CollectJob& job, const std::string& dir,
                                      long long shard, long long first_index);

}  // namespace lanechange::dagger::detail
