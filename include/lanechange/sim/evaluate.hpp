#pragma once
// Many closed-loop rollouts (docs/closed_loop.md, "evaluate"): sampled
// scenarios, each run by every planner named, on threads, resumable after a
// kill. Writes rollouts.csv (a row per scenario and planner) and summary.csv
// (rates and percentiles per planner and behavior).
#include <cstdint>
#include <functional>
#include <memory>
#include <optional>
#include <ostream>
#include <span>
#include <string>
#include <vector>

#include "lanechange/config.hpp"
#include "lanechange/data/dataset.hpp"
#include "lanechange/planner/planner.hpp"
#include "lanechange/scenario.hpp"

namespace lanechange::sim {

/// Builds a planner by name; throws InputError for an unknown one. Later
/// stages (the baselines) know more planners than planner::make_planner.
using PlannerFactory = std::function<std::shared_ptr<const planner::ClosedLoopPlanner>(
    std::string_view name, const Config& config, const std::string& model_dir)>;

struct EvaluateOptions {
  long long count = 0;  ///< sampled scenes; with scenarios_dir: none
  std::uint64_t seed = 0;
  std::optional<Behavior> behavior;  ///< none: each scenario's own draw
  /// Roll out every scene file (*.json) of this folder, in the order of their
  /// names, instead of sampled scenes; scenes.csv maps each index to its file.
  std::string scenarios_dir;
  std::vector<std::string> planners;
  std::string model_dir;  ///< for mlp-miqp
  std::string out_dir;
  long long shard_size = 20;
  double duration = 0.0;  ///< s per rollout; 0: horizon + settle time
  Config config;
  PlannerFactory make_planner = planner::make_planner;
};

struct EvaluateRun {
  int jobs = 0;  ///< worker threads; 0: one per core
  std::ostream* progress = nullptr;
  bool progress_on_terminal = false;
  /// The MPI ranks sharing the run (shard s on rank s mod size); none: alone.
  run::Team* team = nullptr;
};

struct EvaluateReport {
  long long shards_total = 0;
  long long shards_skipped = 0;  ///< finished by an earlier run
  long long rollouts = 0;        ///< run by this call
  double wall_s = 0.0;
};

/// Runs (or resumes) an evaluation. Throws InputError for bad options or an
/// output directory that holds another evaluation (left untouched).
EvaluateReport evaluate(const EvaluateOptions& options, const EvaluateRun& run);

/// One row of rollouts.csv (docs/closed_loop.md); NaN where the cell is empty.
struct RolloutRow {
  long long index = 0;
  std::string behavior, planner, outcome, reason;
  bool collision = false;
  bool at_fault = false;
  bool unsafe_cut_in = false;  ///< RolloutMetrics::unsafe_cut_in
  bool cars_collide = false;   ///< RolloutMetrics::cars_collide
  double takeovers = 0, fallbacks = 0, overruns = 0, failures = 0, clipped = 0;
  double time_to_target_lane = 0, min_gap = 0, min_ttc = 0, max_abs_accel = 0, rms_jerk = 0;
  double max_abs_omega = 0, median_step_ms = 0, p99_step_ms = 0, max_step_ms = 0;
  double first_takeover_t = 0;                 ///< s; NaN: none
  double forced_decel = 0, max_car_decel = 0;  ///< m/s^2
  double time_to_lane_line = 0;                ///< s; NaN: never
  std::string target_lane_slot;                ///< RolloutMetrics::target_lane_slot
  /// The ids of the target-lane cars behind and ahead of the ego at the end
  /// (the rollout's details.gap); empty where none.
  std::string gap_behind, gap_ahead;
  [[nodiscard]] bool success() const { return outcome == "well_posed" && !collision; }
};

/// The shares of outcomes over some rollouts, as summary.csv gives them per
/// planner and behavior; every table of rates uses this one definition.
struct RolloutRates {
  long long rollouts = 0;
  double success = 0, ill_posed = 0, failure = 0, aborted = 0;  ///< shares (success: no collision)
  double collision = 0, at_fault = 0;                           ///< shares
  double unsafe_cut_in = 0, cars_collide = 0;                   ///< shares
  double takeovers = 0, fallbacks = 0, overruns = 0;            ///< per rollout
};
/// All zero for no rows.
[[nodiscard]] RolloutRates rates_of(std::span<const RolloutRow* const> rows);

/// Each planner beside the recorded drivers, over the scenes cut from
/// recordings in which the driver changed into the target lane
/// (SceneOrigin::human_change; docs/recorded.md).
struct HumanComparison {
  std::string planner;
  long long scenes = 0;     ///< scenes where the driver changed into the target lane
  long long changed = 0;    ///< of them, rollouts whose ego's centre crossed into it too
  long long same_gap = 0;   ///< of those, ended between the two cars the driver went between
  long long succeeded = 0;  ///< of the scenes, successful rollouts
  /// s: when the rollout's ego crossed into the target lane minus when the
  /// driver did (both the centre crossing the line), median over `changed`
  /// (NaN for none); negative is sooner than the driver.
  double time_difference_p50 = 0.0;
};
/// `rows` index `scenes` (evaluate --scenarios); planners in the given order.
[[nodiscard]] std::vector<HumanComparison> compare_with_humans(
    std::span<const Scenario> scenes, std::span<const RolloutRow> rows,
    const std::vector<std::string>& planners);

/// Reads a rollouts.csv (or one of its shards). InputError naming the file
/// for a missing file, a header that is not ours, or a malformed row.
[[nodiscard]] std::vector<RolloutRow> read_rollouts(const std::string& path);

/// The column names of rollouts.csv and summary.csv.
[[nodiscard]] std::vector<std::string> rollout_columns();
[[nodiscard]] std::vector<std::string> summary_columns();

}  // namespace lanechange::sim
