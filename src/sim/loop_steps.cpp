#include "sim/loop_steps.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <exception>
#include <string>

#include "lanechange/checks.hpp"
#include "sim/metrics.hpp"

namespace lanechange::sim::detail {

namespace {

using planner::ActStatus;
using planner::Decision;
using Clock = std::chrono::steady_clock;

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

EgoControl ask_planner(planner::PlannerSession& session, const planner::Observation& o,
                       const Config& config, const planner::LaneKeeper& keeper,
                       StepRecord& record) {
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
  if (record.compute_ms > config.closed_loop.step_budget_ms && d.status != ActStatus::Failed) {
    record.overrun = true;
    // Under a deadline of work the decision stands: marked, not overruled.
    if (config.closed_loop.deadline == Deadline::WallClock) {
      record.status = ActStatus::Failed;
      record.reason = "over its budget of " + std::to_string(config.closed_loop.step_budget_ms) +
                      " ms; the fallback acted" +
                      (d.reason.empty() ? "" : " (the planner: " + d.reason + ")");
    }
  }
  if (record.status == ActStatus::Failed) return planner::fallback_control(keeper, o);
  return d.control;
}

EgoControl keep_lane(const planner::LaneKeeper& keeper, const planner::Observation& o,
                     bool target_lane) {
  return keeper.control(o.ego, target_lane ? o.scene->lane_width : 0.0,
                        planner::car_ahead(o, target_lane), planner::car_behind(o, target_lane));
}

bool SettleCheck::settled(const EgoState& ego) {
  if (over_) return true;
  const ClosedLoopSettings& c = config_.closed_loop;
  // The lane keeper's heading response still carries an ego that heads
  // back towards the ego lane about v |theta| / gain further: handed over
  // too early, that drift becomes a reversal the judge counts.
  peak_y_ = std::max(peak_y_, ego.y);
  const double drift = std::max(0.0, -ego.theta) * ego.v / c.keeper_heading_gain;
  const bool keeper_holds = ego.theta >= 0.0 || std::min(peak_y_, lane_width_) - (ego.y - drift) <=
                                                    config_.labels.reversal / 2;
  over_ = std::abs(ego.y - lane_width_) <= c.settled_offset &&
          std::abs(ego.theta) <= c.settled_heading && keeper_holds;
  return over_;
}

void finish_rollout(Rollout& out, const Scenario& scene, const Config& config) {
  Trajectory& t = out.trajectory;
  const auto hit = first_collision(t.ego, t.others, scene);
  t.collision = t.collision || hit.has_value();
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
}

}  // namespace lanechange::sim::detail
