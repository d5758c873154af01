#pragma once
// `lanechange experiments` (docs/experiments.md): one command that runs the
// paper's experiments end to end — expert data, models, Table I, the closed
// loop of every planner (Tables II and III under both lane rules, under the
// paper's own formulation and in dense traffic), the generalization test,
// DAgger and the figures — and writes a report with the paper's
// numbers beside ours. Every stage records its inputs; a rerun reuses a stage
// whose inputs have not changed and resumes one that was killed.
#include <ostream>
#include <string>
#include <string_view>
#include <vector>

#include "lanechange/config.hpp"
#include "lanechange/data/dataset.hpp"

namespace lanechange::experiments {

enum class Scale {
  Tiny,   ///< the CI test: every table and figure, from a handful of scenes
  Small,  ///< the demo: at most 15 minutes on 2 cores
  Paper,  ///< the paper's data and learning sizes
};
[[nodiscard]] std::string_view to_string(Scale scale);
/// InputError naming `field` for an unknown name.
[[nodiscard]] Scale scale_from_string(std::string_view name, std::string_view field);

struct ExperimentSizes {
  long long data_per_behavior = 0;  ///< expert scenarios per behavior for learning
  long long eval_per_behavior = 0;  ///< closed-loop scenarios per behavior
  bool quick_search = false;        ///< smaller hyperparameter grids
  int max_epochs = 300;             ///< of the action network
  /// Scenes drawn for every planner: a congested one and ill-posed ones (the
  /// paper's Figs. 4 and 5).
  int example_scenes = 4;
  /// DAgger on the experiments' model (docs/dagger.md): rounds and the training
  /// scenes rolled out per round; mlp-miqp is scored after every round on as
  /// many held-out scenes as Table II has, of all behaviors.
  int dagger_rounds = 0;
  long long dagger_scenes = 0;
  /// SUMO episodes per density of the built-in highway (docs/sumo.md).
  long long sumo_episodes = 0;
};
[[nodiscard]] ExperimentSizes sizes_of(Scale scale);

struct ExperimentOptions {
  std::string out_dir;
  Scale scale = Scale::Small;
  long long eval_count = 0;  ///< closed-loop scenarios per behavior; 0: the scale's
  /// Planners of Tables II and III; empty: ours, the baselines and keep-lane.
  std::vector<std::string> planners;
  int jobs = 0;  ///< worker threads; 0: one per core
  Config config;
  bool figures = true;  ///< PNGs (needs gnuplot)
  std::ostream* progress = nullptr;
  bool progress_on_terminal = false;
  /// The MPI ranks sharing the run: the data and evaluation stages split
  /// their shards over them; rank 0 alone trains, draws and writes the
  /// report. None: this process alone.
  run::Team* team = nullptr;
  /// A directory of CommonRoad interactive scenario folders, run in SUMO
  /// beside the built-in highway (docs/sumo.md); empty: the highway alone.
  std::string commonroad_dir;
};

struct StageRecord {
  std::string name;
  bool reused = false;  ///< its inputs had not changed since a finished run
  double wall_s = 0.0;  ///< of the run that made it
};

struct ExperimentReport {
  std::vector<StageRecord> stages;
  std::string report_md;    ///< path
  std::string report_html;  ///< path
  double wall_s = 0.0;
};

/// Runs (or resumes) every stage and writes DIR/report.md and
/// DIR/report.html (on rank 0; the other ranks' report names no files).
/// InputError for bad options, before anything is written.
ExperimentReport run_experiments(const ExperimentOptions& options);

/// The commit the program was built from ("-dirty" if the tree had changes;
/// "unknown" outside a git checkout): part of every stage's inputs.
[[nodiscard]] std::string code_version();

}  // namespace lanechange::experiments
