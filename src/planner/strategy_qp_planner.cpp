#include "planner/strategy_qp_planner.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>

#include "lanechange/error.hpp"

namespace lanechange::planner {

namespace {

using Clock = std::chrono::steady_clock;

double ms_since(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

}  // namespace

std::vector<int> modes_of_strategy(const learn::Strategy& strategy, int steps, LaneRule rule) {
  std::vector<int> modes(static_cast<std::size_t>(steps) + 1, -1);
  if (strategy.empty()) return modes;
  for (int k = 1; k <= steps; ++k) {
    const auto at = std::min(static_cast<std::size_t>(k - 1), strategy.size() - 1);
    const auto occupancy = static_cast<expert::LaneOccupancy>(strategy[at] - '0');
    modes[static_cast<std::size_t>(k)] = expert::lane_mode_index(rule, occupancy);
  }
  return modes;
}

StrategyQpPlanner::StrategyQpPlanner(Config config,
                                     std::shared_ptr<const learn::StrategyModel> model)
    : config_(closed_loop_expert(std::move(config))),
      model_(std::move(model)),
      fixed_(config_, std::make_shared<expert::FixedModeLaneChangeSolver>()),
      exact_(config_, std::make_shared<expert::FastLaneChangeSolver>()) {
  if (!model_) throw InputError("--model", "strategy-qp needs a lane-strategy model");
}

CandidateOutcome StrategyQpPlanner::solve_candidate(const Scenario& scene,
                                                    const std::vector<int>& modes,
                                                    const expert::PlanLimits& limits,
                                                    const expert::PlanHints& hints,
                                                    expert::ExpertResult& result) const {
  result = fixed_.plan(scene, limits, {hints.path, &modes});
  CandidateOutcome out;
  out.status = result.status;
  out.objective = result.objective;
  out.rescued = !result.rounds.empty() && std::isfinite(result.rounds.back().trust_radius);
  if (result.status == expert::PlanStatus::Converged) {
    out.collision = fixed_.to_trajectory(result, scene).collision;
  }
  return out;
}

StrategyPlan StrategyQpPlanner::plan(const Scenario& scene, const expert::PlanLimits& limits,
                                     const expert::PlanHints& hints) const {
  const auto start = Clock::now();
  StrategyPlan out;
  const LaneRule rule = effective_config(config_, scene).expert.lane_rule;
  std::vector<learn::Strategy> predicted = model_->predict(scene, config_.strategy_qp.candidates);
  out.predict_ms = ms_since(start);
  // The last plan's modes (closed loop) come first: they were the optimum a
  // step ago, and keep the manoeuvre steady.
  std::vector<std::vector<int>> tried;
  const auto nodes = static_cast<std::size_t>(scene.steps) + 1;
  if (hints.modes != nullptr && hints.modes->size() == nodes) {
    tried.push_back(*hints.modes);
    predicted.insert(predicted.begin(), learn::Strategy());
  }
  for (std::size_t i = tried.size(); i < predicted.size(); ++i) {
    tried.push_back(modes_of_strategy(predicted[i], scene.steps, rule));
  }
  expert::ExpertResult candidate;
  std::vector<int> rescued_hint;
  for (std::size_t i = 0; i < tried.size(); ++i) {
    // Two strategies may agree on this horizon: one solve is enough.
    if (std::find(tried.begin(), tried.begin() + static_cast<std::ptrdiff_t>(i), tried[i]) !=
        tried.begin() + static_cast<std::ptrdiff_t>(i)) {
      continue;
    }
    CandidateOutcome o = solve_candidate(scene, tried[i], limits, hints, candidate);
    o.strategy = predicted[i];
    out.candidates.push_back(o);
    // Only plans of the plain rounds are followed: one the trust region
    // rescued may have stopped in a box far from any fixed point (hundreds
    // of times the optimum's cost in the study); its modes still make the
    // best hint for the exact search.
    if (o.feasible() && o.rescued && rescued_hint.empty()) rescued_hint = tried[i];
    if (!o.feasible() || o.rescued) continue;
    if (out.chosen < 0 || o.objective < out.result.objective) {
      out.chosen = static_cast<int>(out.candidates.size()) - 1;
      out.result = std::move(candidate);
      if (config_.strategy_qp.first_feasible) break;
    }
  }
  if (out.chosen < 0) {
    // No candidate holds: the exact search, started from the likeliest modes.
    if (rescued_hint.empty() && !tried.empty()) rescued_hint = tried.front();
    out.result =
        exact_.plan(scene, limits, {hints.path, rescued_hint.empty() ? nullptr : &rescued_hint});
  }
  out.total_ms = ms_since(start);
  out.result.total_ms = out.total_ms;
  return out;
}

std::unique_ptr<PlannerSession> StrategyQpPlanner::start(const Scenario& /*scene*/) const {
  return std::make_unique<MiqpSession>(
      [this](const Scenario& scene, const expert::PlanLimits& limits,
             const expert::PlanHints& hints) { return plan(scene, limits, hints).result; },
      config_);
}

}  // namespace lanechange::planner
