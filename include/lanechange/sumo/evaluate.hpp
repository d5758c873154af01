#pragma once
// Many SUMO episodes (docs/sumo.md, "Many episodes"): highway seeds at given
// densities, or every CommonRoad interactive folder of a directory, each run
// by every planner named, resumable after a kill, with
// evaluate's rollouts.csv and summary.csv (the behavior column names the
// traffic: "highway_15" for 15 cars per lane and km).
#include <string>
#include <vector>

#include "lanechange/config.hpp"
#include "lanechange/sim/evaluate.hpp"
#include "lanechange/sumo/cosim.hpp"

namespace lanechange::sumo {

struct EvaluateOptions {
  std::vector<double> densities;  ///< cars per lane and km, one group of episodes each
  long long count = 0;            ///< episodes per density
  /// Instead of the highway: one episode per interactive scenario folder
  /// (a subfolder holding NAME.cr.xml) of this directory, by name; the
  /// behavior column reads "commonroad".
  std::string commonroad_dir;
  int seed = 1;  ///< episode i of a density has seed + i
  std::vector<std::string> planners;
  std::string model_dir;
  std::string out_dir;
  long long shard_size = 5;
  HighwaySettings highway;  ///< all but density and seed, which each episode sets
  CoSimSettings loop;       ///< all but work_dir, which each worker sets under out_dir
  Config config;
  sim::PlannerFactory make_planner = planner::make_planner;
};

/// Runs (or resumes) the episodes, the planners made with as_sumo_drives(config).
/// libsumo holds one simulation per process,
/// so `run.jobs` worker processes (forked; 0: one per core) share the shards
/// of this rank. Throws InputError for bad options or a directory holding
/// another evaluation (left untouched); std::runtime_error naming the failed
/// worker's error.
sim::EvaluateReport evaluate(const EvaluateOptions& options, const sim::EvaluateRun& run);

/// The behavior column of a density's episodes: "highway_15".
[[nodiscard]] std::string highway_group(double density);

}  // namespace lanechange::sumo
