// One judge for every planner's rollout, and the measures evaluate tabulates.
#include <algorithm>
#include <cmath>
#include <limits>

#include "lanechange/checks.hpp"
#include "lanechange/error.hpp"
#include "lanechange/run/quantile.hpp"
#include "lanechange/sim/evaluate.hpp"
#include "lanechange/sim/simulator.hpp"
#include "lanechange/traffic.hpp"
#include "sim/metrics.hpp"

namespace lanechange::sim {

std::string_view to_string(Outcome outcome) {
  switch (outcome) {
    case Outcome::WellPosed: return "well_posed";
    case Outcome::IllPosed: return "ill_posed";
    case Outcome::Failure: return "failure";
    case Outcome::Aborted: return "aborted";
  }
  return "?";
}

Outcome outcome_from_string(std::string_view name) {
  for (const Outcome o :
       {Outcome::WellPosed, Outcome::IllPosed, Outcome::Failure, Outcome::Aborted}) {
    if (to_string(o) == name) return o;
  }
  throw InputError("outcome", "unknown outcome \"" + std::string(name) + "\"");
}

Outcome judge(const Trajectory& path, const Config& config, std::string& reason) {
  const std::vector<double> y = path.ys();
  const Labelled l = label_trajectory(y, path.ego.back().theta, path.lane_width, config.labels);
  reason = l.reason;
  if (path.collision) return Outcome::Failure;
  if (l.label == Label::WellPosed) return Outcome::WellPosed;
  if (l.label == Label::IllPosed) return Outcome::IllPosed;
  // Not in the target lane at the end: aborted if the body never touched
  // the line and the ego ends near its own lane's centre.
  const double half_width = config.vehicle.width / 2.0;
  const double highest = *std::max_element(y.begin(), y.end());
  if (highest + half_width <= path.lane_width / 2.0 && std::abs(y.back()) <= config.labels.reach) {
    reason = "stayed in its lane";
    return Outcome::Aborted;
  }
  return Outcome::Failure;
}

namespace {

// Gap and time-to-collision to the cars in the lanes the ego's body touches.
void traffic_measures(const Trajectory& t, const Scenario& scene, RolloutMetrics& m) {
  m.min_gap = std::numeric_limits<double>::infinity();
  m.min_ttc = std::numeric_limits<double>::infinity();
  for (int k = 0; k < t.nodes(); ++k) {
    const EgoState& e = t.ego[static_cast<std::size_t>(k)];
    const double ego_speed = e.v * std::cos(e.theta);
    for (CarIndex c = 0; c < scene.car_count(); ++c) {
      if (!body_in_lane(e.y, scene.vehicle.width, scene.lane_center(c), scene.lane_width)) {
        continue;
      }
      const CarTrack& track = t.others.car(c);
      if (!track.present_at(static_cast<std::size_t>(k))) continue;
      const double dx = track.x[static_cast<std::size_t>(k)] - e.x;
      const double gap = scene.bumper_gap(c, dx);
      m.min_gap = std::min(m.min_gap, gap);
      const double car_speed = track.v[static_cast<std::size_t>(k)];
      const double closing = dx > 0 ? ego_speed - car_speed : car_speed - ego_speed;
      if (closing > 0) m.min_ttc = std::min(m.min_ttc, std::max(0.0, gap) / closing);
    }
  }
}

// The other cars among themselves: the hardest braking, and whether two of
// a lane ever overlapped (each car's own length).
void car_measures(const Trajectory& t, RolloutMetrics& m) {
  const auto n = t.others.car_count();
  for (CarIndex c = 0; c < n; ++c) {
    const CarTrack& track = t.others.car(c);
    for (std::size_t k = 0; k < track.a.size(); ++k) {
      if (track.present_at(k)) m.max_car_decel = std::max(m.max_car_decel, -track.a[k]);
    }
  }
  for (int k = 0; k < t.nodes() && !m.cars_collide; ++k) {
    const auto at = static_cast<std::size_t>(k);
    for (CarIndex i = 0; i < n; ++i) {
      for (CarIndex j = 0; j < i; ++j) {
        if (t.cars[i].lane != t.cars[j].lane || !t.others.car(i).present_at(at) ||
            !t.others.car(j).present_at(at)) {
          continue;
        }
        const double reach = 0.5 * (t.cars[i].size.length + t.cars[j].size.length);
        if (std::abs(t.others.car(i).x[at] - t.others.car(j).x[at]) < reach) m.cars_collide = true;
      }
    }
  }
}

// Where a lane change ended against Eq. 1's gap (between the scene's
// follower and target): in it, ahead of it or behind it.
// Whether the ego's centre ends in the target lane.
bool ends_in_target_lane(const Trajectory& t, const Scenario& scene) {
  return std::abs(t.ego.back().y - scene.lane_width) <= scene.lane_width / 2.0;
}

std::string target_lane_slot(const Trajectory& t, const Scenario& scene) {
  const EgoState& e = t.ego.back();
  if (!ends_in_target_lane(t, scene)) return "";
  const auto last = static_cast<std::size_t>(t.nodes() - 1);
  const auto there = [&](Role role) {
    return scene.has(role) && t.others.car(scene.index_of(role)).present_at(last);
  };
  if (there(Role::Target) && t.others.car(scene.index_of(Role::Target)).x[last] < e.x) {
    return "ahead_of_target";
  }
  if (there(Role::Follower) && t.others.car(scene.index_of(Role::Follower)).x[last] > e.x) {
    return "behind_follower";
  }
  return "follower_target_gap";
}

}  // namespace

namespace detail {

std::optional<nlohmann::json> gap_taken(const Trajectory& t, const Scenario& scene) {
  if (!ends_in_target_lane(t, scene)) return std::nullopt;
  const EgoState& e = t.ego.back();
  const auto last = static_cast<std::size_t>(t.nodes() - 1);
  const auto id_of = [&](bool ahead) {
    std::optional<CarIndex> best;
    for (CarIndex c = 0; c < t.others.car_count(); ++c) {
      const CarTrack& track = t.others.car(c);
      if (scene.cars[c].lane != Lane::Target || !track.present_at(last)) continue;
      const double at = track.x[last];
      if ((at > e.x) != ahead) continue;
      if (!best || (ahead ? at < t.others.car(*best).x[last] : at > t.others.car(*best).x[last])) {
        best = c;
      }
    }
    return best ? nlohmann::json(scene.cars[*best].id) : nlohmann::json();
  };
  return nlohmann::json{{"behind", id_of(false)}, {"ahead", id_of(true)}};
}

RolloutMetrics measure(const Rollout& rollout, const Scenario& scene, const Config& config) {
  RolloutMetrics m;
  const Trajectory& t = rollout.trajectory;
  for (int k = 0; k < t.nodes(); ++k) {
    if (std::abs(t.ego[k].y - scene.lane_width) <= config.labels.reach) {
      m.time_to_target_lane = t.t[k];
      break;
    }
  }
  for (int k = 0; k < t.nodes(); ++k) {
    if (t.ego[k].y >= scene.lane_width / 2.0) {
      m.time_to_lane_line = t.t[k];
      break;
    }
  }
  traffic_measures(t, scene, m);
  car_measures(t, m);
  m.target_lane_slot = target_lane_slot(t, scene);
  m.forced_decel = rollout.forced_decel;
  m.unsafe_cut_in = rollout.forced_decel > config.closed_loop.unsafe_decel;
  double jerk_sq = 0.0;
  const auto applied = static_cast<int>(rollout.steps.size());
  for (int k = 0; k < applied; ++k) {
    const EgoControl& u = t.controls[static_cast<std::size_t>(k)];
    m.max_abs_accel = std::max(m.max_abs_accel, std::abs(u.a));
    m.max_abs_omega = std::max(m.max_abs_omega, std::abs(u.omega));
    const double before = k == 0 ? scene.ego.a : t.controls[static_cast<std::size_t>(k - 1)].a;
    jerk_sq += std::pow((u.a - before) / t.dt, 2);
  }
  m.rms_jerk = applied > 0 ? std::sqrt(jerk_sq / applied) : 0.0;
  std::vector<double> ms;
  planner::ActStatus before = planner::ActStatus::Planned;
  for (std::size_t k = 0; k < rollout.steps.size(); ++k) {
    const StepRecord& s = rollout.steps[k];
    if (s.lane_keeping) continue;
    ms.push_back(s.compute_ms);
    m.max_step_ms = std::max(m.max_step_ms, s.compute_ms);
    // A take-over lasts while the expert drives: count its start. It counts
    // where the planner decided it, even if that step's plan overran its
    // budget: a loaded machine would otherwise move it later.
    const bool took_over = s.decided == planner::ActStatus::TookOver;
    if (took_over && m.first_takeover_t < 0.0) m.first_takeover_t = t.t[k];
    m.takeovers += took_over && before != planner::ActStatus::TookOver ? 1 : 0;
    before = s.decided;
    m.fallbacks += s.status == planner::ActStatus::Fallback ? 1 : 0;
    m.failures += s.status == planner::ActStatus::Failed && !s.overrun ? 1 : 0;
    m.overruns += s.overrun ? 1 : 0;
  }
  for (const StepRecord& s : rollout.steps) m.clipped += s.clipped ? 1 : 0;
  // 0, not NaN, for a rollout whose planner never acted.
  m.median_step_ms = ms.empty() ? 0.0 : run::nearest_rank(ms, 0.5);
  m.p99_step_ms = ms.empty() ? 0.0 : run::nearest_rank(ms, 0.99);
  return m;
}

}  // namespace detail

}  // namespace lanechange::sim
