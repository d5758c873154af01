#include "planner/strategy_qp_planner.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <optional>

#include "lanechange/error.hpp"

namespace lanechange::planner {

namespace {

using Clock = std::chrono::steady_clock;

double ms_since(Clock::time_point start) {
  return std::chrono::duration<double, std::milli>(Clock::now() - start).count();
}

// What a plan's budget leaves once `spent` of its interior-point iterations
// are used and the time since `since` has passed: the screens, every
// candidate's rounds and the exact search share one step budget, so that a
// step under closed_loop.deadline = work stops where its budget says.
expert::PlanLimits left_of(const expert::PlanLimits& limits, Clock::time_point since, long spent) {
  expert::PlanLimits left;
  left.time_limit_s = std::max(0.0, limits.time_limit_s - ms_since(since) / 1000.0);
  left.qp_iterations = limits.qp_iterations == std::numeric_limits<long>::max()
                           ? limits.qp_iterations
                           : std::max(0L, limits.qp_iterations - spent);
  return left;
}

long qp_iterations_of(const expert::ExpertResult& result) {
  long sum = 0;
  for (const expert::RoundReport& r : result.rounds) sum += r.qp_iterations;
  return sum;
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

std::vector<learn::Strategy> neighbour_strategies(const learn::Strategy& strategy, int reach) {
  constexpr auto kNone = learn::Strategy::npos;
  const auto leave = strategy.find_first_not_of('0');
  const auto enter = strategy.find('2');
  const bool one_change = leave != kNone && enter != kNone && leave < enter &&
                          strategy.find_first_not_of('1', leave) == enter &&
                          strategy.find_first_not_of('2', enter) == kNone;
  if (!one_change) return {};
  const auto length = static_cast<int>(strategy.size());
  std::vector<std::pair<int, learn::Strategy>> found;
  for (int shift_leave = -reach; shift_leave <= reach; ++shift_leave) {
    for (int shift_enter = -reach; shift_enter <= reach; ++shift_enter) {
      const int a = static_cast<int>(leave) + shift_leave;
      const int b = static_cast<int>(enter) + shift_enter;
      if ((shift_leave == 0 && shift_enter == 0) || a < 0 || a >= b || b >= length) continue;
      const auto count = [](int n) { return static_cast<std::size_t>(n); };
      found.emplace_back(std::abs(shift_leave) + std::abs(shift_enter),
                         learn::Strategy(count(a), '0') + learn::Strategy(count(b - a), '1') +
                             learn::Strategy(count(length - b), '2'));
    }
  }
  std::stable_sort(found.begin(), found.end(),
                   [](const auto& x, const auto& y) { return x.first < y.first; });
  std::vector<learn::Strategy> out;
  out.reserve(found.size());
  for (auto& f : found) out.push_back(std::move(f.second));
  return out;
}

StrategyQpPlanner::StrategyQpPlanner(Config config,
                                     std::shared_ptr<const learn::StrategyModel> model)
    : config_(closed_loop_expert(std::move(config))),
      model_(std::move(model)),
      fixed_(config_, std::make_shared<expert::FixedModeLaneChangeSolver>()),
      screen_solver_(expert::FixedModeSettings{config_.strategy_qp.rough_screen,
                                               config_.strategy_qp.screen_tolerance}),
      neighbour_screen_solver_(expert::FixedModeSettings{
          config_.strategy_qp.rough_screen, std::min(config_.strategy_qp.screen_tolerance,
                                                     expert::FixedModeSettings{}.rough_tolerance)}),
      exact_(config_, std::make_shared<expert::FastLaneChangeSolver>()) {
  if (!model_) throw InputError("--model", "strategy-qp needs a lane-strategy model");
}

CandidateOutcome StrategyQpPlanner::solve_candidate(const Scenario& scene,
                                                    const std::vector<int>& modes,
                                                    const expert::Gap& gap,
                                                    const expert::PlanLimits& limits,
                                                    const expert::PlanHints& hints,
                                                    expert::ExpertResult& result) const {
  const auto start = Clock::now();
  expert::PlanHints through{hints.path, &modes, hints.path_is_plan, hints.workspace};
  through.gap = &gap;
  through.memory = hints.memory;
  result = fixed_.plan(scene, limits, through);
  CandidateOutcome out;
  out.rounds = result.iterations();
  out.status = result.status;
  out.objective = result.objective;
  out.rescued = !result.rounds.empty() && std::isfinite(result.rounds.back().trust_radius);
  if (result.status == expert::PlanStatus::Converged) {
    out.collision = fixed_.to_trajectory(result, scene).collision;
  }
  out.rounds_ms = ms_since(start);
  return out;
}

// The expert's warm start changes lanes in the middle of the horizon; with
// the modes fixed, rounds that start from a change at the candidate's own
// switch nodes linearize near where they end.
class StrategyQpPlanner::StartTimer {
 public:
  StartTimer(const Config& config, const Scenario& scene, const expert::PlanHints& hints)
      : scene_(scene) {
    const auto nodes = static_cast<std::size_t>(scene.steps) + 1;
    const bool path_fits = hints.path != nullptr && hints.path->states.size() == nodes;
    if (config.strategy_qp.timed_warm_start && !path_fits)
      config_ = effective_config(config, scene);
  }
  void time(Candidate& c) {
    if (!config_) return;
    if (!prediction_) {
      const double dt = scene_.horizon / scene_.steps;
      prediction_ = predict_traffic(scene_, *config_,
                                    scene_.steps + config_->expert.prediction_lead_steps, dt);
    }
    c.start = expert::warm_start_for_modes(scene_, *config_, *prediction_, c.modes, c.gap);
  }

 private:
  const Scenario& scene_;
  std::optional<Config> config_;  // none: the candidates start from the plan's path
  std::optional<TrafficPrediction> prediction_;
};

bool StrategyQpPlanner::can_hold(const Scenario& scene, const expert::PlanHints& hints,
                                 Candidate& c, Linearization& shared) const {
  expert::PlanHints at{c.start.states.empty() ? hints.path : &c.start};
  at.gap = &c.gap;
  if (c.start.states.empty()) {
    if (!shared)
      shared = std::make_shared<const expert::LinearizedRound>(fixed_.first_round(scene, at));
    c.first = shared;
  } else {
    c.first = std::make_shared<const expert::LinearizedRound>(fixed_.first_round(scene, at));
  }
  return expert::lane_modes_can_hold(c.first->qp, c.modes);
}

std::vector<StrategyQpPlanner::Candidate> StrategyQpPlanner::candidates_of(
    const Scenario& scene, const expert::PlanHints& hints, const expert::Gap& gap,
    bool first_gap) const {
  const LaneRule rule = effective_config(config_, scene).expert.lane_rule;
  std::vector<Candidate> list;
  StartTimer starts(config_, scene, hints);
  // The last plan's modes (closed loop) come first: they were the optimum a
  // step ago, and keep the manoeuvre steady.
  const auto nodes = static_cast<std::size_t>(scene.steps) + 1;
  if (hints.modes != nullptr && hints.modes->size() == nodes) {
    list.push_back({{}, *hints.modes, {}, {}, gap});
    starts.time(list.back());
  }
  // With the last plan's modes to go on, the votes are alternatives to them
  // and the plain top k serve; without (open loop, a rollout's first step),
  // every slot a refused vote takes is a step closer to the exact search.
  const int wanted = list.empty() && first_gap ? config_.strategy_qp.candidates
                                               : config_.strategy_qp.replan_candidates;
  const int pool = list.empty() ? std::max(wanted, config_.strategy_qp.vote_pool) : wanted;
  std::vector<Candidate> votes;
  for (learn::Strategy& s : model_->predict(scene, expert::frame_of(gap), pool)) {
    std::vector<int> modes = modes_of_strategy(s, scene.steps, rule);
    votes.push_back({std::move(s), std::move(modes), {}, {}, gap});
  }
  Linearization shared;
  int taken = 0;
  for (Candidate& c : votes) {
    if (taken >= wanted) break;
    // Two strategies may agree on this horizon: one solve is enough.
    const bool seen = std::any_of(list.begin(), list.end(),
                                  [&c](const Candidate& other) { return other.modes == c.modes; });
    if (!seen) starts.time(c);
    if (!seen && pool > wanted && !can_hold(scene, hints, c, shared)) continue;
    ++taken;
    if (!seen) list.push_back(std::move(c));
  }
  return list;
}

bool StrategyQpPlanner::take_candidate(CandidateOutcome& o, const std::vector<int>& modes,
                                       expert::ExpertResult& plan, StrategyPlan& out,
                                       std::vector<int>& rescued_hint) const {
  o.rounds_run = true;
  out.qp_iterations += qp_iterations_of(plan);
  // Only plans of the plain rounds are followed: one the trust region
  // rescued may have stopped in a box far from any fixed point (hundreds of
  // times the optimum's cost in the study); its modes still make the best
  // hint for the exact search.
  if (o.feasible() && o.rescued && rescued_hint.empty()) rescued_hint = modes;
  if (!o.feasible() || o.rescued) return false;
  if (out.chosen >= 0 && o.objective >= out.result.objective) return false;
  out.result = std::move(plan);
  return true;
}

void StrategyQpPlanner::follow_in_order(const Scenario& scene, const expert::PlanLimits& limits,
                                        const expert::PlanHints& hints,
                                        const std::vector<Candidate>& list, bool stop_at_first,
                                        StrategyPlan& out, std::vector<int>& rescued_hint) const {
  const auto start = Clock::now();
  expert::ExpertResult plan;
  for (const Candidate& c : list) {
    CandidateOutcome o =
        solve_candidate(scene, c.modes, c.gap, left_of(limits, start, out.qp_iterations),
                        {c.first_point(hints), hints.modes, c.starts_from_plan(hints)}, plan);
    o.strategy = c.strategy;
    const bool taken = take_candidate(o, c.modes, plan, out, rescued_hint);
    out.candidates.push_back(std::move(o));
    if (!taken) continue;
    out.chosen = static_cast<int>(out.candidates.size()) - 1;
    if (stop_at_first) return;
  }
}

void StrategyQpPlanner::follow_screened(const Scenario& scene, const expert::PlanLimits& limits,
                                        const expert::PlanHints& hints,
                                        const std::vector<Candidate>& list, StrategyPlan& out,
                                        std::vector<int>& rescued_hint) const {
  const auto start = Clock::now();
  expert::LinearizedRound first;
  const auto workspace = screen_solver_.make_workspace();
  std::vector<expert::LaneChangeSolution> screens;
  std::vector<std::size_t> order;
  double best_screen = expert::kInfinity;
  expert::ExpertResult plan;
  int held = 0;
  // out.candidates may hold an earlier gap's: list[j] and screens[j] are
  // out.candidates[first_index + j].
  const std::size_t first_index = out.candidates.size();
  // Closed loop: the last plan's modes, from its own path, mostly converge in
  // one round. Their rounds run first and the votes are screened against that
  // plan's cost, which saves the last modes' screen QP.
  const bool last_plan_first = !list.empty() && list.front().strategy.empty() &&
                               list.front().starts_from_plan(hints) && hints.path != nullptr;
  if (last_plan_first) {
    CandidateOutcome o = solve_candidate(scene, list.front().modes, list.front().gap,
                                         left_of(limits, start, out.qp_iterations),
                                         {hints.path, nullptr, true, hints.workspace}, plan);
    if (take_candidate(o, list.front().modes, plan, out, rescued_hint)) {
      out.chosen = static_cast<int>(first_index);
      held = 1;
      best_screen = out.result.objective;
    }
    out.candidates.push_back(std::move(o));
    screens.emplace_back();
  }
  for (const Candidate& c : list) {
    if (last_plan_first && &c == &list.front()) continue;
    // A candidate proven dearer than the best so far ranks after it: the
    // bound that proves it is enough, and the rest of its QP is saved.
    double cutoff = expert::kInfinity;
    if (config_.strategy_qp.screen_cutoff) cutoff = best_screen;
    screens.push_back(screen_one(scene, hints, c, cutoff, left_of(limits, start, out.qp_iterations),
                                 first, {screen_solver_, workspace.get()}));
    out.qp_iterations += screens.back().qp_iterations;
    CandidateOutcome o;
    o.strategy = c.strategy;
    const expert::MiqpStatus status = screens.back().status;
    if (status == expert::MiqpStatus::Optimal || status == expert::MiqpStatus::Cutoff) {
      o.screen_objective = screens.back().objective;
      order.push_back(out.candidates.size());
      if (status == expert::MiqpStatus::Optimal) {
        best_screen = std::min(best_screen, o.screen_objective);
      }
    } else {
      // The rounds would stop at this very QP.
      o.status = expert::PlanStatus::Infeasible;
    }
    out.candidates.push_back(std::move(o));
  }
  out.screen_ms += ms_since(start);
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return out.candidates[a].screen_objective < out.candidates[b].screen_objective;
  });
  for (std::size_t i : order) {
    if (config_.strategy_qp.skip_dearer && out.chosen >= 0 &&
        out.candidates[i].screen_objective >= out.result.objective) {
      continue;
    }
    const std::size_t j = i - first_index;
    // The rounds go on from the screened solution: it is the first round's.
    // A candidate cut off in the screen has none, and starts where its
    // screen did.
    const bool screened = screens[j].has_solution();
    // The rounds solve in the screen's workspace: it carries the state
    // bounds the screens found binding, and a fresh one would solve the
    // first round twice to find them again. (A session's own workspace stays
    // with the last plan's modes, for the next step's warm start.)
    const expert::PlanHints from_screen{screened ? &screens[j].path : list[j].first_point(hints),
                                        nullptr, screened || list[j].starts_from_plan(hints),
                                        workspace.get()};
    CandidateOutcome& o = out.candidates[i];
    const std::string strategy = o.strategy;
    const double screen_objective = o.screen_objective;
    o = solve_candidate(scene, list[j].modes, list[j].gap,
                        left_of(limits, start, out.qp_iterations), from_screen, plan);
    o.strategy = strategy;
    o.screen_objective = screen_objective;
    if (take_candidate(o, list[j].modes, plan, out, rescued_hint)) out.chosen = static_cast<int>(i);
    held += o.feasible() && !o.rescued ? 1 : 0;
    if (held >= config_.strategy_qp.screen_keep) return;
  }
}

expert::LaneChangeSolution StrategyQpPlanner::screen_one(const Scenario& scene,
                                                         const expert::PlanHints& hints,
                                                         const Candidate& c, double cutoff,
                                                         const expert::PlanLimits& left,
                                                         expert::LinearizedRound& first,
                                                         const Screener& screener) const {
  expert::MiqpSettings settings;
  settings.objective_cutoff = cutoff;
  settings.time_limit_s = left.time_limit_s;
  settings.qp_iteration_limit = left.qp_iterations;
  if (c.first) {
    return screener.solver.solve(c.first->qp, settings,
                                 {screener.workspace, &c.modes, &c.first->point.controls});
  }
  // Candidates with a start of their own each have their linearization;
  // the others share the plan's.
  if (first.point.states.empty() || !c.start.states.empty()) {
    expert::PlanHints at{c.first_point(hints)};
    at.gap = &c.gap;
    first = fixed_.first_round(scene, at);
  }
  return screener.solver.solve(first.qp, settings,
                               {screener.workspace, &c.modes, &first.point.controls});
}

void StrategyQpPlanner::search_neighbours(const Scenario& scene, const expert::PlanLimits& limits,
                                          StrategyPlan& out) const {
  const int reach = config_.strategy_qp.neighbour_nodes;
  if (reach <= 0 || out.chosen < 0) return;
  const learn::Strategy around = out.candidates[static_cast<std::size_t>(out.chosen)].strategy;
  const LaneRule rule = effective_config(config_, scene).expert.lane_rule;
  std::vector<std::vector<int>> tried;
  for (const CandidateOutcome& o : out.candidates) {
    tried.push_back(modes_of_strategy(o.strategy, scene.steps, rule));
  }
  std::vector<Candidate> list;
  for (learn::Strategy& s : neighbour_strategies(around, reach)) {
    std::vector<int> modes = modes_of_strategy(s, scene.steps, rule);
    if (std::find(tried.begin(), tried.end(), modes) != tried.end()) continue;
    tried.push_back(modes);
    list.push_back({std::move(s), std::move(modes), {}, {}, out.result.gap});
  }
  // Every neighbour is screened at the plan's own linearization: a fixed
  // point of its rounds, and close to the neighbours' own.
  const expert::Iterate at_plan = out.result.path;
  const expert::PlanHints from_plan{&at_plan, nullptr, true};
  const auto workspace = neighbour_screen_solver_.make_workspace();
  expert::LinearizedRound first;
  expert::ExpertResult plan;
  std::vector<int> unused_hint;
  const auto start = Clock::now();
  for (const Candidate& c : list) {
    const expert::LaneChangeSolution screen = screen_one(
        scene, from_plan, c, out.result.objective, left_of(limits, start, out.qp_iterations), first,
        {neighbour_screen_solver_, workspace.get()});
    out.qp_iterations += screen.qp_iterations;
    CandidateOutcome o;
    const bool has_point =
        screen.status == expert::MiqpStatus::Optimal || screen.status == expert::MiqpStatus::Cutoff;
    if (!has_point) o.status = expert::PlanStatus::Infeasible;
    if (screen.status == expert::MiqpStatus::Optimal && screen.objective < out.result.objective) {
      o = solve_candidate(scene, c.modes, c.gap, left_of(limits, start, out.qp_iterations),
                          {&screen.path, nullptr, true}, plan);
      if (take_candidate(o, c.modes, plan, out, unused_hint)) {
        out.chosen = static_cast<int>(out.candidates.size());
      }
    }
    if (has_point) o.screen_objective = screen.objective;
    o.strategy = c.strategy;
    out.candidates.push_back(std::move(o));
  }
}

std::vector<expert::Gap> StrategyQpPlanner::gaps_to_try(const Scenario& scene,
                                                        const expert::PlanHints& hints) const {
  if (effective_config(config_, scene).expert.gap == GapChoice::Fixed) {
    return {expert::paper_gap(scene)};
  }
  std::vector<expert::Gap> lane = expert::target_lane_gaps(scene, GapChoice::Best);
  const auto framed_by = [&lane](const expert::GapFrame& frame) {
    return std::find_if(lane.begin(), lane.end(),
                        [&frame](const expert::Gap& g) { return expert::frame_of(g) == frame; });
  };
  const expert::GapSlots slots = expert::gap_slots(scene);
  auto first = lane.end();
  if (hints.last_gap != nullptr) first = framed_by(*hints.last_gap);
  const expert::GapFrame paper = learn::paper_frame(scene);
  if (first == lane.end() && (paper.behind || paper.ahead)) first = framed_by(paper);
  const auto& beside = slots.gaps[expert::kGapSlotBeside];
  if (first == lane.end() && beside) first = framed_by(expert::frame_of(*beside));
  if (first == lane.end()) return {};
  std::vector<expert::Gap> out{*first};
  // The others within the slots, the soonest open first (then the nearest slot).
  const double cap = config_.traffic_max_speed.value_or(expert::kInfinity);
  std::vector<std::pair<std::pair<double, int>, expert::Gap>> others;
  for (int slot = 0; slot < expert::kGapSlots; ++slot) {
    const auto& g = slots.gaps[static_cast<std::size_t>(slot)];
    if (!g || expert::frame_of(*g) == expert::frame_of(out.front())) continue;
    // A slot's gap is one of `lane`'s (gap_slots picks them from it).
    others.push_back({{learn::gap_open_time(scene, expert::frame_of(*g), cap),
                       std::abs(slot - expert::kGapSlotBeside)},
                      *g});
  }
  std::stable_sort(others.begin(), others.end(),
                   [](const auto& a, const auto& b) { return a.first < b.first; });
  const auto wanted = static_cast<std::size_t>(config_.strategy_qp.other_gaps);
  for (std::size_t i = 0; i < others.size() && i < wanted; ++i) out.push_back(others[i].second);
  return out;
}

void StrategyQpPlanner::follow_gap(const Scenario& scene, const expert::PlanLimits& limits,
                                   const expert::PlanHints& hints, const expert::Gap& gap,
                                   bool first_gap, StrategyPlan& out,
                                   std::vector<int>& rescued_hint) const {
  const auto start = Clock::now();
  const std::vector<Candidate> list = candidates_of(scene, hints, gap, first_gap);
  out.predict_ms += ms_since(start);
  if (config_.strategy_qp.screen) {
    follow_screened(scene, limits, hints, list, out, rescued_hint);
  } else {
    follow_in_order(scene, limits, hints, list, config_.strategy_qp.first_feasible, out,
                    rescued_hint);
  }
  if (rescued_hint.empty() && !list.empty()) rescued_hint = list.front().modes;
}

StrategyPlan StrategyQpPlanner::plan(const Scenario& scene, const expert::PlanLimits& limits,
                                     const expert::PlanHints& hints) const {
  const auto start = Clock::now();
  StrategyPlan out;
  const std::vector<expert::Gap> gaps = gaps_to_try(scene, hints);
  out.predict_ms = ms_since(start);
  std::vector<int> rescued_hint;
  // Each gap and stage takes the time the ones before left (its iterations
  // it reads off out.qp_iterations). The last plan's path and modes belong
  // to the first gap; the others start from their own warm starts.
  for (std::size_t i = 0; i < gaps.size() && out.chosen < 0; ++i) {
    const expert::PlanHints from = i == 0 ? hints : expert::PlanHints{};
    follow_gap(scene, left_of(limits, start, 0), from, gaps[i], i == 0, out, rescued_hint);
  }
  if (out.chosen >= 0 && config_.strategy_qp.screen) {
    search_neighbours(scene, left_of(limits, start, 0), out);
  }
  if (out.chosen < 0) {
    // No candidate holds: the exact search, started from the likeliest modes
    // (only what the candidates left of the limit: a step budget is one budget).
    expert::PlanHints exact_hints{hints.path, rescued_hint.empty() ? nullptr : &rescued_hint,
                                  hints.path_is_plan};
    exact_hints.memory = hints.memory;
    out.result = exact_.plan(scene, left_of(limits, start, out.qp_iterations), exact_hints);
    out.qp_iterations += qp_iterations_of(out.result);
  }
  out.total_ms = ms_since(start);
  out.result.total_ms = out.total_ms;
  return out;
}

CandidateOutcome StrategyQpPlanner::assess_strategy(const Scenario& scene,
                                                    const learn::Strategy& strategy) const {
  const LaneRule rule = effective_config(config_, scene).expert.lane_rule;
  const std::vector<expert::Gap> gaps = gaps_to_try(scene, {});
  std::vector<Candidate> one{{strategy,
                              modes_of_strategy(strategy, scene.steps, rule),
                              {},
                              {},
                              gaps.empty() ? expert::paper_gap(scene) : gaps.front()}};
  StartTimer(config_, scene, {}).time(one.front());
  expert::ExpertResult plan;
  CandidateOutcome o = solve_candidate(scene, one.front().modes, one.front().gap, {},
                                       {one.front().first_point({}), nullptr}, plan);
  o.strategy = strategy;
  o.rounds_run = true;
  return o;
}

std::vector<CandidateOutcome> StrategyQpPlanner::assess(const Scenario& scene,
                                                        const expert::PlanLimits& limits,
                                                        const expert::PlanHints& hints) const {
  StrategyPlan all;
  std::vector<int> unused;
  const std::vector<expert::Gap> gaps = gaps_to_try(scene, hints);
  if (gaps.empty()) return {};
  follow_in_order(scene, limits, hints, candidates_of(scene, hints, gaps.front()), false, all,
                  unused);
  return all.candidates;
}

std::unique_ptr<PlannerSession> StrategyQpPlanner::start(const Scenario& /*scene*/) const {
  return std::make_unique<MiqpSession>(
      [this](const Scenario& scene, const expert::PlanLimits& limits,
             const expert::PlanHints& hints,
             expert::ExpertResult& result) { result = plan(scene, limits, hints).result; },
      config_, fixed_.solver().make_workspace());
}

}  // namespace lanechange::planner
