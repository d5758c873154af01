#pragma once
// DAgger for the action network (Ross et al. 2011; docs/dagger.md): roll the learner out in closed
// loop on training scenes, ask the expert to plan from the states it visits, add those labels to
// the data, retrain the network, and measure mlp-miqp on held-out scenes after every round.
#include <cstdint>
#include <ostream>
#include <string>
#include <string_view>
#include <vector>

#include "lanechange/config.hpp"
#include "lanechange/learn/train.hpp"

namespace lanechange::dagger {

/// Who drives the rollouts that the expert labels.
enum class Rollout {
  /// The bare network to the scene's end (Ross et al.'s DAgger): it labels
  /// states past the point where mlp-miqp's check would have taken over.
  Network,
  /// mlp-miqp itself (after HG-DAgger, Kelly et al. 2019): the expert labels
  /// the states the network drives through while its check passes and the
  /// state of the take-over (and past_takeover_s of its recovery).
  Gated,
};

[[nodiscard]] std::string_view to_string(Rollout rollout);
/// "network" or "gated"; InputError naming `field` otherwise.
[[nodiscard]] Rollout parse_rollout(std::string_view name, const char* field);

struct DaggerOptions {
  /// The base model's training (data sets, seed, settings); its out_dir is
  /// where the final model (the last round's) is published.
  learn::TrainOptions train;
  std::string work_dir;  ///< rounds' models, evaluations, labels, tables
  int rounds = 1;
  long long scenes = 100;  ///< training scenes rolled out per round (fresh ones each round)
  std::uint64_t scene_seed = 7001;   ///< sampler seed of those scenes
  int stride = 1;                    ///< the expert labels every stride-th step
  int label_nodes = 1;               ///< nodes kept of each expert plan; 0: all
  long long eval_count = 100;        ///< held-out scenes per evaluation
  std::uint64_t eval_seed = 2026;    ///< must differ from scene_seed and the data's seeds
  double label_time_limit_s = 60.0;  ///< per expert plan, as `generate`'s default
  /// Roll the learner out on scenes the classifier refuses too (the first
  /// version's behaviour); by default only where mlp-miqp lets it drive.
  bool every_scene = false;
  Rollout rollout = Rollout::Network;
  /// Gated only: seconds past the take-over in which the states the expert
  /// drives through (its recovery from the network's state) are labelled
  /// too, as HG-DAgger does; 0: the labels end at the take-over.
  double past_takeover_s = 0.0;
  /// Gated only: at the take-over, the states of the look-ahead that failed
  /// the check (where the network would have driven, up to the failing
  /// node) are labelled too, every stride-th; mlp-miqp's check rolls the
  /// network out there, so those are the states that decide a take-over.
  bool label_lookahead = false;
  /// Label with the expert's lane strategy for the scene fixed: each state's
  /// label is the plan with the modes of the expert's plan from the scene's
  /// start (the free search where they leave no well-posed plan). The free
  /// expert's first control jumps with its strategy between nearby states.
  bool fixed_strategy = false;
  /// Each round's retrain starts from the last round's network and keeps
  /// round 0's standardizers, instead of fresh weights on refitted ones.
  bool fine_tune = false;
  /// Round r's policy is the mean action of the networks of rounds 0..r
  /// (each retrained as without it), so that it rolls out and is scored as
  /// that average. DAgger's guarantee (Ross et al. 2011) holds for the best
  /// round or the mixture of the rounds' policies; the average is the
  /// mixture's deterministic form, and it damps the retrains' own scatter.
  bool average = false;
  /// Ross et al.'s mixing (network rollouts only): round r's rollouts let
  /// the expert act at each step with probability beta^r and the last
  /// round's network otherwise, so that the early rounds' states stay nearer
  /// the expert's own. 0: the network alone from round 1 (beta_r = 0 for
  /// r >= 1, the form Ross et al. found best in practice).
  double beta = 0.0;
  /// Adam's learning rate in the retrains; 0: round 0's. A fine-tune at a
  /// smaller rate stays nearer the last round's network.
  double retrain_learning_rate = 0.0;
  /// Retrains per round, each with its own network seed (the first with the
  /// base's); the one with the fewest take-overs per rollout of mlp-miqp on
  /// the selection scenes becomes the round's network. 1: one retrain, no
  /// selection. Retrains differ by as much as a round changes the network,
  /// so one retrain's take-overs are a draw, not the round's effect.
  int candidates = 1;
  /// Selection scenes: drawn like the training scenes, with their own seed
  /// (never the held-out evaluation's), the same every round.
  long long select_count = 300;
  std::uint64_t select_seed = 7002;
  /// Early stopping of a retrain also on DAgger rows; by default on the
  /// base's own validation rows only.
  bool validate_on_dagger = false;
  Config config;  ///< the closed loop's (rollouts, labels, evaluations)
  int jobs = 0;   ///< threads; 0: one per core
  /// A model already trained with `train` to be round 0 (copied into
  /// work_dir/model-0) instead of training one: the experiments' own model.
  std::string base_model;
};

/// One row of dagger.csv: mlp-miqp with round r's model (round 0: before
/// DAgger), or the expert (planner "miqp", round -1) for reference.
struct RoundRow {
  int round = 0;
  std::string planner;
  long long rollouts = 0;
  double success_rate = 0.0;
  double takeovers_per_rollout = 0.0;
  double collision_rate = 0.0;
  double at_fault_collision_rate = 0.0;
  /// Rollouts the classifier lets the network drive (the same every round:
  /// DAgger retrains the network only), and those the check takes from it
  /// at the first step or later. The other take-overs are the expert's
  /// check overruling a refusal, which DAgger does not touch.
  long long driven = 0;
  long long taken_over_at_start = 0;
  long long taken_over_later = 0;
  long long labels = 0;          ///< expert queries answered with a well-posed plan, this round
  long long dagger_samples = 0;  ///< well-posed sample rows in the aggregated data set so far
};

/// One retrain of a round with selection (DaggerOptions::candidates > 1),
/// as selection.csv lists them.
struct Candidate {
  int round = 0;
  int candidate = 0;  ///< 0..candidates-1
  std::uint64_t network_seed_offset = 0;
  double takeovers_per_rollout = 0.0;  ///< on the selection scenes
  double success_rate = 0.0;           ///< on the selection scenes
  bool chosen = false;
};

struct DaggerReport {
  std::vector<RoundRow> rounds;       ///< round 0..R
  std::vector<Candidate> candidates;  ///< empty without selection
  RoundRow expert;
  std::string dataset_dir;  ///< the aggregated labels (none when R = 0)
};

/// Runs (or resumes: finished steps are kept) R rounds. InputError for bad
/// options (R < 0, no scenes, ...), missing data or a work_dir that holds
/// another DAgger run.
DaggerReport run(const DaggerOptions& options, std::ostream* progress);

/// dagger.csv's columns, and the same rows as a markdown table.
[[nodiscard]] std::vector<std::string> table_columns();
[[nodiscard]] std::string markdown_table(const DaggerReport& report);

/// The rows of a finished run, read back from work_dir/dagger.csv (the
/// data set's path is not kept there). InputError naming the file when it
/// is missing or malformed.
[[nodiscard]] DaggerReport read_report(const std::string& work_dir);

}  // namespace lanechange::dagger
