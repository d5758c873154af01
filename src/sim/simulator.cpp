#include "lanechange/sim/simulator.hpp"

#include <algorithm>
#include <cmath>

#include "lanechange/checks.hpp"
#include "lanechange/ego.hpp"
#include "lanechange/traffic.hpp"
#include "sim/loop_steps.hpp"

namespace lanechange::sim {

namespace {

using planner::Observation;

// The run's state: the real cars and the ego, and what has been recorded.
class Loop {
 public:
  Loop(const Scenario& scene, const Config& config)
      : scene_(scene),
        planning_scene_(planning_view(scene, config.traffic)),
        config_(config),
        traffic_(scene, config, TrafficModel::Records::Replay),
        keeper_(config),
        settle_(config, scene.lane_width) {
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
    for (CarIndex c = 0; c < traffic_.car_count(); ++c) observation_.cars[c] = traffic_.observed(c);
    return observation_;
  }

  EgoControl keep_target_lane(const Observation& o, StepRecord& record) const {
    record.lane_keeping = true;
    return detail::keep_lane(keeper_, o, true);
  }

  EgoControl ask(planner::PlannerSession& session, const Observation& o, StepRecord& record) {
    return detail::ask_planner(session, o, config_, keeper_, record);
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
    if (over_ || !settle_.settled(ego_)) return;
    over_ = true;
    out.manoeuvre_over_at = node * dt_;
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
  detail::SettleCheck settle_;
  Trajectory path_;
  Observation observation_;
  double forced_decel_ = 0.0;
};

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
  detail::finish_rollout(out, scene, config);
  return out;
}

}  // namespace lanechange::sim
