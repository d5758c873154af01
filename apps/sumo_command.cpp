// lanechange sumo: one episode of a planner in SUMO traffic (docs/sumo.md).
#include <filesystem>
#include <iostream>

#include "commands.hpp"
#include "lanechange/baselines/baselines.hpp"
#include "lanechange/error.hpp"
#include "lanechange/run/quantile.hpp"
#include "lanechange/sim/simulator.hpp"
#include "lanechange/sumo/cosim.hpp"

namespace lanechange::app {

namespace {

struct SumoArgs {
  std::string planner = "miqp";
  std::string model_dir;
  bool highway = false;
  std::string commonroad;  ///< an interactive scenario folder
  sumo::HighwaySettings road;
  sumo::CoSimSettings loop;
  std::string prediction = "constant_speed";
  std::string out_path;
};

void run_episode(SumoArgs& a, const Config& given) {
  if (a.highway == !a.commonroad.empty()) {
    throw InputError("--highway", "name the traffic: --highway or --commonroad DIR");
  }
  const Config config = sumo::as_sumo_drives(
      given, a.highway ? sumo::SumoCarModel{} : sumo::commonroad_car_model(a.commonroad));
  a.loop.prediction = behavior_from_string(a.prediction, "--prediction");
  if (a.loop.work_dir.empty()) a.loop.work_dir = a.out_path + ".sumo";
  const auto planner = baselines::make_planner(a.planner, config, a.model_dir);
  sumo::CoSimResult r = a.highway ? sumo::run_highway(*planner, config, a.road, a.loop)
                                  : sumo::run_commonroad(*planner, config, a.commonroad, a.loop);
  nlohmann::json& details = r.rollout.trajectory.details;
  details["sumo"] = {{"collisions", r.sumo_collisions},
                     {"scenes", r.scenes},
                     {"median_step_ms", run::nearest_rank(r.sumo_step_ms, 0.5)},
                     {"max_step_ms", run::nearest_rank(r.sumo_step_ms, 1.0)},
                     {"max_pose_error", r.max_pose_error},
                     {"follower_braking", r.follower_braking}};
  sim::save_rollout(r.rollout, a.out_path);
  const auto& m = r.rollout.metrics;
  std::cerr << "outcome " << sim::to_string(r.rollout.outcome)
            << (r.rollout.trajectory.collision ? " (collision)" : "") << ", "
            << r.rollout.steps.size() << " steps, " << r.scene.car_count()
            << " car tracks, planner median step " << m.median_step_ms << " ms, SUMO median step "
            << run::nearest_rank(r.sumo_step_ms, 0.5) << " ms, forced braking " << m.forced_decel
            << " m/s^2 (the cars behind it braked " << r.follower_braking << ")"
            << (r.rollout.reason.empty() ? "" : "; " + r.rollout.reason) << "\n";
}

}  // namespace

void add_sumo(CLI::App& app, const ConfigSource& config) {
  auto* cmd = app.add_subcommand("sumo", "Run one lane change of a planner in SUMO traffic");
  auto a = make_args<SumoArgs>();
  add_planner_option(*cmd, a->planner, "Planner");
  cmd->add_option("--model", a->model_dir,
                  "Model directory (lanechange train), for mlp-miqp and strategy-qp");
  cmd->add_flag("--highway", a->highway, "A straight road with seeded random traffic");
  cmd->add_option("--commonroad", a->commonroad,
                  "A CommonRoad interactive scenario folder (NAME.cr.xml, NAME.net.xml, ...)");
  cmd->add_option("--lanes", a->road.lanes, "Lanes of the highway")->capture_default_str();
  cmd->add_option("--length", a->road.length, "Length of the highway, m")->capture_default_str();
  cmd->add_option("--density", a->road.density, "Cars per lane and km")->capture_default_str();
  cmd->add_option("--speed-limit", a->road.speed_limit, "m/s")->capture_default_str();
  cmd->add_option("--seed", a->road.seed, "Seeds the traffic and SUMO")->capture_default_str();
  cmd->add_option("--settle", a->road.settle_time, "Seconds of traffic before the ego enters")
      ->capture_default_str();
  cmd->add_option("--range", a->loop.range, "m from the ego: the cars the planner sees")
      ->capture_default_str();
  cmd->add_option("--request-after", a->loop.request_after,
                  "Seconds in the ego lane before the change is asked")
      ->capture_default_str();
  cmd->add_option("--duration", a->loop.duration,
                  "Seconds from the request (default: the horizon plus closed_loop.settle_time)");
  cmd->add_option("--prediction", a->prediction,
                  "How planners predict SUMO's cars: idm, constant_speed or constant_accel")
      ->capture_default_str();
  cmd->add_flag("!--no-signal", a->loop.signal_change,
                "The ego does not ask SUMO for the change: SUMO's cars do not cooperate with it");
  cmd->add_option("--work", a->loop.work_dir, "Directory for SUMO's files (default: OUT.sumo)");
  cmd->add_option("--out", a->out_path, "Rollout JSON file")->required();
  cmd->callback([a, config] { run_episode(*a, config()); });
}

}  // namespace lanechange::app
