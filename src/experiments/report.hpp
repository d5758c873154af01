#pragma once
// The report of a run: every number read from the run's own files.
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "experiments/document.hpp"
#include "experiments/tables.hpp"
#include "lanechange/experiments/experiments.hpp"
#include "lanechange/sim/evaluate.hpp"

namespace lanechange::experiments {

struct ExampleScene {
  std::string name;  ///< file stem under figures/
  std::string behavior;
  long long index = 0;
  std::string why;  ///< why this scene was chosen
};

struct ReportInputs {
  const ExperimentOptions* options = nullptr;
  ExperimentSizes sizes;
  std::vector<std::string> planners;
  std::vector<std::string> expert_planners;  ///< those run under both lane rules
  nlohmann::json metrics;                    ///< the model's metrics.json
  std::vector<sim::RolloutRow> footprint;    ///< the default lane rule
  std::vector<sim::RolloutRow> either_or;    ///< the literal rule (baselines' rows copied)
  std::vector<sim::RolloutRow> paper;        ///< the paper's formulation and traffic
  std::vector<sim::RolloutRow> dense;        ///< dense traffic, the default formulation
  Interval dense_target_lane_cars;
  nlohmann::json dense_metrics;       ///< the dense model's metrics.json
  std::vector<sim::RolloutRow> sumo;  ///< SUMO traffic: the highway and CommonRoad folders
  std::vector<double> sumo_densities;
  std::optional<double> car_decel_limit;  ///< traffic.max_decel of the run
  ExpertLabels labels;
  std::vector<ExampleScene> examples;
  std::optional<dagger::DaggerReport> dagger;  ///< none when DAgger did not run
  dagger::DaggerOptions dagger_options;
  std::map<std::string, std::uint64_t> seeds;
  std::vector<StageRecord> stages;
  double wall_s = 0.0;
};

[[nodiscard]] Document build_report(const ReportInputs& in);

}  // namespace lanechange::experiments
