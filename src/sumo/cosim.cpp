// The co-simulation's closed loop: the same steps as our simulator's
// (sim/loop_steps.hpp), with SUMO moving the other cars.
#include "lanechange/sumo/cosim.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <utility>

#include "lanechange/ego.hpp"
#include "lanechange/error.hpp"
#include "lanechange/trajectory.hpp"
#include "sim/loop_steps.hpp"
#include "sumo/connection.hpp"
#include "sumo/highway.hpp"
#include "sumo/interactive.hpp"
#include "sumo/tracks.hpp"

namespace lanechange::sumo {

namespace {

using detail::SumoCar;
using Clock = std::chrono::steady_clock;

// m beyond the range a car seen once stays in the planner's scene, so that
// a car at the range's edge does not hand the planner a new scene each step.
constexpr double kRangeHysteresis = 20.0;

// The planner's scene: the cars around the ego now, as a scene that starts now.
Scenario scene_of(const Config& config, const EgoState& ego, const std::vector<SumoCar>& cars,
                  Behavior prediction, double desired_speed, Side side) {
  Scenario s = default_scenario(config);
  s.target_side = side;
  s.behavior = prediction;
  s.idm.desired_speed = desired_speed;
  s.ego = ego;
  for (const SumoCar& car : cars) s.cars.push_back(as_other_car(car, prediction));
  for (const Role role : kRoles) s.roles[static_cast<std::size_t>(role)] = nearest_in_role(s, role);
  return s;
}

// s: the closed loop's step, the plans' node spacing.
double step_length(const Config& config) {
  const Scenario defaults = default_scenario(config);
  return defaults.horizon / defaults.steps;
}

class Episode {
 public:
  Episode(detail::SumoConnection& sumo, detail::RoadFrame frame, const Config& config,
          const CoSimSettings& settings, double speed_limit)
      : sumo_(sumo),
        frame_(std::move(frame)),
        config_(config),
        settings_(settings),
        keeper_(config),
        settle_(config, config.lane_width),
        dt_(step_length(config)),
        desired_speed_(speed_limit) {}

  CoSimResult run(const planner::ClosedLoopPlanner& planner, EgoState ego) {
    ego_ = ego;
    const double dt = dt_;
    warm_up(dt);
    const double duration = settings_.duration > 0.0 ? settings_.duration
                                                     : default_scenario(config_).horizon +
                                                           config_.closed_loop.settle_time;
    const int steps = std::max(1, static_cast<int>(std::lround(duration / dt)));
    if (settings_.signal_change) {
      sumo_.signal_ego_change(frame_.side() == Side::Left ? 1 : -1, duration);
    }
    CoSimResult out;
    sim::Rollout& rollout = out.rollout;
    path_.planner = std::string(planner.name());
    path_.dt = dt;
    path_.lane_width = config_.lane_width;
    path_.target_side = frame_.side();
    path_.others.dt = dt;
    const EgoState start = ego_;
    std::unique_ptr<planner::PlannerSession> session;
    read_cars();
    for (int k = 0; k <= steps; ++k) {
      if (update_scene(planner, session, k)) ++out.scenes;
      record_node(k);
      if (k == steps) break;
      const planner::Observation& o = observation_;
      sim::StepRecord record;
      EgoControl u = over_ ? keep_lane(o, true, record) : ask(*session, o, record);
      record.clipped = planner::clip_to_limits(u, ego_, scene_.limits, dt);
      path_.controls.push_back(u);
      out.sumo_step_ms.push_back(advance(u, dt, k, out));
      if (!over_ && settle_.settled(ego_)) {
        over_ = true;
        rollout.manoeuvre_over_at = (k + 1) * dt;
      }
      rollout.steps.push_back(std::move(record));
    }
    path_.controls.push_back(path_.controls.empty() ? EgoControl{} : path_.controls.back());
    out.scene = tracks_.scene(
        scene_of(config_, start, {}, settings_.prediction, desired_speed_, frame_.side()),
        first_roles_);
    path_.cars = tracked_cars(out.scene);
    path_.others.cars = tracks_.take_tracks(path_.t.size());
    path_.collision = !contacts_.empty();
    rollout.trajectory = std::move(path_);
    rollout.forced_decel = forced_decel_;
    sim::detail::finish_rollout(rollout, out.scene, config_);
    explain_sumo_contact(rollout);
    out.sumo_collisions = static_cast<int>(contacts_.size());
    out.max_pose_error = max_pose_error_;
    return out;
  }

 private:
  // The lane keeper drives the ego in its lane, unrecorded, while the cars
  // around react to it.
  void warm_up(double dt) {
    const int steps = static_cast<int>(std::lround(settings_.request_after / dt));
    for (int k = 0; k < steps; ++k) {
      sumo_.cars_near(frame_, ego_.x, settings_.range, near_);
      scene_ = scene_of(config_, ego_, near_, settings_.prediction, desired_speed_, frame_.side());
      fill_observation(0);
      sim::StepRecord unused;
      EgoControl u = keep_lane(observation_, false, unused);
      (void)planner::clip_to_limits(u, ego_, scene_.limits, dt);
      ego_ = step_exact(ego_, u, dt);
      ego_.a = u.a;
      sumo_.move_ego(frame_, ego_, config_.vehicle.length);
      sumo_.step();
    }
  }

  // The cars around the ego now, out to the range and its hysteresis: once
  // per step, after SUMO's.
  void read_cars() { sumo_.cars_near(frame_, ego_.x, settings_.range + kRangeHysteresis, near_); }

  // A new scene, and a new planner session, where the cars around the ego
  // changed (entered or left the range, or changed lanes). Returns whether it
  // did. The clock runs on from the request: the manoeuvre's deadline is the
  // request's, whatever cars come and go.
  bool update_scene(const planner::ClosedLoopPlanner& planner,
                    std::unique_ptr<planner::PlannerSession>& session, int k) {
    std::erase_if(near_, [&](const SumoCar& c) {
      return std::abs(c.state.x - ego_.x) > settings_.range && !in_scene(c);
    });
    const bool same =
        session && near_.size() == scene_.car_count() &&
        std::all_of(near_.begin(), near_.end(), [&](const SumoCar& c) { return in_scene(c); });
    if (!same) {
      scene_ = scene_of(config_, ego_, near_, settings_.prediction, desired_speed_, frame_.side());
      session = planner.start(scene_);
      if (k == 0) {
        for (const Role role : kRoles) {
          if (scene_.has(role))
            first_roles_[static_cast<std::size_t>(role)] = scene_.cars[scene_.index_of(role)].id;
        }
      }
    }
    fill_observation(k);
    return !same;
  }

  [[nodiscard]] bool in_scene(const SumoCar& c) const {
    const auto at = scene_.find(c.id);
    return at && scene_.cars[*at].lane == c.lane;
  }

  void fill_observation(int step) {
    observation_.scene = &scene_;
    observation_.step = step;
    observation_.t = step * dt_;
    observation_.ego = ego_;
    observation_.cars.assign(scene_.car_count(), CarState{});
    for (const SumoCar& c : near_) {
      if (const auto at = scene_.find(c.id)) observation_.cars[*at] = c.state;
    }
  }

  EgoControl keep_lane(const planner::Observation& o, bool target, sim::StepRecord& record) const {
    record.lane_keeping = true;
    return sim::detail::keep_lane(keeper_, o, target);
  }

  EgoControl ask(planner::PlannerSession& session, const planner::Observation& o,
                 sim::StepRecord& record) const {
    return sim::detail::ask_planner(session, o, config_, keeper_, record);
  }

  // Moves the ego by our model, puts it into SUMO and steps SUMO; returns
  // SUMO's share of the step in ms.
  double advance(EgoControl u, double dt, int k, CoSimResult& out) {
    ego_ = step_exact(ego_, u, dt);
    ego_.a = u.a;
    const auto start = Clock::now();
    sumo_.move_ego(frame_, ego_, config_.vehicle.length);
    sumo_.step();
    const double ms = std::chrono::duration<double, std::milli>(Clock::now() - start).count();
    max_pose_error_ =
        std::max(max_pose_error_, sumo_.ego_pose_error(frame_, ego_, config_.vehicle.length));
    for (const detail::SumoContact& c : sumo_.ego_contacts()) {
      contacts_.push_back({c, (k + 1) * dt});
    }
    read_cars();
    const detail::FollowerBraking braking = sumo_.cars_behind_ego(near_, dt, out.followers);
    forced_decel_ = std::max(forced_decel_, braking.forced);
    out.follower_braking = std::max(out.follower_braking, braking.actual);
    return ms;
  }

  void record_node(int k) {
    path_.t.push_back(k * dt_);
    path_.ego.push_back(ego_);
    tracks_.record(k, near_);
  }

  // SUMO saw a contact that our check of the bodies did not: say so.
  void explain_sumo_contact(sim::Rollout& rollout) const {
    if (contacts_.empty() || rollout.reason.rfind("collision", 0) == 0) return;
    const auto& [c, t] = contacts_.front();
    rollout.collision_at_fault = c.ego_collider;
    rollout.reason = "SUMO reports a collision with " + c.other + " at " + std::to_string(t) + " s";
    rollout.trajectory.reason = rollout.reason;
  }

  detail::SumoConnection& sumo_;
  detail::RoadFrame frame_;
  const Config& config_;
  CoSimSettings settings_;
  planner::LaneKeeper keeper_;
  sim::detail::SettleCheck settle_;
  EgoState ego_;
  Scenario scene_;
  std::array<std::string, 3> first_roles_;
  std::vector<SumoCar> near_;
  planner::Observation observation_;
  detail::TrackRecorder tracks_;
  Trajectory path_;
  double dt_;
  double desired_speed_;  ///< m/s: of the predicted cars (IDM), the road's speed limit
  bool over_ = false;
  double forced_decel_ = 0.0;
  double max_pose_error_ = 0.0;
  std::vector<std::pair<detail::SumoContact, double>> contacts_;
};

// SUMO's options beside the network and traffic files.
std::vector<std::string> sumo_arguments(double dt, int seed, const std::string& dir) {
  return {"--step-length", std::to_string(dt), "--seed", std::to_string(seed),
          // The sublane model: a straddling ego occupies both lanes, so the
          // cars of both see it, and lateral contacts are checked.
          "--lateral-resolution", "0.8",
          // A contact is reported, never resolved by moving a car away.
          "--collision.action", "warn", "--collision.mingap-factor", "0", "--time-to-teleport",
          "-1", "--no-step-log", "true", "--no-warnings", "true", "--duration-log.disable", "true",
          "--xml-validation", "never", "--error-log", dir + "/sumo_errors.log"};
}

}  // namespace

Config as_sumo_drives(Config config, const SumoCarModel& cars) {
  config.traffic.sees_ego = SeesEgo::Overlapping;
  config.traffic.follow_decel = cars.decel;
  config.traffic.min_gap = cars.min_gap;
  config.traffic.reaction_time = cars.tau;
  return config;
}

void validate(const HighwaySettings& h) {
  if (h.lanes < 2 || h.lanes > 8) throw InputError("lanes", "must be 2 to 8");
  if (h.ego_lane < 0 || h.ego_lane + 1 >= h.lanes) {
    throw InputError("ego_lane", "needs a lane to its left: 0 to lanes - 2");
  }
  if (!(h.length >= 500.0 && h.length <= 100000.0))
    throw InputError("length", "must be 500 m to 100 km");
  if (!(h.density > 0.0 && h.density <= 120.0)) {
    throw InputError("density", "must be above 0 and at most 120 cars per lane and km");
  }
  if (!(h.speed_limit > 0.0 && h.speed_limit <= 70.0))
    throw InputError("speed_limit", "must be in (0, 70] m/s");
  if (!(h.settle_time >= 0.0 && h.settle_time <= 3600.0))
    throw InputError("settle_time", "must be 0 to 3600 s");
  if (!(h.ego_position >= 100.0 && h.ego_position <= h.length - 300.0)) {
    throw InputError("ego_position",
                     "must leave 100 m behind and 300 m ahead of the ego on the road");
  }
}

void validate(const CoSimSettings& s) {
  if (!(s.range >= 20.0 && s.range <= 1000.0)) throw InputError("range", "must be 20 to 1000 m");
  if (!(s.request_after >= 0.0 && s.request_after <= 600.0))
    throw InputError("request_after", "must be 0 to 600 s");
  if (!(s.duration >= 0.0 && s.duration <= 600.0))
    throw InputError("duration", "must be 0 to 600 s");
  if (s.prediction == Behavior::Replay)
    throw InputError("prediction", "SUMO's cars have no record to replay");
  if (s.work_dir.empty()) throw InputError("work_dir", "needs a directory for SUMO's files");
}

CoSimResult run_highway(const planner::ClosedLoopPlanner& planner, const Config& config,
                        const HighwaySettings& highway, const CoSimSettings& settings) {
  validate(highway);
  validate(settings);
  std::filesystem::create_directories(settings.work_dir);
  const detail::HighwayFiles files =
      detail::write_highway(highway, config.lane_width, settings.work_dir);
  std::vector<std::string> args =
      sumo_arguments(step_length(config), highway.seed, settings.work_dir);
  args.insert(args.begin(), {"-n", files.network, "-r", files.routes});
  detail::SumoConnection sumo(args);
  const int settle_steps = static_cast<int>(std::lround(highway.settle_time / step_length(config)));
  for (int k = 0; k < settle_steps; ++k) sumo.step();
  const double lane_y = (highway.ego_lane + 0.5) * config.lane_width;
  const detail::RoadFrame frame({{0.0, lane_y}, {highway.length, lane_y}}, config.lane_width,
                                Side::Left);
  const EgoState ego =
      sumo.replace_car_with_ego(frame, detail::highway_lane(highway.ego_lane), highway.ego_position,
                                config.vehicle, config.limits);
  sumo.step();
  Episode episode(sumo, frame, config, settings, highway.speed_limit);
  return episode.run(planner, ego);
}

CoSimResult run_commonroad(const planner::ClosedLoopPlanner& planner, const Config& config,
                           const std::string& folder, const CoSimSettings& settings) {
  validate(settings);
  std::filesystem::create_directories(settings.work_dir);
  const detail::InteractiveScenario scenario = detail::read_interactive(folder, settings.work_dir);
  std::vector<std::string> args = sumo_arguments(step_length(config), 0, settings.work_dir);
  args.insert(args.begin(), scenario.sumo_files.begin(), scenario.sumo_files.end());
  // A recorded car whose route SUMO cannot drive (a ramp entered from the
  // main road) is left out, named in sumo_errors.log, rather than the scenario.
  args.insert(args.end(), {"--ignore-route-errors", "true"});
  std::optional<detail::SumoConnection> sumo;
  try {
    sumo.emplace(args);
  } catch (const std::exception& e) {
    throw InputError(folder, std::string("SUMO cannot load it: ") + e.what());
  }
  const commonroad::State& start = scenario.start;
  const detail::EgoRoad road = sumo->road_at(start.position.x, start.position.y);
  const bool left = road.lane_index + 1 < road.lanes;
  if (!left && road.lane_index == 0) {
    throw InputError(folder, "the planning problem's lane has no neighbour to change to");
  }
  // The scene's lane width is the ego lane's own.
  Config local = config;
  local.lane_width = road.lane_width;
  const detail::RoadFrame frame(road.centre, road.lane_width, left ? Side::Left : Side::Right);
  const detail::RoadPose pose =
      frame.to_road({start.position.x, start.position.y, start.orientation});
  EgoState ego{pose.x, pose.y, std::clamp(start.velocity, config.limits.v.lo, config.limits.v.hi),
               pose.theta, 0.0};
  sumo->add_ego(frame, road.edges, ego, config.vehicle);
  sumo->step();
  Episode episode(*sumo, frame, local, settings, road.speed_limit);
  return episode.run(planner, ego);
}

}  // namespace lanechange::sumo
