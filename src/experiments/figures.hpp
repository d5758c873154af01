#pragma once
// The report's summary figures, drawn by gnuplot from a run's rollouts.
#include <string>
#include <vector>

#include "lanechange/dagger/dagger.hpp"
#include "lanechange/sim/evaluate.hpp"

namespace lanechange::experiments {

/// Success per planner, grouped by the other cars' behavior (bars).
void plot_success_bars(const std::vector<sim::RolloutRow>& rows,
                       const std::vector<std::string>& planners, const std::string& png_path);

/// The distribution of each rollout's median step time per planner, as
/// cumulative shares over a logarithmic time axis.
void plot_step_times(const std::vector<sim::RolloutRow>& rows,
                     const std::vector<std::string>& planners, const std::string& png_path);

/// The DAgger curve: mlp-miqp's success and take-overs per round, with
/// miqp's success as the line to reach.
void plot_dagger(const dagger::DaggerReport& report, const std::string& png_path);

}  // namespace lanechange::experiments
