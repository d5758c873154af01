#pragma once
// The report's tables, computed from the files of a run (model metrics,
// rollouts, the expert's open-loop labels), with the paper's numbers beside.
#include <map>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "experiments/document.hpp"
#include "lanechange/dagger/dagger.hpp"
#include "lanechange/sim/evaluate.hpp"

namespace lanechange::experiments {

/// The expert's open-loop label per (behavior, scenario index).
using ExpertLabels = std::map<std::pair<std::string, long long>, std::string>;

/// Reads the scenarios files of data sets. InputError naming a malformed file.
[[nodiscard]] ExpertLabels read_expert_labels(const std::vector<std::string>& dataset_dirs);

/// Table I: held-out accuracy per classifier, without and with the behavior input.
[[nodiscard]] Table classifier_table(const nlohmann::json& metrics);
/// The SVM's row-normalised confusion matrix (the paper's Fig. 3).
[[nodiscard]] Table svm_confusion_table(const nlohmann::json& metrics);

/// Table II: per planner, rates, take-overs, step time and comfort.
[[nodiscard]] Table comparison_table(const std::vector<sim::RolloutRow>& rows,
                                     const std::vector<std::string>& planners);
/// One sentence on the traffic itself: how many rollouts show two other cars
/// overlapping, and the hardest braking of any car against `limit`.
[[nodiscard]] std::string traffic_check(const std::vector<sim::RolloutRow>& rows,
                                        std::optional<double> limit);
/// Table III: success per behavior and planner.
[[nodiscard]] Table behavior_table(const std::vector<sim::RolloutRow>& rows,
                                   const std::vector<std::string>& planners);

struct GeneralizationResult {
  long long ill_posed = 0;  ///< scenes the expert plans ill-posed (open loop)
  Table table;              ///< per planner: the share it ends well-posed
};
[[nodiscard]] GeneralizationResult generalization_table(const std::vector<sim::RolloutRow>& rows,
                                                        const ExpertLabels& labels,
                                                        const std::vector<std::string>& planners);

/// Sentences for every planner whose success beats mlp-miqp's, with the
/// measured reasons (aborts, take-overs, collisions).
[[nodiscard]] std::vector<std::string> where_others_beat_ours(
    const std::vector<sim::RolloutRow>& rows, const std::vector<std::string>& planners);

/// DAgger's rounds (0: before DAgger) and the expert for reference.
[[nodiscard]] Table dagger_table(const dagger::DaggerReport& report);
/// The two DAgger targets, judged on the rows: take-overs fall with
/// every round, and mlp-miqp ends within 2 points of miqp's success.
[[nodiscard]] std::vector<std::string> dagger_verdicts(const dagger::DaggerReport& report);

/// The share as a percentage with one decimal ("–" for an empty set).
[[nodiscard]] std::string percent(long long part, long long whole);

}  // namespace lanechange::experiments
