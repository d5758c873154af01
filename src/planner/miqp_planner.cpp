// The exact expert in closed loop: re-plan from the current state every
// `replan_period` steps, warm-started from the last plan shifted by the
// steps since it was made; follow the last feasible plan when a re-plan
// fails, and the lane keeper when there is none.
#include "planner/miqp_planner.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <utility>

#include "lanechange/checks.hpp"
#include "lanechange/ego.hpp"

namespace lanechange::planner {

namespace {

using expert::ExpertResult;
using expert::Iterate;
using expert::PlanStatus;

// Of the step budget, the expert leaves this much for the rest of the step:
// the check that called it (mlp-miqp), and the node QP or round that is
// running when its time limit passes, which it finishes before it returns.
constexpr double kStepReserveMs = 3.0;

// What `limits` leave after the plan `spent`.
expert::PlanLimits limits_left(const expert::PlanLimits& limits, const ExpertResult& spent) {
  long iterations = 0;
  for (const expert::RoundReport& round : spent.rounds) iterations += round.qp_iterations;
  expert::PlanLimits left = limits;
  left.time_limit_s = std::max(0.0, limits.time_limit_s - spent.total_ms / 1000.0);
  if (limits.qp_iterations != std::numeric_limits<long>::max()) {
    left.qp_iterations = std::max(0L, limits.qp_iterations - iterations);
  }
  return left;
}

}  // namespace

Iterate shifted(const Iterate& path, int by, int steps, double dt) {
  Iterate out;
  shifted(path, by, steps, dt, out);
  return out;
}

void shifted(const Iterate& path, int by, int steps, double dt, Iterate& out) {
  out.states.clear();
  out.controls.clear();
  const int last_state = static_cast<int>(path.states.size()) - 1;
  const int last_control = static_cast<int>(path.controls.size()) - 1;
  for (int k = 0; k <= steps; ++k) {
    const int from = k + by;
    expert::State z = path.states[std::min(from, last_state)];
    const int beyond = std::max(0, from - last_state);
    z[expert::kX] += beyond * dt * z[expert::kV] * std::cos(z[expert::kTheta]);
    z[expert::kY] += beyond * dt * z[expert::kV] * std::sin(z[expert::kTheta]);
    out.states.push_back(z);
    if (k < steps) out.controls.push_back(path.controls[std::min(from, last_control)]);
  }
}

std::vector<int> shifted(const std::vector<int>& modes, int by, int steps) {
  std::vector<int> out;
  shifted(modes, by, steps, out);
  return out;
}

void shifted(const std::vector<int>& modes, int by, int steps, std::vector<int>& out) {
  out.assign(static_cast<std::size_t>(steps) + 1, -1);
  if (modes.empty()) return;
  const int last = static_cast<int>(modes.size()) - 1;
  for (int k = 1; k <= steps; ++k) out[k] = modes[std::min(k + by, last)];
}

Config closed_loop_expert(Config config) {
  config.expert.monotone_lateral =
      config.expert.monotone_lateral || config.closed_loop.monotone_lateral;
  return config;
}

Scenario scene_now(const Observation& o, const Config& config, double deadline_set_at) {
  Scenario scene;
  scene_now(o, config, scene, deadline_set_at);
  return scene;
}

void scene_now(const Observation& o, const Config& config, Scenario& scene,
               double deadline_set_at) {
  scene = *o.scene;
  scene.ego = o.ego;
  for (CarIndex c = 0; c < scene.car_count(); ++c) scene.cars[c].state = o.car(c);
  const double dt = o.scene->horizon / o.scene->steps;
  if (config.closed_loop.horizon_mode == HorizonMode::Shrinking) {
    const double left =
        std::max(config.closed_loop.min_horizon, o.scene->horizon - (o.t - deadline_set_at));
    scene.steps = std::max(2, static_cast<int>(std::lround(left / dt)));
    scene.horizon = scene.steps * dt;
  }
}

MiqpSession::MiqpSession(const expert::ExpertPlanner& expert, const Config& config)
    : MiqpSession(
          [&expert](const Scenario& scene, const expert::PlanLimits& limits,
                    const expert::PlanHints& hints,
                    expert::ExpertResult& result) { expert.plan(scene, limits, hints, result); },
          config, expert.solver().make_workspace()) {}

MiqpSession::MiqpSession(PlanFunction plan, const Config& config,
                         std::unique_ptr<expert::LaneChangeWorkspace> workspace)
    : plan_function_(std::move(plan)),
      config_(config),
      keeper_(config),
      workspace_(std::move(workspace)) {}

Decision MiqpSession::act(const Observation& o) {
  const bool due = !plan_ || o.step - plan_step_ >= config_.closed_loop.replan_period;
  std::string failure;
  if (due) failure = replan(o);
  if (plan_) {
    const int offset = o.step - plan_step_;
    const bool fresh = offset <= config_.closed_loop.stale_plan_steps;
    if (offset < static_cast<int>(plan_->controls.size()) && (failure.empty() || fresh)) {
      const expert::Control& u = plan_->controls[static_cast<std::size_t>(offset)];
      Decision d{{u[expert::kA], u[expert::kOmega]}, ActStatus::Planned, ""};
      if (!failure.empty()) d.reason = "re-plan failed (" + failure + "): following the last plan";
      return d;
    }
  }
  return fallback(o, failure.empty() ? "the last plan has run out" : failure);
}

std::string MiqpSession::replan(const Observation& o) {
  scene_now(o, config_, scene_, deadline_set_at_);
  const Scenario& scene = scene_;
  const double dt = scene.horizon / scene.steps;
  expert::PlanHints hints;
  const auto nodes = static_cast<std::size_t>(scene.steps) + 1;
  guess_.states.reserve(nodes);  // at the first re-plan: the later ones fill them
  guess_.controls.reserve(nodes);
  guess_modes_.reserve(nodes);
  if (plan_) {
    shifted(*plan_, o.step - plan_step_, scene.steps, dt, guess_);
    shifted(modes_, o.step - plan_step_, scene.steps, guess_modes_);
    hints = {&guess_, &guess_modes_, true};
    hints.last_gap = &plan_gap_;
  }
  hints.memory = &memory_;
  if (workspace_) {
    workspace_->advance(o.step - workspace_step_);
    workspace_step_ = o.step;
    hints.workspace = workspace_.get();
  }
  const ClosedLoopSettings& loop = config_.closed_loop;
  expert::PlanLimits limits{
      std::max(0.0, step_wall_limit_ms(loop, loop.step_budget_ms) - kStepReserveMs) / 1000.0};
  if (loop.deadline == Deadline::Work) limits.qp_iterations = loop.step_qp_iterations;
  plan_function_(scene, limits, hints, result_);
  double plan_ms = result_.total_ms;
  // A plan cut by its budget, with or without a path, leaves none for a retry.
  const bool no_plan = result_.status != PlanStatus::Converged &&
                       result_.status != PlanStatus::TimeLimit &&
                       result_.status != PlanStatus::WorkLimit;
  const bool shrunk = scene.horizon < o.scene->horizon - 0.5 * dt;
  const bool fresh_plan = plan_ && o.step - plan_step_ <= config_.closed_loop.stale_plan_steps;
  if (no_plan && !fresh_plan && (shrunk || hints.path != nullptr)) {
    // No lane change has met the deadline the first plan set for longer
    // than a plan stays fresh: the gap it aimed for has gone. Give the next
    // gap the whole horizon from now, as a driver who missed a gap waits for
    // the next; and plan it from a warm start per gap, not from the last
    // plan, which the ego has left. (A step that fails while the last plan
    // is fresh follows that plan, and the next step tries again.)
    if (shrunk) deadline_set_at_ = o.t;
    scene_now(o, config_, scene_, deadline_set_at_);
    plan_cold(scene_, limits_left(limits, result_), hints);
    plan_ms += result_.total_ms;
  }
  const ExpertResult& result = result_;
  last_plan_ms_ = plan_ms;
  last_status_ = result.status;
  // A plan cut by its budget still drives with the best it found: the
  // fallback is for steps with no safe plan at all.
  if (result.status != PlanStatus::Converged && !result.cut_with_incumbent()) {
    return std::string(expert::to_string(result.status)) + ": " + result.reason;
  }
  std::string collision = collision_of(result, scene_);
  if (!collision.empty()) return collision;
  plan_ = result.path;
  modes_ = result.modes;
  plan_gap_ = expert::frame_of(result.gap);
  plan_step_ = o.step;
  return "";
}

void MiqpSession::plan_cold(const Scenario& scene, const expert::PlanLimits& limits,
                            expert::PlanHints hints) {
  hints.path = nullptr;
  hints.modes = nullptr;
  hints.path_is_plan = false;
  hints.last_gap = nullptr;
  plan_function_(scene, limits, hints, result_);
}

std::string MiqpSession::collision_of(const ExpertResult& plan, const Scenario& scene) {
  expert::poses_along(plan.path, scene.ego, scene.steps, scene.horizon / scene.steps, poses_);
  // The lane rows bound the body's lateral extent, not its corners at a
  // heading: at a steep crossing at low speed a corner can reach a car.
  const auto contact = first_collision(poses_, plan.prediction, scene);
  if (!contact) return "";
  char why[160];
  std::snprintf(why, sizeof why, "the plan's path meets the %s at t = %.1f s",
                scene.cars[contact->car].id.c_str(), contact->time);
  return why;
}

Decision MiqpSession::fallback(const Observation& o, const std::string& why) {
  return {fallback_control(keeper_, o), ActStatus::Fallback, "no feasible plan: " + why};
}

std::unique_ptr<PlannerSession> MiqpPlanner::start(const Scenario& /*scene*/) const {
  return std::make_unique<MiqpSession>(expert_, config_);
}

}  // namespace lanechange::planner
