#include <cmath>
#include <iostream>

#include "common/json_fields.hpp"
#include "lanechange/sim/simulator.hpp"
#include "run/json_numbers.hpp"

namespace lanechange::sim {

namespace {

using nlohmann::json;

// The steps where something other than the planner's own method acted.
json events(const Rollout& r) {
  json out = {{"took_over", json::array()},
              {"fallback", json::array()},
              {"failed", json::array()},
              {"clipped", json::array()}};
  const double dt = r.trajectory.dt;
  for (std::size_t k = 0; k < r.steps.size(); ++k) {
    const StepRecord& s = r.steps[k];
    const json at = {{"step", k}, {"t", static_cast<double>(k) * dt}, {"reason", s.reason}};
    if (s.status == planner::ActStatus::TookOver) out["took_over"].push_back(at);
    if (s.status == planner::ActStatus::Fallback && !s.lane_keeping) out["fallback"].push_back(at);
    if (s.status == planner::ActStatus::Failed) out["failed"].push_back(at);
    if (s.clipped) out["clipped"].push_back(k);
  }
  return out;
}

}  // namespace

json rollout_to_json(const Rollout& r) {
  json out = trajectory_to_json(r.trajectory);
  const RolloutMetrics& m = r.metrics;
  out["outcome"] = to_string(r.outcome);
  out["collision_at_fault"] = r.collision_at_fault;
  out["compute_ms"]["median_step"] = m.median_step_ms;
  out["compute_ms"]["p99_step"] = m.p99_step_ms;
  json per_step = json::array();
  for (const StepRecord& s : r.steps) per_step.push_back(s.compute_ms);
  out["compute_ms"]["steps"] = per_step;
  out["events"] = events(r);
  out["manoeuvre_over_at"] =
      run::number_or_null(r.manoeuvre_over_at >= 0 ? r.manoeuvre_over_at : NAN);
  out["metrics"] = {
      {"time_to_target_lane",
       run::number_or_null(m.time_to_target_lane >= 0 ? m.time_to_target_lane : NAN)},
      {"time_to_lane_line",
       run::number_or_null(m.time_to_lane_line >= 0 ? m.time_to_lane_line : NAN)},
      {"min_gap", run::number_or_null(m.min_gap)},
      {"min_ttc", run::number_or_null(m.min_ttc)},
      {"max_abs_accel", m.max_abs_accel},
      {"rms_jerk", m.rms_jerk},
      {"max_abs_omega", m.max_abs_omega},
      {"takeovers", m.takeovers},
      {"first_takeover_t", run::number_or_null(m.first_takeover_t >= 0 ? m.first_takeover_t : NAN)},
      {"fallbacks", m.fallbacks},
      {"clipped", m.clipped},
      {"overruns", m.overruns},
      {"failures", m.failures},
      {"forced_decel", m.forced_decel},
      {"unsafe_cut_in", m.unsafe_cut_in},
      {"max_car_decel", m.max_car_decel},
      {"cars_collide", m.cars_collide}};
  return out;
}

void save_rollout(const Rollout& rollout, const std::string& path) {
  const std::string text = rollout_to_json(rollout).dump() + "\n";
  if (path.empty() || path == "-") {
    std::cout << text;
    return;
  }
  lanechange::detail::write_file_atomically(path, text);
}

}  // namespace lanechange::sim
