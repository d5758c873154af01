#include "lanechange/config.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <numbers>

#include "common/config_fields.hpp"

namespace lanechange {

namespace {

void require(bool ok, const char* field, const char* problem) {
  if (!ok) throw InputError(field, problem);
}

}  // namespace

double step_wall_limit_ms(const ClosedLoopSettings& c, double own_ms) {
  constexpr double kGuardBudgets = 10.0;
  return c.deadline == Deadline::WallClock ? own_ms
                                           : std::max(own_ms, kGuardBudgets * c.step_budget_ms);
}

namespace {

void validate_closed_loop(const ClosedLoopSettings& c) {
  require(c.settle_time >= 0, "closed_loop.settle_time", "must not be negative");
  require(c.step_budget_ms > 0, "closed_loop.step_budget_ms", "must be positive");
  require(c.step_qp_iterations > 0, "closed_loop.step_qp_iterations", "must be positive");
  require(c.replan_period >= 1, "closed_loop.replan_period", "must be at least 1");
  require(c.min_horizon > 0, "closed_loop.min_horizon", "must be positive");
  require(c.stale_plan_steps >= 0, "closed_loop.stale_plan_steps", "must not be negative");
  require(c.settled_heading > 0 && c.settled_offset > 0, "closed_loop",
          "settled_heading and settled_offset must be positive");
  require(c.keeper_lateral_gain > 0 && c.keeper_heading_gain > 0, "closed_loop",
          "the lane keeper's gains must be positive");
  require(c.keeper_rear_horizon >= 0 && std::isfinite(c.keeper_rear_horizon),
          "closed_loop.keeper_rear_horizon", "must be finite and not negative");
  require(c.keeper_backout_heading > 0 && c.keeper_backout_heading < std::numbers::pi / 2,
          "closed_loop.keeper_backout_heading", "must be in (0, pi/2) rad");
  require(c.lookahead >= 0, "closed_loop.lookahead", "must not be negative");
  require(c.lookahead_tolerance >= 0, "closed_loop.lookahead_tolerance", "must not be negative");
  require(c.refusal_check_period >= 0, "closed_loop.refusal_check_period", "must not be negative");
}

void validate_dwa(const DwaSettings& d) {
  require(d.horizon > 0 && d.horizon <= 10, "dwa.horizon", "must be in (0, 10] s");
  require(d.accel_samples >= 1 && d.accel_samples <= 101, "dwa.accel_samples",
          "must be in [1, 101]");
  require(d.yaw_rate_samples >= 1 && d.yaw_rate_samples <= 101, "dwa.yaw_rate_samples",
          "must be in [1, 101]");
  require(d.max_jerk > 0, "dwa.max_jerk", "must be positive");
  require(d.max_yaw_accel > 0, "dwa.max_yaw_accel", "must be positive");
  require(d.margin >= 0, "dwa.margin", "must not be negative");
  require(d.braking_decel > 0, "dwa.braking_decel", "must be positive");
  require(d.desired_speed >= 0, "dwa.desired_speed", "must not be negative");
  require(d.goal_preview > 0, "dwa.goal_preview", "must be positive");
  require(d.weight_lateral >= 0 && d.weight_heading >= 0 && d.weight_clearance >= 0 &&
              d.weight_speed >= 0,
          "dwa", "weights must not be negative");
}

void validate_lattice(const LatticeSettings& l) {
  require(l.min_duration > 0, "lattice.min_duration", "must be positive");
  require(l.max_duration >= l.min_duration && l.max_duration <= 20, "lattice.max_duration",
          "must be in [min_duration, 20] s");
  require(l.duration_samples >= 1 && l.duration_samples <= 50, "lattice.duration_samples",
          "must be in [1, 50]");
  require(l.offset_spread >= 0, "lattice.offset_spread", "must not be negative");
  require(l.speed_step > 0, "lattice.speed_step", "must be positive");
  require(l.speed_samples >= 1 && l.speed_samples <= 101, "lattice.speed_samples",
          "must be in [1, 101]");
  require(l.desired_speed >= 0, "lattice.desired_speed", "must not be negative");
  require(l.margin >= 0, "lattice.margin", "must not be negative");
  require(l.max_curvature > 0, "lattice.max_curvature", "must be positive");
  require(l.max_heading > 0 && l.max_heading < 1.5, "lattice.max_heading",
          "must be in (0, 1.5) rad");
  require(l.weight_jerk >= 0 && l.weight_duration >= 0 && l.weight_offset >= 0 &&
              l.weight_speed >= 0 && l.weight_lateral >= 0 && l.weight_longitudinal >= 0,
          "lattice", "weights must not be negative");
}

void validate_mpc(const MpcSettings& m) {
  require(m.circles >= 1 && m.circles <= 20, "mpc.circles", "must be between 1 and 20");
  require(std::isfinite(m.margin) && m.margin >= 0, "mpc.margin", "must not be negative");
  require(std::isfinite(m.time_limit_ms) && m.time_limit_ms > 0, "mpc.time_limit_ms",
          "must be positive");
  require(m.max_iterations >= 1, "mpc.max_iterations", "must be at least 1");
  require(m.step_iterations >= 1, "mpc.step_iterations", "must be at least 1");
  require(std::isfinite(m.tolerance) && m.tolerance > 0, "mpc.tolerance", "must be positive");
  require(std::isfinite(m.gate_distance) && m.gate_distance >= 0, "mpc.gate_distance",
          "must not be negative");
}

}  // namespace

void Config::validate() const {
  require(lane_width > 0, "lane_width", "must be positive");
  require(vehicle.length > 0, "vehicle.length", "must be positive");
  require(vehicle.width > 0, "vehicle.width", "must be positive");
  require(vehicle.width < lane_width, "vehicle.width", "must be narrower than the lane");
  require(limits.v.lo >= 0, "limits.v", "must not allow negative speeds");
  require(limits.a.lo < 0 && limits.a.hi > 0, "limits.a", "must contain zero strictly");
  require(limits.omega.lo < 0 && limits.omega.hi > 0, "limits.omega", "must contain zero strictly");
  require(limits.lateral_margin >= 0, "limits.lateral_margin", "must not be negative");
  require(idm.desired_speed > 0, "idm.desired_speed", "must be positive");
  require(idm.time_headway >= 0, "idm.time_headway", "must not be negative");
  require(idm.min_gap >= 0, "idm.min_gap", "must not be negative");
  require(idm.max_accel > 0, "idm.max_accel", "must be positive");
  require(idm.comfortable_decel > 0, "idm.comfortable_decel", "must be positive");
  require(idm.exponent > 0, "idm.exponent", "must be positive");
  require(!traffic_max_speed || *traffic_max_speed > 0, "traffic_max_speed",
          "must be positive, or null for no cap");
  require(traffic.reaction_time > 0, "traffic.reaction_time", "must be positive");
  require(traffic.follow_decel > 0, "traffic.follow_decel", "must be positive");
  require(traffic.min_gap >= 0, "traffic.min_gap", "must not be negative");
  require(!expert.cut_in_decel || *expert.cut_in_decel > 0, "expert.cut_in_decel",
          "must be positive or null");
  require(expert.restore_distance_within >= 0, "expert.restore_distance_within",
          "must not be negative");
  require(traffic.replay_prediction != Behavior::Replay, "traffic.replay_prediction",
          "must be a model (constant_speed, constant_accel or idm), not replay");
  require(!traffic.max_decel || *traffic.max_decel > 0, "traffic.max_decel",
          "must be positive, or null for no limit");
  require(closed_loop.unsafe_decel > 0, "closed_loop.unsafe_decel", "must be positive");
  for (const auto* d : {&safety.leader, &safety.follower, &safety.target}) {
    require(d->standstill >= 0 && d->time_headway >= 0, "safety", "distances must not be negative");
  }
  require(expert.horizon > 0, "expert.horizon", "must be positive");
  require(expert.steps >= 2 && expert.steps <= 10000, "expert.steps", "must be in [2, 10000]");
  require(expert.weight_accel >= 0 && expert.weight_jerk >= 0 && expert.weight_lateral >= 0 &&
              expert.weight_terminal_x >= 0,
          "expert", "cost weights must not be negative");
  require(expert.max_iterations >= 1, "expert.max_iterations", "must be at least 1");
  require(expert.convergence_tolerance > 0, "expert.convergence_tolerance", "must be positive");
  require(expert.cycle_tolerance >= 0, "expert.cycle_tolerance", "must not be negative");
  require(expert.trust_radius > 0, "expert.trust_radius", "must be positive");
  require(expert.trust_shrink > 0 && expert.trust_shrink < 1, "expert.trust_shrink",
          "must be in (0, 1)");
  require(expert.trust_rounds >= 1, "expert.trust_rounds", "must be at least 1");
  require(expert.big_m > 0, "expert.big_m", "must be positive");
  require(expert.line_clearance >= 0 && expert.line_clearance <= 1, "expert.line_clearance",
          "must be in [0, 1] m");
  require(std::isfinite(expert.min_turn_radius) && expert.min_turn_radius >= 0,
          "expert.min_turn_radius", "must be finite and not negative (0: off)");
  require(expert.prediction_lead_steps >= 0 && expert.prediction_lead_steps <= 10,
          "expert.prediction_lead_steps", "must be in [0, 10]");
  require(labels.reach > 0, "labels.reach", "must be positive");
  require(labels.reversal >= 0, "labels.reversal", "must not be negative");
  require(labels.max_final_heading > 0, "labels.max_final_heading", "must be positive");
  require(sampler.leader_speed.lo >= 0 && sampler.follower_speed.lo >= 0 &&
              sampler.target_speed.lo >= 0 && sampler.ego_speed_ratio.lo >= 0,
          "sampler", "speeds must not be negative");
  require(sampler.leader_headway.lo >= 0, "sampler.leader_headway", "must not be negative");
  require(sampler.gap_length.lo >= 0, "sampler.gap_length", "must not be negative");
  const Interval cars = sampler.target_lane_cars;
  require(cars.lo >= 0 && cars.hi <= 100 && cars.lo == std::floor(cars.lo) &&
              cars.hi == std::floor(cars.hi),
          "sampler.target_lane_cars", "must be whole numbers in [0, 100]");
  require(sampler.rear_headway.lo >= 0, "sampler.rear_headway", "must not be negative");
  validate_closed_loop(closed_loop);
  validate_dwa(dwa);
  validate_lattice(lattice);
  validate_mpc(mpc);
  require(strategy_qp.candidates >= 1, "strategy_qp.candidates", "must be at least 1");
  require(strategy_qp.screen_tolerance > 0.0 && strategy_qp.screen_tolerance < 1.0,
          "strategy_qp.screen_tolerance", "must lie in (0, 1)");
  require(strategy_qp.vote_pool >= 1, "strategy_qp.vote_pool", "must be at least 1");
  require(strategy_qp.replan_candidates >= 1, "strategy_qp.replan_candidates",
          "must be at least 1");
  require(strategy_qp.screen_keep >= 1, "strategy_qp.screen_keep", "must be at least 1");
  require(strategy_qp.other_gaps >= 0, "strategy_qp.other_gaps", "must not be negative");
}

TrafficSettings paper_traffic() {
  TrafficSettings t;
  t.followers_react = false;
  t.max_decel = std::nullopt;
  return t;
}

Config paper_formulation(Config config) {
  config.expert.gap = GapChoice::Fixed;
  config.expert.cut_in_decel = std::nullopt;
  config.expert.restore_distance_within = 0.0;
  config.traffic = paper_traffic();
  return config;
}

namespace {

// The authors' public MATLAB code (NOTES.md and reference/README.md).
Config authors_preset() {
  Config c;
  c.preset = "authors";
  c.idm.desired_speed = 30.0 / 3.6;
  c.idm.max_accel = 6.0;
  c.safety.leader = {0.0, 3.0};
  c.safety.target = {0.0, 3.0};
  c.safety.follower = {0.0, 0.0};
  c.expert.weight_terminal_x = 0.005;
  c.expert.jerk_weighting = JerkWeighting::Difference;
  c.expert.lane_rule = LaneRule::Footprint;
  c.expert.line_clearance = 0.0;
  c.expert.constrain_initial_node = true;
  c.expert.prediction_lead_steps = 1;
  c.expert.warm_start = WarmStart::Authors;
  c.expert.aim_behind_target = false;
  c.expert.globalisation = Globalisation::Off;  // more than 10 rounds is a failure there
  c.expert.gap = GapChoice::Fixed;
  c.expert.cut_in_decel = std::nullopt;
  c.expert.restore_distance_within = 0.0;
  c.traffic_integration = TrafficIntegration::Euler;
  c.traffic = paper_traffic();
  c.sampler.target_speed = {20.0 / 3.6, 40.0 / 3.6};
  return c;
}

}  // namespace

std::vector<std::string> preset_names() { return {"paper", "authors"}; }

Config make_preset(std::string_view name) {
  if (name == "paper") return Config{};
  if (name == "authors") return authors_preset();
  throw InputError("preset",
                   "unknown preset \"" + std::string(name) + "\" (expected paper or authors)");
}

void to_json(nlohmann::json& out, const Config& config) { out = detail::write_value(config); }

nlohmann::json expert_data_config(nlohmann::json config) {
  if (config.is_object()) {
    for (const char* planner_only : {"mpc", "dwa", "lattice", "strategy_qp"}) {
      config.erase(planner_only);
    }
  }
  return config;
}

Config config_from_json(const nlohmann::json& in) {
  if (!in.is_object()) throw InputError("", "a config must be a JSON object");
  std::string preset = "paper";
  if (auto it = in.find("preset"); it != in.end()) detail::read_value(*it, "preset", preset);
  Config config = make_preset(preset);
  detail::read_value(in, "", config);
  config.validate();
  return config;
}

Config load_config(const std::string& path) {
  return config_from_json(detail::read_json_file(path));
}

void save_config(const Config& config, const std::string& path) {
  detail::write_file_atomically(path, detail::write_value(config).dump(2) + "\n");
}

}  // namespace lanechange
