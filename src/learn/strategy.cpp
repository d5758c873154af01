#include "lanechange/learn/strategy.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <optional>

#include "lanechange/error.hpp"
#include "lanechange/learn/learn_data.hpp"
#include "lanechange/traffic.hpp"

namespace lanechange::learn {

using nlohmann::json;

namespace {

// Where each column of a plan node sits in PlanNodeTable::states.
struct NodeColumns {
  Eigen::Index t, ego_a0, x, y, v, theta, a, cars;  // cars: leader_x, then v, a, per car
  NodeColumns() {
    const auto& names = PlanNodeTable::columns();
    auto at = [&names](const char* name) {
      return static_cast<Eigen::Index>(std::find(names.begin(), names.end(), name) - names.begin());
    };
    t = at("t");
    ego_a0 = at("ego_a0");
    x = at("x");
    y = at("y");
    v = at("v");
    theta = at("theta");
    a = at("a");
    cars = at("leader_x");
  }
};

// The scene a plan node stands for: the ego and the cars there, the rest of
// the horizon, the scenario's behavior. `last_a` is the acceleration applied
// in the step before (the scene's ego.a means that). `view` (a row of
// PlanNodeTable::gap_view, or empty) puts the plan's own gap's cars in the
// follower's and target's places, as the planner votes for a gap; without
// it the rows see the scene's follower and target.
Eigen::VectorXd node_features(const Eigen::RowVectorXd& z, const Eigen::RowVectorXd& view,
                              double last_a, double horizon_left, int behavior,
                              double traffic_speed_cap) {
  static const NodeColumns c;
  Scenario scene = three_car_scenario(Config{});
  scene.set_behavior(static_cast<Behavior>(behavior));
  scene.ego = {z(c.x), z(c.y), z(c.v), z(c.theta), last_a};
  for (Eigen::Index i = 0; i < 3; ++i) {
    const Eigen::Index at = c.cars + 3 * i;  // x, v, a of car i, in Role order
    scene.car(static_cast<Role>(i)) = {z(at), z(at + 1), z(at + 2)};
  }
  if (view.size() > 0) {
    // The view holds behind, ahead, leader, each as dx, dv, a.
    constexpr std::array<Role, 3> kViewRoles = {Role::Follower, Role::Target, Role::Leader};
    for (Eigen::Index i = 0; i < 3; ++i) {
      scene.car(kViewRoles[static_cast<std::size_t>(i)]) = {
          scene.ego.x + view(3 * i), scene.ego.v + view(3 * i + 1), view(3 * i + 2)};
    }
  }
  scene.horizon = horizon_left;
  return strategy_features(scene, traffic_speed_cap);
}

// The rows of one plan (its nodes first to last in `rows`, of PlanNodeTable).
void add_plan(const LearningData& data, const std::vector<int>& rows, int stride,
              StrategyRows& out) {
  static const NodeColumns c;
  const PlanNodeTable& t = data.plan_nodes;
  std::vector<int> modes;
  modes.reserve(rows.size());
  for (int r : rows) modes.push_back(t.lane_mode[static_cast<std::size_t>(r)]);
  const int last = static_cast<int>(rows.size()) - 1;
  const double end_time = t.states(rows.back(), c.t);
  const int behavior =
      data.scenarios
          .behavior[static_cast<std::size_t>(t.scenario[static_cast<std::size_t>(rows[0])])];
  const int step = stride > 0 ? stride : last + 1;
  for (int k = 0; k + 2 <= last; k += step) {
    const auto& z = t.states.row(rows[static_cast<std::size_t>(k)]);
    const double last_a =
        k == 0 ? z(c.ego_a0) : t.states(rows[static_cast<std::size_t>(k - 1)], c.a);
    const Eigen::RowVectorXd view =
        t.gap_view.rows() == t.states.rows()
            ? Eigen::RowVectorXd(t.gap_view.row(rows[static_cast<std::size_t>(k)]))
            : Eigen::RowVectorXd();
    out.features.push_back(
        node_features(z, view, last_a, end_time - z(c.t), behavior, out.traffic_speed_cap));
    out.labels.push_back(strategy_of(modes, k));
  }
}

}  // namespace

const std::vector<std::string>& strategy_feature_names() {
  static const std::vector<std::string> names = {"ego_y",
                                                 "ego_theta",
                                                 "ego_v",
                                                 "ego_a",
                                                 "leader_dx",
                                                 "leader_v",
                                                 "leader_a",
                                                 "follower_dx",
                                                 "follower_v",
                                                 "follower_a",
                                                 "target_dx",
                                                 "target_v",
                                                 "target_a",
                                                 "horizon",
                                                 "behavior_constant_speed",
                                                 "behavior_constant_accel",
                                                 "behavior_idm",
                                                 "gap_open_s"};
  return names;
}

namespace {

// How far ahead gap_open_s looks: past the 5 s horizon, so that "opens late"
// and "does not open" stay apart, and the same for every horizon left.
constexpr double kGapLookahead = 10.0;
constexpr double kGapTimeStep = 0.1;

// The k nearest rows offered so far as (squared distance, row), nearest
// first, ties to the earlier row whatever order the rows come in: a bounded
// max-heap, where sorting an index of every row took about as long again as
// the distances themselves.
class NearestRows {
 public:
  explicit NearestRows(int k) : wanted_(static_cast<std::size_t>(std::max(k, 0))) {
    heap_.reserve(wanted_ + 1);
  }
  [[nodiscard]] bool full() const { return heap_.size() == wanted_; }
  /// The k-th's squared distance; only when full().
  [[nodiscard]] double farthest() const { return heap_.front().first; }
  void offer(double squared_distance, int row) {
    const std::pair<double, int> candidate{squared_distance, row};
    if (heap_.size() < wanted_) {
      heap_.push_back(candidate);
      std::push_heap(heap_.begin(), heap_.end());
      return;
    }
    if (wanted_ == 0 || !(candidate < heap_.front())) return;
    std::pop_heap(heap_.begin(), heap_.end());
    heap_.back() = candidate;
    std::push_heap(heap_.begin(), heap_.end());
  }
  [[nodiscard]] std::vector<std::pair<double, int>> sorted() && {
    std::sort_heap(heap_.begin(), heap_.end());
    return std::move(heap_);
  }

 private:
  std::size_t wanted_;
  std::vector<std::pair<double, int>> heap_;  // the farthest kept on top
};

// The behavior one-hot's columns among the features, where a model has them.
constexpr Eigen::Index kFirstBehaviorFeature = 14;
constexpr Eigen::Index kBehaviorFeatures = 3;

// Relative slack on a behavior's bound: a bound is a partial sum of the
// rows' own float terms, so it is never above a row's distance in the scan's
// order of summation; the slack covers a compiler that fuses or reorders it.
constexpr double kBoundSlack = 1e-5;

// A side of a gap without a car: as the gap features read it, a car
// kOpenGapDistance away at the ego's speed.
CarState open_side(const EgoState& ego, double side) {
  return {ego.x + side * expert::kOpenGapDistance, ego.v, 0.0};
}

// The three cars a strategy is voted on, and the safe distances to the two
// that frame the gap.
struct VotedCars {
  CarState leader, behind, ahead;
  SafeDistance behind_needed, ahead_needed;
};

VotedCars voted_cars(const Scenario& s, const expert::GapFrame& frame) {
  std::optional<CarIndex> leader = s.roles[static_cast<std::size_t>(Role::Leader)];
  if (!leader) {
    std::vector<CarState> now;
    now.reserve(s.car_count());
    for (const OtherCar& car : s.cars) now.push_back(car.state);
    leader = nearest_in_lane(s, now, Lane::Ego, s.ego.x, true);
  }
  const auto of = [&s](std::optional<CarIndex> car, SafeDistance base) {
    return car ? s.centre_safe_distance(*car, base) : base;
  };
  return {leader ? s.car(*leader) : open_side(s.ego, 1.0),
          frame.behind ? s.car(*frame.behind) : open_side(s.ego, -1.0),
          frame.ahead ? s.car(*frame.ahead) : open_side(s.ego, 1.0),
          of(frame.behind, s.safe_distance.follower), of(frame.ahead, s.safe_distance.target)};
}

double gap_open_time(const EgoState& ego, VotedCars cars, double traffic_speed_cap) {
  const double ahead_needed = cars.ahead_needed.standstill + cars.ahead_needed.time_headway * ego.v;
  // The cars move as the constant-acceleration traffic model moves them
  // (stopping at 0, held at the cap), so the feature agrees with the scenes.
  for (int i = 0; i * kGapTimeStep <= kGapLookahead; ++i) {
    const double t = i * kGapTimeStep;
    if (i > 0) {
      advance_constant_accel(cars.ahead, kGapTimeStep, traffic_speed_cap);
      advance_constant_accel(cars.behind, kGapTimeStep, traffic_speed_cap);
    }
    const double ego_x = ego.x + ego.v * t;
    const double behind_needed =
        cars.behind_needed.standstill + cars.behind_needed.time_headway * cars.behind.v;
    if (cars.ahead.x - ego_x >= ahead_needed && ego_x - cars.behind.x >= behind_needed) return t;
  }
  return kGapLookahead;
}

}  // namespace

expert::GapFrame paper_frame(const Scenario& scene) {
  return {scene.roles[static_cast<std::size_t>(Role::Follower)],
          scene.roles[static_cast<std::size_t>(Role::Target)]};
}

double gap_open_time(const Scenario& s, const expert::GapFrame& frame, double traffic_speed_cap) {
  return gap_open_time(s.ego, voted_cars(s, frame), traffic_speed_cap);
}

double gap_open_time(const Scenario& s, double traffic_speed_cap) {
  return gap_open_time(s, paper_frame(s), traffic_speed_cap);
}

Eigen::VectorXd strategy_features(const Scenario& s, const expert::GapFrame& frame,
                                  double traffic_speed_cap) {
  const VotedCars cars = voted_cars(s, frame);
  const CarState& l = cars.leader;
  const CarState& b = cars.behind;
  const CarState& g = cars.ahead;
  Eigen::VectorXd f(static_cast<Eigen::Index>(strategy_feature_names().size()));
  f << s.ego.y, s.ego.theta, s.ego.v, s.ego.a, l.x - s.ego.x, l.v, l.a, b.x - s.ego.x, b.v, b.a,
      g.x - s.ego.x, g.v, g.a, s.horizon, 0.0, 0.0, 0.0,
      gap_open_time(s.ego, cars, traffic_speed_cap);
  f(14 + static_cast<Eigen::Index>(s.behavior)) = 1.0;
  return f;
}

Eigen::VectorXd strategy_features(const Scenario& s, double traffic_speed_cap) {
  return strategy_features(s, paper_frame(s), traffic_speed_cap);
}

Strategy strategy_of(const std::vector<int>& lane_modes, int from) {
  Strategy out;
  for (std::size_t k = static_cast<std::size_t>(from) + 1; k < lane_modes.size(); ++k) {
    const int m = lane_modes[k];
    if (m < 0 || m > 2) {
      std::string what = "node ";
      what += std::to_string(k);
      what += " of a plan has no lane mode";
      throw InputError("", what);
    }
    out += static_cast<char>('0' + m);
  }
  return out;
}

StrategyRows strategy_rows(const LearningData& data, const std::vector<int>& scenarios,
                           int node_stride) {
  const std::vector<char> member = mask_of(scenarios, data.scenarios.rows());
  StrategyRows out;
  out.traffic_speed_cap = config_from_json(data.config)
                              .traffic_max_speed.value_or(std::numeric_limits<double>::infinity());
  const PlanNodeTable& t = data.plan_nodes;
  // Nodes of one plan are consecutive rows of the table.
  for (int r = 0; r < t.rows();) {
    std::vector<int> plan;
    const int scenario = t.scenario[static_cast<std::size_t>(r)];
    for (; r < t.rows() && t.scenario[static_cast<std::size_t>(r)] == scenario; ++r) {
      plan.push_back(r);
    }
    if (member[static_cast<std::size_t>(scenario)] && plan.size() >= 3) {
      add_plan(data, plan, node_stride, out);
    }
  }
  return out;
}

StrategyModel StrategyModel::fit(const StrategyRows& rows, const StrategySettings& settings) {
  if (settings.neighbors < 1) throw InputError("strategy.neighbors", "must be at least 1");
  const auto& features = rows.features;
  const auto& labels = rows.labels;
  if (features.empty()) {
    throw InputError("--data", "holds no converged plan to learn lane strategies from");
  }
  StrategyModel m;
  m.neighbors_ = settings.neighbors;
  m.traffic_speed_cap_ = rows.traffic_speed_cap;
  Eigen::MatrixXd x(static_cast<Eigen::Index>(features.size()), features[0].size());
  for (std::size_t i = 0; i < features.size(); ++i) {
    x.row(static_cast<Eigen::Index>(i)) = features[i].transpose();
  }
  m.standardizer_ = Standardizer::fit(x);
  m.points_ = m.standardizer_.apply(x).transpose();
  m.arrange_table();
  std::map<Strategy, int> index;
  for (const Strategy& s : labels) {
    const auto [it, fresh] = index.emplace(s, static_cast<int>(m.strategies_.size()));
    if (fresh) m.strategies_.push_back(s);
    m.label_.push_back(it->second);
  }
  return m;
}

namespace {

// Each row's behavior, from its one-hot features. None where the model has no
// such features, or where the rows of a behavior do not all share one value
// (rows fitted from other features than strategy_features'): a behavior's
// bound is read off its first row.
std::optional<std::vector<int>> behavior_groups(const Eigen::MatrixXd& points) {
  if (points.rows() < kFirstBehaviorFeature + kBehaviorFeatures) return std::nullopt;
  constexpr auto kCount = static_cast<std::size_t>(kBehaviorFeatures);
  using OneHot = std::array<float, kCount>;
  std::vector<int> group(static_cast<std::size_t>(points.cols()));
  std::array<std::optional<OneHot>, kCount> first;  // each behavior's first row's
  for (Eigen::Index r = 0; r < points.cols(); ++r) {
    OneHot mine{};
    std::size_t g = 0;
    for (std::size_t k = 0; k < kCount; ++k) {
      mine[k] = static_cast<float>(points(kFirstBehaviorFeature + static_cast<Eigen::Index>(k), r));
      if (mine[k] > mine[g]) g = k;
    }
    if (!first[g]) first[g] = mine;
    if (*first[g] != mine) return std::nullopt;
    group[static_cast<std::size_t>(r)] = static_cast<int>(g);
  }
  return group;
}

}  // namespace

void StrategyModel::arrange_table() {
  const Eigen::Index n = points_.cols();
  const std::optional<std::vector<int>> behavior = behavior_groups(points_);
  const int groups = behavior ? static_cast<int>(kBehaviorFeatures) : 1;
  table_row_.clear();
  group_begin_.assign(1, 0);
  for (int g = 0; g < groups; ++g) {
    for (Eigen::Index r = 0; r < n; ++r) {
      if (!behavior || (*behavior)[static_cast<std::size_t>(r)] == g) {
        table_row_.push_back(static_cast<int>(r));
      }
    }
    group_begin_.push_back(static_cast<Eigen::Index>(table_row_.size()));
  }
  table_.resize(n, points_.rows());
  for (Eigen::Index i = 0; i < n; ++i) {
    table_.row(i) = points_.col(table_row_[static_cast<std::size_t>(i)]).transpose().cast<float>();
  }
}

Eigen::VectorXf StrategyModel::standardized_query(const Eigen::VectorXd& features) const {
  if (features.size() != points_.rows()) {
    std::string what = "the strategy model takes ";
    what += std::to_string(points_.rows());
    what += " features, not ";
    what += std::to_string(features.size());
    throw InputError("", what);
  }
  // Both the rows and the query are rounded to float alike, so a row the
  // query repeats is at exactly 0 and decides alone.
  return ((features - standardizer_.mean).cwiseQuotient(standardizer_.scale)).cast<float>();
}

// The behavior one-hot's share of the squared distance from q to every row
// of group g (they all share it), summed as the scan sums it.
float StrategyModel::behavior_bound(const Eigen::VectorXf& q, std::size_t g) const {
  const Eigen::Index begin = group_begin_[g];
  if (group_begin_.size() == 2 || begin == group_begin_[g + 1]) return 0.0F;
  float bound = 0.0F;
  for (Eigen::Index j = kFirstBehaviorFeature; j < kFirstBehaviorFeature + kBehaviorFeatures; ++j) {
    const float d = table_(begin, j) - q(j);
    bound += d * d;
  }
  return bound;
}

std::vector<std::pair<double, int>> StrategyModel::nearest(const Eigen::VectorXf& q,
                                                           bool skip_far_behaviors) const {
  std::vector<std::pair<float, std::size_t>> order;  // (bound, group): the nearest behavior first
  for (std::size_t g = 0; g + 1 < group_begin_.size(); ++g) {
    order.emplace_back(skip_far_behaviors ? behavior_bound(q, g) : 0.0F, g);
  }
  std::sort(order.begin(), order.end());
  NearestRows nearest(neighbors_);
  // The k-th's distance once there are k (exact in float: the rows'
  // distances are floats), until then none.
  float worst = std::numeric_limits<float>::infinity();
  Eigen::VectorXf d2;
  for (const auto& [bound, g] : order) {
    if (bound > worst * (1.0 + kBoundSlack)) continue;
    const Eigen::Index begin = group_begin_[g];
    const Eigen::Index size = group_begin_[g + 1] - begin;
    // Squared distances summed feature by feature, each a contiguous column;
    // float halves the bytes read, the bound on this loop.
    d2.setZero(size);
    for (Eigen::Index j = 0; j < table_.cols(); ++j) {
      d2.array() += (table_.col(j).segment(begin, size).array() - q(j)).square();
    }
    for (Eigen::Index i = 0; i < size; ++i) {
      // Most rows are farther than the k-th so far: one comparison each.
      if (d2(i) > worst) continue;
      nearest.offer(d2(i), table_row_[static_cast<std::size_t>(begin + i)]);
      if (nearest.full()) worst = static_cast<float>(nearest.farthest());
    }
  }
  return std::move(nearest).sorted();
}

std::vector<Strategy> StrategyModel::predict(const Eigen::VectorXd& features, int count) const {
  return vote(nearest(standardized_query(features), true), count);
}

std::vector<Strategy> StrategyModel::predict_by_scan(const Eigen::VectorXd& features,
                                                     int count) const {
  return vote(nearest(standardized_query(features), false), count);
}

std::vector<Strategy> StrategyModel::vote(const std::vector<std::pair<double, int>>& nearest,
                                          int count) const {
  // Inverse-distance votes: a scene seen before (distance 0) decides alone.
  std::vector<std::pair<double, int>> votes;  // (weight, strategy)
  for (const auto& [squared_distance, row] : nearest) {
    const int s = label_[static_cast<std::size_t>(row)];
    const double w = 1.0 / (std::sqrt(squared_distance) + 1e-9);
    auto it =
        std::find_if(votes.begin(), votes.end(), [s](const auto& v) { return v.second == s; });
    if (it == votes.end()) {
      votes.emplace_back(w, s);
    } else {
      it->first += w;
    }
  }
  std::stable_sort(votes.begin(), votes.end(),
                   [](const auto& a, const auto& b) { return a.first > b.first; });
  std::vector<Strategy> out;
  for (std::size_t i = 0; i < votes.size() && static_cast<int>(i) < count; ++i) {
    out.push_back(strategies_[static_cast<std::size_t>(votes[i].second)]);
  }
  return out;
}

json StrategyModel::to_json() const {
  std::vector<double> points(points_.data(), points_.data() + points_.size());
  const auto& all = strategy_feature_names();
  const std::vector<std::string> names(all.begin(), all.begin() + points_.rows());
  json out = {{"format", kStrategyFormat}, {"features", names},
              {"neighbors", neighbors_},   {"standardizer", standardizer_.to_json()},
              {"strategies", strategies_}, {"labels", label_},
              {"points", points}};
  // JSON has no infinity: no cap is written as null.
  out["traffic_speed_cap"] =
      std::isfinite(traffic_speed_cap_) ? json(traffic_speed_cap_) : json(nullptr);
  return out;
}

StrategyModel StrategyModel::from_json(const json& j) {
  if (j.value("format", std::string()) != kStrategyFormat) {
    throw InputError("", "not a " + std::string(kStrategyFormat) + " strategy model");
  }
  // A model from before a feature was added has the leading ones: it votes
  // on those, as it was trained.
  const auto names = j.at("features").get<std::vector<std::string>>();
  const auto& all = strategy_feature_names();
  if (names.empty() || names.size() > all.size() ||
      !std::equal(names.begin(), names.end(), all.begin())) {
    throw InputError("", "the strategy model was trained on other features");
  }
  StrategyModel m;
  m.neighbors_ = j.at("neighbors").get<int>();
  // Models from before the cap was recorded computed their features without one.
  if (j.contains("traffic_speed_cap") && !j.at("traffic_speed_cap").is_null()) {
    m.traffic_speed_cap_ = j.at("traffic_speed_cap").get<double>();
    if (!(m.traffic_speed_cap_ > 0.0)) {
      throw InputError("", "the strategy model's traffic speed cap is not positive");
    }
  }
  m.standardizer_ = Standardizer::from_json(j.at("standardizer"));
  m.strategies_ = j.at("strategies").get<std::vector<Strategy>>();
  m.label_ = j.at("labels").get<std::vector<int>>();
  const auto points = j.at("points").get<std::vector<double>>();
  const auto width = static_cast<Eigen::Index>(names.size());
  const auto n = static_cast<Eigen::Index>(m.label_.size());
  if (static_cast<Eigen::Index>(points.size()) != width * n || m.neighbors_ < 1) {
    throw InputError("", "the strategy model's rows do not fit its labels");
  }
  for (const Strategy& s : m.strategies_) {
    if (s.empty() || s.find_first_not_of("012") != Strategy::npos) {
      throw InputError("", "the strategy model holds a strategy other than lane modes 0, 1, 2");
    }
  }
  for (int l : m.label_) {
    if (l < 0 || l >= static_cast<int>(m.strategies_.size())) {
      throw InputError("", "the strategy model names a strategy it does not hold");
    }
  }
  m.points_ = Eigen::Map<const Eigen::MatrixXd>(points.data(), width, n);
  m.arrange_table();
  return m;
}

}  // namespace lanechange::learn
