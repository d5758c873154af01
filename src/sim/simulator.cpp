#include "lanechange/sim/simulator.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <exception>
#include <limits>

#include "lanechange/checks.hpp"
#include "lanechange/ego.hpp"
#include "lanechange/traffic.hpp"
#include "sim/metrics.hpp"

namespace lanechange::sim {

namespace {

using planner::ActStatus;
using planner::Decision;
using planner::Observation;
using Clock = std::chrono::steady_clock;

// The run's state: the real cars and the ego, and what has been recorded.
class Loop {
 public:
  Loop(const Scenario& scene, const Config& config)
      : scene_(scene),
        planning_scene_(planning_view(scene, config.traffic)),
        config_(config),
        traffic_(scene, config, TrafficModel::Records::Replay),
        keeper_(config) {
    ego_ = scene.ego;
    dt_ = scene.horizon / scene.steps;
    path_.dt = dt_;
    path_.lane_width = scene.lane_width;
    path_.target_side = scene.target_side;
    path_.others.dt = dt_;
    path_.others.cars.resize(scene.car_count());
    path_.cars = tracked_cars(scene);
    observation_.scene = &planning_scene_;
    observation_.cars.resize(scene.car_count());
    record_node();
  }

  void run(const planner::ClosedLoopPlanner& planner, int steps, Rollout& out) {
    path_.planner = std::string(planner.name());
    auto session = planner.start(planning_scene_);
    for (int k = 0; k < steps; ++k) {
      const Observation& o = observe(k);
      StepRecord record;
      EgoControl u = over_ ? keep_target_lane(o, record) : ask(*session, o, record);
      record.clipped = planner::clip_to_limits(u, ego_, scene_.limits, dt_);
      advance(u);
      settle_check(k + 1, out);
      out.steps.push_back(std::move(record));
    }
    // The last node repeats the control before it (formats.md).
    path_.controls.push_back(path_.controls.empty() ? EgoControl{} : path_.controls.back());
    out.trajectory = std::move(path_);
    out.forced_decel = forced_decel_;
  }

 private:
  // Updated in place: a step allocates nothing for what the planner sees.
  const Observation& observe(int k) {
    observation_.step = k;
    observation_.t = k * dt_;
    observation_.ego = ego_;
    std::copy(traffic_.cars().begin(), traffic_.cars().end(), observation_.cars.begin());
    return observation_;
  }

  EgoControl keep_target_lane(const Observation& o, StepRecord& record) const {
    record.lane_keeping = true;
    return keeper_.control(o.ego, scene_.lane_width, planner::car_ahead(o, true),
                           planner::car_behind(o, true));
  }

  // The planner's answer, timed; a throw or an overrun hands the step to the
  // fallback and is recorded.
  EgoControl ask(planner::PlannerSession& session, const Observation& o, StepRecord& record) {
    const auto start = Clock::now();
    Decision d;
    try {
      d = session.act(o);
    } catch (const std::exception& e) {
      d = {{}, ActStatus::Failed, std::string("the planner threw: ") + e.what()};
    }
    record.compute_ms = std::chrono::duration<double, std::milli>(Clock::now() - start).count();
    record.status = d.status;
    record.decided = d.status;
    record.reason = d.reason;
    if (record.compute_ms > config_.closed_loop.step_budget_ms && d.status != ActStatus::Failed) {
      record.overrun = true;
      // Under a deadline of work the decision stands: marked, not overruled.
      if (config_.closed_loop.deadline == Deadline::WallClock) {
        record.status = ActStatus::Failed;
        record.reason = "over its budget of " + std::to_string(config_.closed_loop.step_budget_ms) +
                        " ms; the fallback acted" +
                        (d.reason.empty() ? "" : " (the planner: " + d.reason + ")");
      }
    }
    if (record.status == ActStatus::Failed) return planner::fallback_control(keeper_, o);
    return d.control;
  }

  void advance(EgoControl u) {
    path_.controls.push_back(u);
    // The cars react to where the ego is at the start of the step, as the
    // ego's controller reacts to where they are.
    traffic_.step(dt_, {ego_.x, ego_.y, ego_.v});
    ego_ = step_exact(ego_, u, dt_);
    ego_.a = u.a;
    record_node();
  }

  void record_node() {
    path_.t.push_back(static_cast<double>(path_.t.size()) * dt_);
    path_.ego.push_back(ego_);
    for (CarIndex c = 0; c < traffic_.car_count(); ++c) {
      CarTrack& track = path_.others.cars[c];
      const CarState& car = traffic_.car(c);
      track.x.push_back(car.x);
      track.v.push_back(car.v);
      // The acceleration applied from this node on is known one step later;
      // until then it repeats the last one.
      if (!track.a.empty()) track.a.back() = car.a;
      track.a.push_back(car.a);
      if (traffic_.followed_ego(c)) forced_decel_ = std::max(forced_decel_, -car.a);
    }
  }

  void settle_check(int node, Rollout& out) {
    if (over_) return;
    const ClosedLoopSettings& c = config_.closed_loop;
    // The lane keeper's heading response still carries an ego that heads
    // back towards the ego lane about v |theta| / gain further: handed over
    // too early, that drift becomes a reversal the judge counts.
    peak_y_ = std::max(peak_y_, ego_.y);
    const double drift = std::max(0.0, -ego_.theta) * ego_.v / c.keeper_heading_gain;
    const bool keeper_holds =
        ego_.theta >= 0.0 ||
        std::min(peak_y_, scene_.lane_width) - (ego_.y - drift) <= config_.labels.reversal / 2;
    if (std::abs(ego_.y - scene_.lane_width) <= c.settled_offset &&
        std::abs(ego_.theta) <= c.settled_heading && keeper_holds) {
      over_ = true;
      out.manoeuvre_over_at = node * dt_;
    }
  }

  const Scenario& scene_;
  /// What the planners see: replayed cars by their predicted behavior, no record.
  Scenario planning_scene_;
  const Config& config_;
  TrafficModel traffic_;
  planner::LaneKeeper keeper_;
  EgoState ego_;
  double dt_ = 0.1;
  bool over_ = false;
  double peak_y_ = -std::numeric_limits<double>::infinity();
  Trajectory path_;
  Observation observation_;
  double forced_decel_ = 0.0;
};

// Not at fault: run into from behind by a car of the lane the ego's body has
// been wholly in for at least kReactionTime, time that car had to react. A
// cut-in closer than that, or any other contact, is the ego's.
bool at_fault(const Trajectory& t, const Scenario& scene, const Collision& hit) {
  constexpr double kReactionTime = 1.0;  // s
  const auto node = static_cast<std::size_t>(hit.node);
  const double half_width = scene.vehicle.width / 2.0;
  const double lane = scene.lane_center(hit.car);
  auto inside = [&](std::size_t k) {
    return std::abs(t.ego[k].y - lane) + half_width <= scene.lane_width / 2.0;
  };
  if (t.others.car(hit.car).x[node] >= t.ego[node].x) return true;
  std::size_t first = node;
  while (first > 0 && inside(first - 1)) --first;
  return !inside(node) || t.t[node] - t.t[first] < kReactionTime;
}

}  // namespace

Rollout simulate(const Scenario& scene, const planner::ClosedLoopPlanner& planner,
                 const Config& base, const SimOptions& options) {
  const Config config = effective_config(base, scene);
  const double duration =
      options.duration > 0.0 ? options.duration : scene.horizon + config.closed_loop.settle_time;
  const double dt = scene.horizon / scene.steps;
  const int steps = std::max(1, static_cast<int>(std::lround(duration / dt)));
  Rollout out;
  Loop loop(scene, config);
  loop.run(planner, steps, out);
  Trajectory& t = out.trajectory;
  const auto hit = first_collision(t.ego, t.others, scene);
  t.collision = hit.has_value();
  out.outcome = judge(t, config, out.reason);
  if (hit) {
    out.collision_at_fault = at_fault(t, scene, *hit);
    out.reason = "collision with the " + scene.cars[hit->car].id + " at " +
                 std::to_string(hit->time) + " s" +
                 (out.collision_at_fault ? "" : " (run into from behind: not at fault)");
  }
  t.label = out.outcome == Outcome::WellPosed  ? Label::WellPosed
            : out.outcome == Outcome::IllPosed ? Label::IllPosed
                                               : Label::Failure;
  t.reason = out.reason;
  if (const auto gap = detail::gap_taken(t, scene)) t.details["gap"] = *gap;
  out.metrics = detail::measure(out, scene, config);
  t.compute_total_ms = 0.0;
  for (const StepRecord& s : out.steps) t.compute_total_ms += s.compute_ms;
  t.compute_max_step_ms = out.metrics.max_step_ms;
  return out;
}

}  // namespace lanechange::sim
