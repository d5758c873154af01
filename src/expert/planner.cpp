#include "lanechange/expert/planner.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>

#include "lanechange/ego.hpp"

namespace lanechange::expert {

std::string_view to_string(PlanStatus status) {
  switch (status) {
    case PlanStatus::Converged: return "converged";
    case PlanStatus::IterationLimit: return "iteration_limit";
    case PlanStatus::Cycling: return "cycling";
    case PlanStatus::Infeasible: return "infeasible";
    case PlanStatus::TimeLimit: return "time_limit";
    case PlanStatus::SolverError: return "solver_error";
  }
  return "?";
}

ExpertPlanner::ExpertPlanner(Config config, std::shared_ptr<const LaneChangeSolver> solver)
    : config_(std::move(config)), solver_(std::move(solver)) {
  config_.validate();
}

namespace {

using Clock = std::chrono::steady_clock;

double elapsed_ms(Clock::time_point since) {
  return std::chrono::duration<double, std::milli>(Clock::now() - since).count();
}

std::vector<EgoFootprint> footprint_of(const Iterate& path) {
  std::vector<EgoFootprint> out;
  out.reserve(path.states.size());
  for (const State& z : path.states) out.push_back({z[kX], z[kY], z[kV]});
  return out;
}

double largest_position_change(const Iterate& a, const Iterate& b) {
  double most = 0.0;
  for (std::size_t k = 0; k < a.states.size(); ++k) {
    most = std::max({most, std::abs(a.states[k][kX] - b.states[k][kX]),
                     std::abs(a.states[k][kY] - b.states[k][kY])});
  }
  return most;
}

PlanStatus status_of_failed_round(MiqpStatus s) {
  switch (s) {
    case MiqpStatus::Infeasible: return PlanStatus::Infeasible;
    case MiqpStatus::TimeLimit: return PlanStatus::TimeLimit;
    default: return PlanStatus::SolverError;
  }
}

std::vector<std::optional<LaneOccupancy>> occupancy_of(const LaneChangeQp& qp,
                                                       const std::vector<int>& modes) {
  std::vector<std::optional<LaneOccupancy>> out(modes.size());
  for (std::size_t k = 0; k < modes.size() && k < qp.node_modes.size(); ++k) {
    const auto& choices = qp.node_modes[k];
    if (modes[k] >= 0 && static_cast<std::size_t>(modes[k]) < choices.size()) {
      out[k] = choices[static_cast<std::size_t>(modes[k])].occupancy;
    }
  }
  return out;
}

}  // namespace

ExpertResult ExpertPlanner::plan(const Scenario& scenario, const PlanLimits& limits) const {
  const auto start = Clock::now();
  const Config config = effective_config(config_, scenario);
  const int steps = scenario.steps;
  const double dt = scenario.horizon / steps;
  const int predicted_steps = steps + config.expert.prediction_lead_steps;
  ExpertResult result;
  result.prediction = predict_traffic(scenario, config, predicted_steps, dt);
  Iterate point = warm_start(scenario, config, result.prediction);
  const bool reactive = scenario.behavior == Behavior::Idm;
  const auto workspace = solver_->make_workspace();
  std::vector<int> mode_hint;
  Iterate two_back;  // the solution of the round before the last
  for (int round = 1; round <= config.expert.max_iterations; ++round) {
    if (reactive) {
      const auto ego_path = footprint_of(point);
      result.prediction = predict_traffic(scenario, config, predicted_steps, dt, &ego_path);
    }
    const LaneChangeQp qp = build_lane_change_qp(scenario, config, point, result.prediction);
    MiqpSettings settings;
    settings.time_limit_s = std::max(0.001, limits.time_limit_s - elapsed_ms(start) / 1000.0);
    // The previous round's lane modes (the warm start's, first) are a good
    // first guess; the back-end proves or improves on them.
    if (result.modes.empty()) {
      mode_hint.assign(steps + 1, -1);
      for (int k = 0; k <= steps; ++k) {
        if (!qp.node_modes[k].empty()) mode_hint[k] = qp.best_mode(point, k);
      }
    } else {
      mode_hint = result.modes;
    }
    const LaneChangeSolution solution =
        solver_->solve(qp, settings, {workspace.get(), &mode_hint, &point.controls});
    RoundReport report{solution.status,  solution.objective,     kInfinity,
                       solution.nodes,   solution.qp_iterations, solution.incumbent_qps,
                       solution.solve_ms};
    if (solution.status != MiqpStatus::Optimal || !solution.has_solution()) {
      result.rounds.push_back(report);
      result.status = status_of_failed_round(solution.status);
      result.reason = "round " + std::to_string(round) + ": " +
                      std::string(lanechange::expert::to_string(solution.status)) +
                      (solution.message.empty() ? "" : " (" + solution.message + ")");
      result.total_ms = elapsed_ms(start);
      return result;
    }
    if (round > 1) report.max_change = largest_position_change(solution.path, result.path);
    const double repeat = round > 2 ? largest_position_change(solution.path, two_back) : kInfinity;
    const bool cycling = repeat <= config.expert.cycle_tolerance &&
                         report.max_change > config.expert.convergence_tolerance;
    result.rounds.push_back(report);
    two_back = std::move(result.path);
    result.path = solution.path;
    result.modes = solution.modes;
    result.occupancy = occupancy_of(qp, solution.modes);
    result.objective = solution.objective;
    point = solution.path;
    if (round > 1 && report.max_change <= config.expert.convergence_tolerance) {
      result.status = PlanStatus::Converged;
      result.total_ms = elapsed_ms(start);
      return result;
    }
    if (cycling) {
      // The next round starts where the last but one did, so it repeats it:
      // the rounds alternate between two paths and never converge.
      result.status = PlanStatus::Cycling;
      char reason[160];
      std::snprintf(reason, sizeof reason,
                    "round %d repeats round %d (to %.1e m) while consecutive rounds differ by "
                    "%.3f m: the rounds alternate between two paths",
                    round, round - 2, repeat, report.max_change);
      result.reason = reason;
      result.total_ms = elapsed_ms(start);
      return result;
    }
  }
  result.status = PlanStatus::IterationLimit;
  char reason[128];
  std::snprintf(reason, sizeof reason, "not converged after %d rounds (last change %.3f m)",
                config.expert.max_iterations, result.rounds.back().max_change);
  result.reason = reason;
  result.total_ms = elapsed_ms(start);
  return result;
}

Trajectory ExpertPlanner::to_trajectory(const ExpertResult& result,
                                        const Scenario& scenario) const {
  if (result.path.states.empty()) {
    Trajectory t = failed_trajectory("miqp", scenario, result.reason);
    t.compute_total_ms = t.compute_max_step_ms = result.total_ms;
    return t;
  }
  const Config config = effective_config(config_, scenario);
  const int steps = scenario.steps;
  Trajectory t;
  t.planner = "miqp";
  t.dt = scenario.horizon / steps;
  t.lane_width = scenario.lane_width;
  EgoState state = scenario.ego;
  double defect = 0.0;
  for (int k = 0; k <= steps; ++k) {
    t.t.push_back(k * t.dt);
    const Control& u = result.path.controls[std::min(k, steps - 1)];
    state.a = u[kA];
    t.ego.push_back(state);
    t.controls.push_back({u[kA], u[kOmega]});
    const State& z = result.path.states[k];
    defect = std::max({defect, std::abs(state.x - z[kX]), std::abs(state.y - z[kY])});
    if (k < steps) state = step_trapezoidal(state, {u[kA], u[kOmega]}, t.dt);
  }
  t.others.dt = t.dt;
  for (Car c : kAllCars) {
    const CarTrack& full = result.prediction.car(c);
    CarTrack& track = t.others.cars[static_cast<std::size_t>(c)];
    track.x.assign(full.x.begin(), full.x.begin() + steps + 1);
    track.v.assign(full.v.begin(), full.v.begin() + steps + 1);
    track.a.assign(full.a.begin(), full.a.begin() + steps + 1);
  }
  const auto collision = first_collision(t.ego, t.others, scenario);
  t.collision = collision.has_value();
  if (result.status != PlanStatus::Converged) {
    t.label = Label::Failure;
    t.reason = result.reason;
  } else {
    const Labelled l =
        label_trajectory(t.ys(), t.ego.back().theta, scenario.lane_width, config.labels);
    t.label = l.label;
    t.reason = l.reason;
    if (t.collision && t.label != Label::Failure) {
      t.label = Label::Failure;
      t.reason = "collision with the " + std::string(lanechange::to_string(collision->car)) +
                 " at t = " + std::to_string(collision->time) + " s";
    }
  }
  t.compute_total_ms = result.total_ms;
  t.compute_max_step_ms = result.total_ms;
  nlohmann::json rounds = nlohmann::json::array();
  for (const RoundReport& r : result.rounds) {
    rounds.push_back(
        {{"status", lanechange::expert::to_string(r.status)},
         {"objective", std::isfinite(r.objective) ? nlohmann::json(r.objective) : nlohmann::json()},
         {"max_change",
          std::isfinite(r.max_change) ? nlohmann::json(r.max_change) : nlohmann::json()},
         {"nodes", r.nodes},
         {"qp_iterations", r.qp_iterations},
         {"incumbent_qps", r.incumbent_qps},
         {"solve_ms", r.solve_ms}});
  }
  t.details = {{"objective", result.objective},      {"iterations", result.iterations()},
               {"status", to_string(result.status)}, {"solver", solver_->name()},
               {"linearization_defect", defect},     {"rounds", rounds}};
  return t;
}

}  // namespace lanechange::expert
