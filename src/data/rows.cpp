#include "data/rows.hpp"

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>

#include "run/csv.hpp"

namespace lanechange::data {

namespace {

// The scene at t = 0, as the classifier and the action network see it.
const std::vector<std::string>& scene_columns() {
  static const std::vector<std::string> columns = {
      "ego_x0",      "ego_y0",    "ego_v0",    "ego_theta0",  "ego_a0",
      "leader_x0",   "leader_v0", "leader_a0", "follower_x0", "follower_v0",
      "follower_a0", "target_x0", "target_v0", "target_a0"};
  return columns;
}

// The data set's rows are the paper's: its three cars, by role.
std::array<double, 14> scene_values(const Scenario& s) {
  const CarState& l = s.leader();
  const CarState& f = s.follower();
  const CarState& g = s.target();
  return {s.ego.x, s.ego.y, s.ego.v, s.ego.theta, s.ego.a, l.x, l.v,
          l.a,     f.x,     f.v,     f.a,         g.x,     g.v, g.a};
}

std::string join(const std::vector<std::string>& columns) {
  std::string line;
  for (const std::string& c : columns) line += (line.empty() ? "" : ",") + c;
  return line + "\n";
}

// Shortest text that reads back as the same double; a missing value
// (no solution) is an empty field, which pandas and MATLAB read as NaN.
void put(std::string& out, double value) {
  out += ',';
  if (!std::isfinite(value)) return;
  char buffer[32];
  const auto end = std::to_chars(buffer, buffer + sizeof buffer, value).ptr;
  out.append(buffer, end);
}

void put(std::string& out, std::uint64_t value) {
  out += ',';
  out += std::to_string(value);
}

void put(std::string& out, std::string_view text) {
  out += ',';
  out += text;
}

std::string scene_text(const Scenario& s) {
  std::string out;
  for (double v : scene_values(s)) put(out, v);
  return out;
}

// The other cars at node k as the plan saw them: what the action network
// observes of the traffic while it drives.
void put_traffic(std::string& out, const Scenario& s, const TrafficPrediction& others, int k) {
  for (const Role role : kRoles) {
    const CarTrack& track = others.car(s.index_of(role));
    const auto at = static_cast<std::size_t>(k);
    for (const auto* series : {&track.x, &track.v, &track.a}) {
      put(out, at < series->size() ? (*series)[at] : std::nan(""));
    }
  }
}

// The plan's own gap as the ego sees it at node k: what a network that
// drives to a chosen gap observes (format 4).
void put_gap_view(std::string& out, const Scenario& s, const PlanOutcome& outcome, int k,
                  std::vector<CarState>& cars) {
  const TrafficPrediction& others = outcome.trajectory.others;
  const auto at = static_cast<std::size_t>(k);
  cars.resize(s.cars.size());
  for (CarIndex c = 0; c < cars.size(); ++c) {
    const CarTrack& track = others.car(c);
    const auto value = [at](const std::vector<double>& series) {
      return at < series.size() ? series[at] : std::nan("");
    };
    cars[c] = {value(track.x), value(track.v), value(track.a)};
  }
  const EgoState& ego = outcome.trajectory.ego[at];
  for (double v : expert::gap_view(s, cars, ego, outcome.gap_frame)) put(out, v);
}

void put_samples(std::string& out, std::uint64_t index, const Scenario& scenario,
                 const std::string& scene, const PlanOutcome& outcome) {
  const Trajectory& t = outcome.trajectory;
  std::vector<CarState> cars;
  for (int k = 0; k < t.nodes(); ++k) {
    const EgoState& z = t.ego[k];
    out += std::to_string(index);
    put(out, static_cast<std::uint64_t>(k));
    put(out, to_string(outcome.label));
    put(out, t.t[k]);
    out += scene;
    for (double v : {z.x, z.y, z.v, z.theta, t.controls[k].a, t.controls[k].omega}) put(out, v);
    put_traffic(out, scenario, t.others, k);
    const auto at = static_cast<std::size_t>(k);
    const int lanes = at < outcome.lane_modes.size() ? outcome.lane_modes[at] : -1;
    out += ',';
    if (lanes >= 0) out += std::to_string(lanes);
    put_gap_view(out, scenario, outcome, k, cars);
    out += '\n';
  }
}

bool is_scene_column(const std::string& name) {
  const auto& scene = scene_columns();
  return std::find(scene.begin(), scene.end(), name) != scene.end();
}

// The gap columns of the scenarios file: the features, the plan's gap (its
// slot, and the ids of the cars framing it), the label of each slot's gap.
const std::vector<std::string>& gap_columns() {
  static const std::vector<std::string> columns = [] {
    std::vector<std::string> c;
    for (const std::string& name : expert::gap_feature_names()) {
      if (!is_scene_column(name)) c.push_back(name);
    }
    c.insert(c.end(), {"gap_slot", "gap_behind", "gap_ahead"});
    for (int slot = 0; slot < expert::kGapSlots; ++slot) {
      c.push_back("gap_" + std::string(expert::gap_slot_name(slot)) + "_label");
    }
    return c;
  }();
  return columns;
}

void put_gaps(std::string& out, const Scenario& s, const PlanOutcome& outcome) {
  // The features the scene columns hold already (the ego's) are not repeated.
  const std::vector<double> features = expert::gap_features(s, expert::gap_slots(s));
  for (std::size_t i = 0; i < features.size(); ++i) {
    if (!is_scene_column(expert::gap_feature_names()[i])) put(out, features[i]);
  }
  out += ',';
  if (outcome.gap_slot >= 0) out += expert::gap_slot_name(outcome.gap_slot);
  put(out, outcome.gap_behind);
  put(out, outcome.gap_ahead);
  for (const auto& label : outcome.slot_labels) put(out, label ? to_string(*label) : "");
}

const std::vector<std::string>& traffic_columns() {
  static const std::vector<std::string> columns = {"leader_x",   "leader_v",   "leader_a",
                                                   "follower_x", "follower_v", "follower_a",
                                                   "target_x",   "target_v",   "target_a"};
  return columns;
}

}  // namespace

std::vector<std::string> scenario_columns() {
  std::vector<std::string> c = {"index", "sub_seed", "behavior"};
  c.insert(c.end(), scene_columns().begin(), scene_columns().end());
  c.insert(c.end(), {"label", "status", "collision", "objective", "iterations", "samples"});
  // Format 3 adds the scene through its gap slots, the gap the plan takes and
  // the label through each slot's gap, before the reason.
  c.insert(c.end(), gap_columns().begin(), gap_columns().end());
  // The reason is last: it is the only field that may need quotes.
  c.emplace_back("reason");
  return c;
}

std::vector<std::string> sample_columns() {
  std::vector<std::string> c = {"index", "k", "label", "t"};
  c.insert(c.end(), scene_columns().begin(), scene_columns().end());
  c.insert(c.end(), {"x", "y", "v", "theta", "a", "omega"});
  // Format 2 appends; the columns of format 1 keep their places.
  c.insert(c.end(), traffic_columns().begin(), traffic_columns().end());
  c.emplace_back("lane_mode");
  // Format 4 appends the plan's gap as the ego sees it at the node.
  c.insert(c.end(), expert::gap_view_names().begin(), expert::gap_view_names().end());
  return c;
}

std::vector<std::string> timing_columns() { return {"index", "solve_ms"}; }

std::vector<std::string> classifier_features() {
  std::vector<std::string> c = {"ego_x0", "ego_v0"};
  for (const char* car : {"leader", "follower", "target"}) {
    for (const char* q : {"_x0", "_v0", "_a0"}) c.push_back(std::string(car) + q);
  }
  return c;
}

std::vector<std::string> action_inputs() {
  std::vector<std::string> c = scene_columns();
  c.insert(c.end(), {"t", "x", "y", "v", "theta"});
  c.insert(c.end(), traffic_columns().begin(), traffic_columns().end());
  return c;
}

std::vector<std::string> gap_action_inputs() {
  std::vector<std::string> c = {"t", "y", "v", "theta"};
  c.insert(c.end(), expert::gap_view_names().begin(), expert::gap_view_names().end());
  return c;
}

std::vector<std::string> action_targets() { return {"a", "omega"}; }

std::vector<std::string> gap_classifier_features() { return expert::gap_feature_names(); }

ScenarioRows header_rows() {
  return {join(scenario_columns()), join(sample_columns()), join(timing_columns())};
}

ScenarioRows scenario_rows(std::uint64_t index, std::uint64_t sub_seed, const Scenario& scenario,
                           const PlanOutcome& outcome) {
  const std::string scene = scene_text(scenario);
  ScenarioRows rows;
  std::string& out = rows.scenarios;
  out += std::to_string(index);
  put(out, sub_seed);
  put(out, to_string(scenario.behavior));
  out += scene;
  put(out, to_string(outcome.label));
  put(out, outcome.status);
  put(out, static_cast<std::uint64_t>(outcome.collision ? 1 : 0));
  put(out, outcome.objective);
  put(out, static_cast<std::uint64_t>(outcome.iterations));
  put(out, static_cast<std::uint64_t>(outcome.trajectory.nodes()));
  put_gaps(out, scenario, outcome);
  put(out, run::csv_field(outcome.reason));
  out += '\n';
  put_samples(rows.samples, index, scenario, scene, outcome);
  rows.timing += std::to_string(index);
  put(rows.timing, outcome.solve_ms);
  rows.timing += '\n';
  return rows;
}

}  // namespace lanechange::data
