#pragma once
// The field lists of the config structs, shared by the config and scenario
// readers and writers.
#include <array>
#include <concepts>

#include "common/json_fields.hpp"
#include "lanechange/config.hpp"

namespace lanechange {

inline constexpr std::array<detail::EnumName<LaneRule>, 3> enum_names(LaneRule) {
  return {{{LaneRule::EitherOr, "either_or"},
           {LaneRule::Footprint, "footprint"},
           {LaneRule::FootprintHeading, "footprint_heading"}}};
}

inline constexpr std::array<detail::EnumName<JerkWeighting>, 2> enum_names(JerkWeighting) {
  return {{{JerkWeighting::Derivative, "derivative"}, {JerkWeighting::Difference, "difference"}}};
}

inline constexpr std::array<detail::EnumName<WarmStart>, 2> enum_names(WarmStart) {
  return {{{WarmStart::Quintic, "quintic"}, {WarmStart::Authors, "authors"}}};
}

inline constexpr std::array<detail::EnumName<TrafficIntegration>, 2> enum_names(
    TrafficIntegration) {
  return {{{TrafficIntegration::Ballistic, "ballistic"}, {TrafficIntegration::Euler, "euler"}}};
}

inline constexpr std::array<detail::EnumName<ReversalReference>, 2> enum_names(ReversalReference) {
  return {{{ReversalReference::TargetCenter, "target_center"},
           {ReversalReference::RunningMax, "running_max"}}};
}

inline constexpr std::array<detail::EnumName<HorizonMode>, 2> enum_names(HorizonMode) {
  return {{{HorizonMode::Receding, "receding"}, {HorizonMode::Shrinking, "shrinking"}}};
}

inline constexpr std::array<detail::EnumName<Deadline>, 2> enum_names(Deadline) {
  return {{{Deadline::Work, "work"}, {Deadline::WallClock, "wall_clock"}}};
}

template <class V, class S>
void visit_fields(V& v, S& s) requires std::same_as<std::remove_const_t<S>, ClosedLoopSettings> {
  v("settle_time", s.settle_time);
  v("step_budget_ms", s.step_budget_ms);
  v("deadline", s.deadline);
  v("step_qp_iterations", s.step_qp_iterations);
  v("replan_period", s.replan_period);
  v("horizon_mode", s.horizon_mode);
  v("monotone_lateral", s.monotone_lateral);
  v("min_horizon", s.min_horizon);
  v("stale_plan_steps", s.stale_plan_steps);
  v("settled_heading", s.settled_heading);
  v("settled_offset", s.settled_offset);
  v("keeper_lateral_gain", s.keeper_lateral_gain);
  v("keeper_heading_gain", s.keeper_heading_gain);
  v("keeper_rear_horizon", s.keeper_rear_horizon);
  v("keeper_backout_heading", s.keeper_backout_heading);
  v("lookahead", s.lookahead);
  v("lookahead_tolerance", s.lookahead_tolerance);
  v("refusal_check_period", s.refusal_check_period);
  v("unsafe_decel", s.unsafe_decel);
}

inline constexpr std::array<detail::EnumName<Behavior>, 4> enum_names(Behavior) {
  return {{{Behavior::ConstantSpeed, "constant_speed"},
           {Behavior::ConstantAccel, "constant_accel"},
           {Behavior::Idm, "idm"},
           {Behavior::Replay, "replay"}}};
}

inline constexpr std::array<detail::EnumName<SeesEgo>, 2> enum_names(SeesEgo) {
  return {{{SeesEgo::InLane, "in_lane"}, {SeesEgo::Overlapping, "overlapping"}}};
}

template <class V, class S>
void visit_fields(V& v, S& s) requires std::same_as<std::remove_const_t<S>, TrafficSettings> {
  v("followers_react", s.followers_react);
  v("reaction_time", s.reaction_time);
  v("follow_decel", s.follow_decel);
  v("min_gap", s.min_gap);
  v("sees_ego", s.sees_ego);
  v("max_decel", s.max_decel);
  v("replay_prediction", s.replay_prediction);
}

inline constexpr std::array<detail::EnumName<Globalisation>, 2> enum_names(Globalisation) {
  return {{{Globalisation::Off, "off"}, {Globalisation::TrustRegion, "trust_region"}}};
}

inline constexpr std::array<detail::EnumName<GapChoice>, 2> enum_names(GapChoice) {
  return {{{GapChoice::Fixed, "fixed"}, {GapChoice::Best, "best"}}};
}

template <class V, class S>
void visit_fields(V& v, S& s) requires std::same_as<std::remove_const_t<S>, VehicleSize> {
  v("length", s.length);
  v("width", s.width);
}

template <class V, class S>
void visit_fields(V& v, S& s) requires std::same_as<std::remove_const_t<S>, Limits> {
  v("v", s.v);
  v("a", s.a);
  v("omega", s.omega);
  v("lateral_margin", s.lateral_margin);
}

template <class V, class S>
void visit_fields(V& v, S& s) requires std::same_as<std::remove_const_t<S>, IdmParameters> {
  v("desired_speed", s.desired_speed);
  v("time_headway", s.time_headway);
  v("min_gap", s.min_gap);
  v("max_accel", s.max_accel);
  v("comfortable_decel", s.comfortable_decel);
  v("exponent", s.exponent);
}

template <class V, class S>
void visit_fields(V& v, S& s) requires std::same_as<std::remove_const_t<S>, SafeDistance> {
  v("standstill", s.standstill);
  v("time_headway", s.time_headway);
}

template <class V, class S>
void visit_fields(V& v, S& s) requires std::same_as<std::remove_const_t<S>, SafetyMargins> {
  v("leader", s.leader);
  v("follower", s.follower);
  v("target", s.target);
}

template <class V, class S>
void visit_fields(V& v, S& s) requires std::same_as<std::remove_const_t<S>, ExpertSettings> {
  v("horizon", s.horizon);
  v("steps", s.steps);
  v("weight_accel", s.weight_accel);
  v("weight_jerk", s.weight_jerk);
  v("weight_lateral", s.weight_lateral);
  v("weight_terminal_x", s.weight_terminal_x);
  v("weight_yaw_rate", s.weight_yaw_rate);
  v("jerk_weighting", s.jerk_weighting);
  v("lane_rule", s.lane_rule);
  v("line_clearance", s.line_clearance);
  v("max_iterations", s.max_iterations);
  v("convergence_tolerance", s.convergence_tolerance);
  v("cycle_tolerance", s.cycle_tolerance);
  v("globalisation", s.globalisation);
  v("trust_radius", s.trust_radius);
  v("trust_shrink", s.trust_shrink);
  v("trust_rounds", s.trust_rounds);
  v("big_m", s.big_m);
  v("fix_terminal_lateral", s.fix_terminal_lateral);
  v("constrain_initial_node", s.constrain_initial_node);
  v("prediction_lead_steps", s.prediction_lead_steps);
  v("monotone_lateral", s.monotone_lateral);
  v("min_turn_radius", s.min_turn_radius);
  v("warm_start", s.warm_start);
  v("aim_behind_target", s.aim_behind_target);
  v("gap", s.gap);
  v("cut_in_decel", s.cut_in_decel);
  v("restore_distance_within", s.restore_distance_within);
}

template <class V, class S>
void visit_fields(V& v, S& s) requires std::same_as<std::remove_const_t<S>, LabelTolerances> {
  v("reach", s.reach);
  v("reversal", s.reversal);
  v("reference", s.reference);
  v("max_final_heading", s.max_final_heading);
}

template <class V, class S>
void visit_fields(V& v, S& s) requires std::same_as<std::remove_const_t<S>, SamplerSettings> {
  v("leader_speed", s.leader_speed);
  v("follower_speed", s.follower_speed);
  v("target_speed", s.target_speed);
  v("ego_speed_ratio", s.ego_speed_ratio);
  v("leader_headway", s.leader_headway);
  v("follower_offset", s.follower_offset);
  v("gap_length", s.gap_length);
  v("accel", s.accel);
  v("target_lane_cars", s.target_lane_cars);
  v("rear_headway", s.rear_headway);
}

template <class V, class S>
void visit_fields(V& v, S& s) requires std::same_as<std::remove_const_t<S>, MpcSettings> {
  v("circles", s.circles);
  v("margin", s.margin);
  v("time_limit_ms", s.time_limit_ms);
  v("max_iterations", s.max_iterations);
  v("step_iterations", s.step_iterations);
  v("tolerance", s.tolerance);
  v("terminal_gap", s.terminal_gap);
  v("gate_distance", s.gate_distance);
}

template <class V, class S>
void visit_fields(V& v, S& s) requires std::same_as<std::remove_const_t<S>, DwaSettings> {
  v("horizon", s.horizon);
  v("accel_samples", s.accel_samples);
  v("yaw_rate_samples", s.yaw_rate_samples);
  v("max_jerk", s.max_jerk);
  v("max_yaw_accel", s.max_yaw_accel);
  v("margin", s.margin);
  v("braking_decel", s.braking_decel);
  v("keep_safe_distances", s.keep_safe_distances);
  v("desired_speed", s.desired_speed);
  v("goal_preview", s.goal_preview);
  v("weight_lateral", s.weight_lateral);
  v("weight_heading", s.weight_heading);
  v("weight_clearance", s.weight_clearance);
  v("weight_speed", s.weight_speed);
}

template <class V, class S>
void visit_fields(V& v, S& s) requires std::same_as<std::remove_const_t<S>, LatticeSettings> {
  v("min_duration", s.min_duration);
  v("max_duration", s.max_duration);
  v("duration_samples", s.duration_samples);
  v("offset_spread", s.offset_spread);
  v("speed_step", s.speed_step);
  v("speed_samples", s.speed_samples);
  v("desired_speed", s.desired_speed);
  v("margin", s.margin);
  v("keep_safe_distances", s.keep_safe_distances);
  v("max_curvature", s.max_curvature);
  v("max_heading", s.max_heading);
  v("weight_jerk", s.weight_jerk);
  v("weight_duration", s.weight_duration);
  v("weight_offset", s.weight_offset);
  v("weight_speed", s.weight_speed);
  v("weight_lateral", s.weight_lateral);
  v("weight_longitudinal", s.weight_longitudinal);
}

template <class V, class S>
void visit_fields(V& v, S& s) requires std::same_as<std::remove_const_t<S>, StrategyQpSettings> {
  v("candidates", s.candidates);
  v("vote_pool", s.vote_pool);
  v("replan_candidates", s.replan_candidates);
  v("screen", s.screen);
  v("screen_keep", s.screen_keep);
  v("rough_screen", s.rough_screen);
  v("screen_tolerance", s.screen_tolerance);
  v("screen_cutoff", s.screen_cutoff);
  v("skip_dearer", s.skip_dearer);
  v("neighbour_nodes", s.neighbour_nodes);
  v("timed_warm_start", s.timed_warm_start);
  v("first_feasible", s.first_feasible);
  v("other_gaps", s.other_gaps);
}

template <class V, class S>
void visit_fields(V& v, S& s) requires std::same_as<std::remove_const_t<S>, Config> {
  v("preset", s.preset);
  v("lane_width", s.lane_width);
  v("vehicle", s.vehicle);
  v("limits", s.limits);
  v("idm", s.idm);
  v("traffic_max_speed", s.traffic_max_speed);
  v("traffic_integration", s.traffic_integration);
  v("traffic", s.traffic);
  v("safety", s.safety);
  v("expert", s.expert);
  v("labels", s.labels);
  v("sampler", s.sampler);
  v("closed_loop", s.closed_loop);
  v("mpc", s.mpc);
  v("dwa", s.dwa);
  v("lattice", s.lattice);
  v("strategy_qp", s.strategy_qp);
}

}  // namespace lanechange
