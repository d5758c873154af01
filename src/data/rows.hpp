#pragma once
// The CSV rows of a shard (docs/dataset.md). Numbers are written in their
// shortest exact form (std::to_chars), so a file is the same on every run and
// a reader gets the very doubles we had.
#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include "lanechange/expert/gap_slots.hpp"
#include "lanechange/scenario.hpp"
#include "lanechange/trajectory.hpp"

namespace lanechange::data {

/// What planning one scenario gave: a plan, a failure, or an exception.
struct PlanOutcome {
  std::string status;  ///< PlanStatus name, or "exception"
  std::string reason;  ///< empty for well-posed
  Label label = Label::Failure;
  bool collision = false;
  double objective = 0.0;  ///< not finite when there is no solution
  int iterations = 0;
  double solve_ms = 0.0;
  Trajectory trajectory;  ///< no nodes when there is no solution
  /// Lanes the plan lets the ego occupy per node (-1 none, else the
  /// LaneOccupancy value); as long as the trajectory, or empty.
  std::vector<int> lane_modes;
  /// The slot (expert::GapSlots) of the gap the plan takes: -1 without a
  /// solution, or for a gap further out than the slots reach.
  int gap_slot = -1;
  std::string gap_behind, gap_ahead;  ///< ids of the cars framing it; empty where open
  expert::GapFrame gap_frame;         ///< the same cars by index
  /// The label of the best plan through each slot's gap alone (label_gaps);
  /// none where the slot has no gap or the labels were not asked for.
  std::array<std::optional<Label>, expert::kGapSlots> slot_labels;
};

/// One scenario's lines in each of a shard's three files.
struct ScenarioRows {
  std::string scenarios;
  std::string samples;
  std::string timing;
};

[[nodiscard]] std::vector<std::string> scenario_columns();
[[nodiscard]] std::vector<std::string> sample_columns();
[[nodiscard]] std::vector<std::string> timing_columns();
/// Which sample columns feed which model (written into the manifest).
[[nodiscard]] std::vector<std::string> classifier_features();
[[nodiscard]] std::vector<std::string> action_inputs();
/// The inputs of a network that drives to a chosen gap: the ego's time,
/// lateral place, speed and heading, and expert::gap_view.
[[nodiscard]] std::vector<std::string> gap_action_inputs();
[[nodiscard]] std::vector<std::string> action_targets();
/// The scene columns that describe it through its gap slots (the gap
/// classifier's inputs).
[[nodiscard]] std::vector<std::string> gap_classifier_features();

/// The header line of each file.
[[nodiscard]] ScenarioRows header_rows();
[[nodiscard]] ScenarioRows scenario_rows(std::uint64_t index, std::uint64_t sub_seed,
                                         const Scenario& scenario, const PlanOutcome& outcome);

}  // namespace lanechange::data
