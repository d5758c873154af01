#pragma once
// The learned integer part of a plan (docs/strategy.md): a plan's lane
// strategy is its lane occupancy at every node after the first, and a
// k-nearest-neighbour vote over standardized scene features ranks the
// strategies of the nearest training scenes, CoCo-style: a classifier over
// the strategies seen in the data. The rows are the plans' starts and, for
// the closed loop, their later nodes as scenes of their own with the rest of
// the plan's strategy (a plan from there would keep it, up to re-linearizing).
#include <Eigen/Dense>
#include <limits>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "lanechange/expert/gap_slots.hpp"
#include "lanechange/learn/classifier.hpp"
#include "lanechange/scenario.hpp"

namespace lanechange::learn {

struct LearningData;

inline constexpr std::string_view kStrategyFormat = "lanechange.strategy/1";
inline constexpr std::string_view kStrategyFile = "strategy.json";

/// The lane occupancy of nodes 1..L of a plan, one character each: '0' ego
/// lane, '1' both lanes, '2' target lane (LaneOccupancy's values, as the
/// data sets' lane_mode column). Applied to a horizon of another length, its
/// last node repeats or its tail is cut.
using Strategy = std::string;

struct StrategySettings {
  int neighbors = 15;   ///< rows that vote
  int node_stride = 5;  ///< a closed-loop row every this many nodes of a plan (0: starts only)
};

/// The features of a scene, in strategy_feature_names() order: the ego's
/// lateral state, speed and acceleration, each car's gap to the ego, speed
/// and acceleration, the horizon, the behavior one-hot and gap_open_time().
/// Relative gaps make a scene mid-manoeuvre look like a start. New features
/// go at the end: a model trained before one was added uses the leading ones.
[[nodiscard]] const std::vector<std::string>& strategy_feature_names();
/// `traffic_speed_cap` (m/s, +infinity for none) is the traffic model's
/// (Config::traffic_max_speed), for gap_open_time().
[[nodiscard]] Eigen::VectorXd strategy_features(const Scenario& scene, double traffic_speed_cap);
/// The same for a lane change into `frame`'s gap, in a scene of any number of
/// cars: the gap's two framing cars stand in the follower's and the target's
/// places, the leader is the leader's role (else the nearest ego-lane car
/// ahead), and a side without a car reads kOpenGapDistance away at the ego's
/// speed, as the gap features read it. The form above is this one with
/// paper_frame(scene).
[[nodiscard]] Eigen::VectorXd strategy_features(const Scenario& scene,
                                                const expert::GapFrame& frame,
                                                double traffic_speed_cap);
/// Eq. 1's gap: the scene's follower and target.
[[nodiscard]] expert::GapFrame paper_frame(const Scenario& scene);

/// The first time (s, on a 0.1 s grid, at most 10) at which an ego that keeps
/// its speed would be at the centre safe distances behind the target car and
/// ahead of the follower, each car keeping its acceleration as the
/// constant-acceleration traffic model does (advance_constant_accel: a car
/// stops at 0 and holds `traffic_speed_cap`). The gaps alone
/// do not tell the vote when a lane change becomes possible: most scenes
/// where no top-k strategy held changed lanes late, while the neighbours
/// changed early (docs/strategy.md).
[[nodiscard]] double gap_open_time(const Scenario& scene, double traffic_speed_cap);
/// The same for `frame`'s gap (its two cars in the target's and follower's places).
[[nodiscard]] double gap_open_time(const Scenario& scene, const expert::GapFrame& frame,
                                   double traffic_speed_cap);

/// Training rows: scenes and the strategy their plan follows from there.
struct StrategyRows {
  std::vector<Eigen::VectorXd> features;
  std::vector<Strategy> labels;
  /// The traffic speed cap the features were computed with.
  double traffic_speed_cap = std::numeric_limits<double>::infinity();
};

/// The rows of the converged plans of `scenarios` (rows of ScenarioTable):
/// each plan's start, and every `node_stride`-th node after it (0: starts only).
[[nodiscard]] StrategyRows strategy_rows(const LearningData& data,
                                         const std::vector<int>& scenarios, int node_stride);

class StrategyModel {
 public:
  /// InputError when there are no rows.
  static StrategyModel fit(const StrategyRows& rows, const StrategySettings& settings);
  static StrategyModel from_json(const nlohmann::json& j);
  [[nodiscard]] nlohmann::json to_json() const;

  /// Up to `count` distinct strategies, most likely first (the neighbours'
  /// inverse-distance vote). A behavior whose rows the one-hot features alone
  /// put farther than the k-th nearest found so far is not scanned: the same
  /// neighbours as predict_by_scan's, at a third of the rows read where the
  /// query's own behavior decides.
  [[nodiscard]] std::vector<Strategy> predict(const Eigen::VectorXd& features, int count) const;
  /// The same vote with every row's distance computed: the reference the
  /// vote is tested and benchmarked against.
  [[nodiscard]] std::vector<Strategy> predict_by_scan(const Eigen::VectorXd& features,
                                                      int count) const;
  [[nodiscard]] std::vector<Strategy> predict(const Scenario& scene, int count) const {
    return predict(strategy_features(scene, traffic_speed_cap_).head(points_.rows()), count);
  }
  /// The vote for a lane change into `frame`'s gap.
  [[nodiscard]] std::vector<Strategy> predict(const Scenario& scene, const expert::GapFrame& frame,
                                              int count) const {
    return predict(strategy_features(scene, frame, traffic_speed_cap_).head(points_.rows()), count);
  }
  [[nodiscard]] std::vector<Strategy> predict_by_scan(const Scenario& scene, int count) const {
    return predict_by_scan(strategy_features(scene, traffic_speed_cap_).head(points_.rows()),
                           count);
  }
  /// The leading strategy_feature_names() it was trained on.
  [[nodiscard]] int features() const { return static_cast<int>(points_.rows()); }
  [[nodiscard]] int rows() const { return static_cast<int>(label_.size()); }
  [[nodiscard]] int strategies() const { return static_cast<int>(strategies_.size()); }

 private:
  int neighbors_ = 15;
  /// Its rows' (StrategyRows::traffic_speed_cap): a scene is featured alike.
  double traffic_speed_cap_ = std::numeric_limits<double>::infinity();
  Standardizer standardizer_;
  Eigen::MatrixXd points_;  ///< standardized features, one column per row
  /// points_ in float, one row per model row, the rows of each behavior
  /// together (in their order): the vote's scan reads a column per feature,
  /// contiguous, at half the bytes, one behavior at a time.
  Eigen::MatrixXf table_;
  std::vector<int> table_row_;             ///< the model row (of label_) of each table_ row
  std::vector<Eigen::Index> group_begin_;  ///< each behavior's first table_ row, then the end
  std::vector<int> label_;                 ///< index into strategies_, per column
  std::vector<Strategy> strategies_;

  void arrange_table();
  [[nodiscard]] float behavior_bound(const Eigen::VectorXf& q, std::size_t group) const;
  [[nodiscard]] std::vector<std::pair<double, int>> nearest(const Eigen::VectorXf& q,
                                                            bool skip_far_behaviors) const;
  [[nodiscard]] Eigen::VectorXf standardized_query(const Eigen::VectorXd& features) const;
  [[nodiscard]] std::vector<Strategy> vote(const std::vector<std::pair<double, int>>& nearest,
                                           int count) const;
};

/// The strategy of a plan's lane modes (LaneOccupancy values per node, -1
/// where none applies) from node `from` on. InputError for a node without one.
[[nodiscard]] Strategy strategy_of(const std::vector<int>& lane_modes, int from = 0);

}  // namespace lanechange::learn
