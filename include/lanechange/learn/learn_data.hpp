#pragma once
// The expert's data sets as the learning stage sees them (docs/learning.md):
// one classifier row per scenario, one action row per node of a well-posed
// plan, and a split by scenario so a trajectory never straddles train and
// test. Columns are found by the names the manifests list, never by position.
#include <Eigen/Dense>
#include <array>
#include <cstdint>
#include <nlohmann/json.hpp>
#include <random>
#include <string>
#include <string_view>
#include <vector>

#include "lanechange/expert/gap_slots.hpp"

namespace lanechange::learn {

inline constexpr int kClasses = 3;
/// Class c is kLabelNames[c]; the data sets' `label` column spells them so.
inline constexpr std::array<std::string_view, kClasses> kLabelNames = {"well_posed", "ill_posed",
                                                                       "failure"};
inline constexpr int kWellPosed = 0;
inline constexpr int kFailure = 2;
/// The gap classifier's classes: a slot of expert::GapSlots (its gap is the
/// one to take), or kNoGap (no lane change is worth trying).
inline constexpr int kGapClasses = expert::kGapSlots + 1;
inline constexpr int kNoGap = expert::kGapSlots;
inline constexpr int kBehaviors = 3;
/// The order of the optional behavior one-hot input.
inline constexpr std::array<std::string_view, kBehaviors> kBehaviorNames = {
    "constant_speed", "constant_accel", "idm"};

/// Which data set a model was trained on: enough to tell it from another.
struct DatasetIdentity {
  std::string dir;
  std::string manifest_crc32;  ///< of manifest.json as read
  long long scenarios = 0;
  std::uint64_t seed = 0;
};

/// The scenarios of all data sets, one row each.
struct ScenarioTable {
  Eigen::MatrixXd features;      ///< rows x classifier_features, raw (SI units)
  std::vector<int> label;        ///< index into kLabelNames
  std::vector<int> behavior;     ///< index into kBehaviorNames
  std::vector<int> dataset;      ///< index into LearningData::datasets
  std::vector<long long> index;  ///< the scenario's index within its data set
  /// rows x gap_classifier_features (no columns for data sets without them).
  Eigen::MatrixXd gap_features;
  /// The slot of the gap the expert's plan completes well-posed, else kNoGap.
  std::vector<int> gap_class;
  /// Bit s set where slot s's gap is known to be completed well-posed: the
  /// plan's own gap, and with gap labels every slot labelled so.
  std::vector<unsigned> completable_slots;
  [[nodiscard]] int rows() const { return static_cast<int>(label.size()); }
};

/// The nodes of well-posed plans, one row each.
struct SampleTable {
  Eigen::MatrixXd inputs;     ///< rows x action_inputs
  Eigen::MatrixXd targets;    ///< rows x action_targets (a, omega)
  std::vector<int> scenario;  ///< row of ScenarioTable the node belongs to
  [[nodiscard]] int rows() const { return static_cast<int>(scenario.size()); }
};

/// Every node of the converged, collision-free plans (well-posed and
/// ill-posed): the states of the ego and the cars there, and the plan's lane
/// mode, for the strategy model (docs/strategy.md).
struct PlanNodeTable {
  /// The columns of `states`, by their data-set names.
  static const std::vector<std::string>& columns();
  Eigen::MatrixXd states;  ///< rows x columns()
  /// rows x expert::gap_view_names(): the plan's own gap seen from the ego at
  /// the node; no rows where the data sets predate it (formats 2 and 3).
  Eigen::MatrixXd gap_view;
  std::vector<int> lane_mode;  ///< LaneOccupancy's value; -1 at k = 0
  std::vector<int> node;       ///< k
  std::vector<int> scenario;   ///< row of ScenarioTable the node belongs to
  [[nodiscard]] int rows() const { return static_cast<int>(scenario.size()); }
};

struct LearningData {
  std::vector<DatasetIdentity> datasets;
  std::vector<std::string> classifier_features;
  /// Empty where the data sets describe no gaps (format 2).
  std::vector<std::string> gap_classifier_features;
  /// Every data set labels each gap slot (generate --gap-labels).
  bool gap_labels = false;
  std::vector<std::string> action_inputs;
  std::vector<std::string> action_targets;
  std::string dataset_format;
  nlohmann::json config;  ///< the expert config all data sets share
  ScenarioTable scenarios;
  SampleTable samples;
  PlanNodeTable plan_nodes;
};

/// Reads and checks (row counts, checksums: summarize_dataset) the data sets.
/// InputError when one is missing or damaged, when they disagree on the
/// columns or the expert config, or when a needed column is absent.
/// `network_inputs` names the manifest's list of the action network's input
/// columns ("action_inputs" or "gap_action_inputs"); a data set without it
/// is an InputError.
[[nodiscard]] LearningData load_learning_data(const std::vector<std::string>& dirs,
                                              const char* network_inputs = "action_inputs");

/// Rows of ScenarioTable on each side.
struct Split {
  std::vector<int> train;
  std::vector<int> test;
};

/// A seeded split of n scenarios: round(test_share n) go to the test side.
/// The same (n, share, seed) gives the same split on every platform.
[[nodiscard]] Split split_scenarios(int n, double test_share, std::uint64_t seed);

/// Fisher-Yates with our own draw: std::shuffle and the std distributions
/// differ between standard libraries, and splits and folds must not.
void seeded_shuffle(std::vector<int>& values, std::mt19937_64& rng);

/// The sample rows whose scenario is on the given side (`member[s]`).
[[nodiscard]] std::vector<int> sample_rows_of(const SampleTable& samples,
                                              const std::vector<char>& member);

/// A membership mask of size n from a list of rows.
[[nodiscard]] std::vector<char> mask_of(const std::vector<int>& rows, int n);

/// The classifier inputs of the given rows, with the behavior one-hot
/// appended when asked.
[[nodiscard]] Eigen::MatrixXd classifier_inputs(const ScenarioTable& table,
                                                const std::vector<int>& rows, bool with_behavior);

/// Names of classifier_inputs' columns.
[[nodiscard]] std::vector<std::string> classifier_input_names(const LearningData& data,
                                                              bool with_behavior);

}  // namespace lanechange::learn
