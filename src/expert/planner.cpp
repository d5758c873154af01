#include "lanechange/expert/planner.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <optional>

#include "lanechange/ego.hpp"

namespace lanechange::expert {

std::string_view to_string(PlanStatus status) {
  switch (status) {
    case PlanStatus::Converged: return "converged";
    case PlanStatus::IterationLimit: return "iteration_limit";
    case PlanStatus::Cycling: return "cycling";
    case PlanStatus::Infeasible: return "infeasible";
    case PlanStatus::TimeLimit: return "time_limit";
    case PlanStatus::WorkLimit: return "work_limit";
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

void footprint_of(const Iterate& path, std::vector<EgoFootprint>& out) {
  out.clear();
  for (const State& z : path.states) out.push_back({z[kX], z[kY], z[kV]});
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
    case MiqpStatus::WorkLimit: return PlanStatus::WorkLimit;
    default: return PlanStatus::SolverError;
  }
}

void occupancy_of(const LaneChangeQp& qp, const std::vector<int>& modes,
                  std::vector<std::optional<LaneOccupancy>>& out) {
  out.assign(modes.size(), std::nullopt);
  for (std::size_t k = 0; k < modes.size() && k < qp.node_modes.size(); ++k) {
    const auto& choices = qp.node_modes[k];
    if (modes[k] >= 0 && static_cast<std::size_t>(modes[k]) < choices.size()) {
      out[k] = choices[static_cast<std::size_t>(modes[k])].occupancy;
    }
  }
}

// What every round of one plan shares.
struct RoundContext {
  const Scenario& scenario;
  const Config& config;
  const LaneChangeSolver& solver;
  LaneChangeWorkspace* workspace;
  Clock::time_point start;
  double time_limit_s;
  long qp_iteration_limit;
  long* qp_iterations_spent;  ///< by the plan's rounds so far
  int predicted_steps;
  double dt;
  const std::vector<int>* first_modes;  ///< lane modes to try first in round 1 (or none)
  const Gap* only_gap;                  ///< the one gap to plan through (or none)
  bool first_point_is_warm_start;       ///< round 1 then warm-starts each gap on its own
  PlanMemory& memory;                   ///< each gap's problem and prediction, built in place
};

// Keeps the round's solution within `radius` of the linearization point in x
// and y at every node: the trust region. Where the point lies farther than
// that outside y's own bounds (a rollout may overshoot them by its defect),
// the box shrinks to the nearest bound rather than become empty.
void restrict_to_box(LaneChangeQp& qp, const Iterate& point, double radius) {
  for (int k = 1; k <= qp.steps; ++k) {
    for (int c : {kX, kY}) {
      const double lo = qp.state_lower[k][c];
      const double hi = qp.state_upper[k][c];
      qp.state_lower[k][c] = std::min(std::max(lo, point.states[k][c] - radius), hi);
      qp.state_upper[k][c] = std::max(std::min(hi, point.states[k][c] + radius), lo);
    }
  }
}

// The cars as a round linearized about `point` sees them, into `prediction`:
// again only where they react to the ego.
void predict_along(const Scenario& scenario, const Config& config, int predicted_steps, double dt,
                   const Iterate& point, PlanMemory& memory, TrafficPrediction& prediction) {
  if (traffic_reacts(scenario, config)) {
    footprint_of(point, memory.ego_path);
    predict_traffic(scenario, config, predicted_steps, dt, &memory.ego_path, memory.traffic,
                    prediction);
  }
}

bool hint_path_fits(const Scenario& scenario, const PlanHints& hints) {
  const auto nodes = static_cast<std::size_t>(scenario.steps) + 1;
  return hints.path != nullptr && hints.path->states.size() == nodes &&
         hints.path->controls.size() == nodes - 1;
}

// The first linearization point, into memory.point: the hint's path where it
// fits, else the configured warm start.
void first_point(const Scenario& scenario, const Config& config, const PlanHints& hints,
                 const TrafficPrediction& prediction, PlanMemory& memory) {
  if (hint_path_fits(scenario, hints)) {
    memory.point = *hints.path;
    return;
  }
  paper_gap(scenario, memory.paper_gap);
  warm_start(scenario, config, prediction, memory.paper_gap, memory.point);
}

int predicted_steps_of(const Scenario& scenario, const Config& config) {
  return scenario.steps + config.expert.prediction_lead_steps;
}

// True when the path ends between the gap's framing cars as predicted.
bool ends_in(const Gap& gap, const Iterate& path, const TrafficPrediction& p) {
  const auto last = static_cast<std::size_t>(path.states.size()) - 1;
  const double x = path.states.back()[kX];
  const auto behind = gap.car_behind();
  const auto ahead = gap.car_ahead();
  return (!behind || p.car(*behind).x[std::min(last, p.car(*behind).x.size() - 1)] < x) &&
         (!ahead || x < p.car(*ahead).x[std::min(last, p.car(*ahead).x.size() - 1)]);
}

// The allowed gaps, the likeliest first so that its optimum cuts the others
// off early: the last round's, else the one the linearization point ends in.
const std::vector<Gap>& gaps_in_order(const RoundContext& c, const ExpertResult& result,
                                      const Iterate& point) {
  std::vector<Gap>& gaps = c.memory.gaps;
  if (c.only_gap != nullptr) {
    gaps.resize(1);
    gaps[0] = *c.only_gap;
    return gaps;
  }
  target_lane_gaps(c.scenario, c.config.expert.gap, gaps, &c.memory.spare_gaps);
  const bool have_last = !result.path.states.empty();
  const auto first = std::find_if(gaps.begin(), gaps.end(), [&](const Gap& g) {
    return have_last ? g == result.gap : ends_in(g, point, result.prediction);
  });
  if (first != gaps.end()) std::rotate(gaps.begin(), first, first + 1);
  return gaps;
}

// The modes to try first: the previous round's (the warm start's, first),
// else those the point meets best in this gap's problem.
void mode_hint_for(const RoundContext& c, const ExpertResult& result, const LaneChangeQp& qp,
                   const Iterate& point, std::vector<int>& hint) {
  hint = result.modes;
  if (hint.empty() && c.first_modes != nullptr) hint = *c.first_modes;
  if (hint.empty()) {
    hint.assign(qp.steps + 1, -1);
    for (int k = 0; k <= qp.steps; ++k) {
      if (!qp.node_modes[k].empty()) hint[k] = qp.best_mode(point, k);
    }
  }
}

// Adds a gap's solve to the round's counts.
void add_work(LaneChangeSolution& total, const LaneChangeSolution& part) {
  total.nodes += part.nodes;
  total.qp_iterations += part.qp_iterations;
  total.incumbent_qps += part.incumbent_qps;
  total.solve_ms += part.solve_ms;
}

// The gap's MIQP linearized about `point`, the cars re-predicted along it when
// they react to the ego, solved within `radius` of it when finite, cut off at
// `cutoff`, into `out`. Its problem and the cars as it saw them stay in the
// context's memory until the next gap's.
void solve_gap(const RoundContext& c, const Gap& gap, const Iterate& point, double radius,
               double cutoff, const ExpertResult& result, LaneChangeSolution& out) {
  PlanMemory& memory = c.memory;
  memory.gap_cars.assign(memory.round_start);
  predict_along(c.scenario, c.config, c.predicted_steps, c.dt, point, memory, memory.gap_cars);
  LaneChangeQp& qp = memory.problem;
  build_lane_change_qp(c.scenario, c.config, point, memory.gap_cars, gap, qp);
  if (std::isfinite(radius)) restrict_to_box(qp, point, radius);
  mode_hint_for(c, result, qp, point, memory.mode_hint);
  MiqpSettings settings;
  settings.time_limit_s = c.time_limit_s - elapsed_ms(c.start) / 1000.0;
  settings.qp_iteration_limit = c.qp_iteration_limit - *c.qp_iterations_spent;
  settings.objective_cutoff = cutoff;
  c.solver.solve_into(qp, settings, {c.workspace, &memory.mode_hint, &point.controls}, out);
  *c.qp_iterations_spent += out.qp_iterations;
}

// Below `objective` by more than the gap tolerances: what another gap must beat.
double cutoff_below(double objective) {
  const MiqpSettings tolerances;
  return objective -
         std::max(tolerances.absolute_gap, tolerances.relative_gap * std::abs(objective));
}

// One round: the MIQP of each allowed gap solved, each cut off by the best so
// far, so the least of their optima is the round's, exactly. Each gap is
// linearized about `point`, or, with `warm_start_per_gap` (a first round
// from no plan), about a warm start aimed into it: a path aimed elsewhere
// may be too slow or too fast to linearize a change into this gap. A gap whose
// solve stops at a limit or fails ends the round with that status. Updates the
// prediction the result reports.
// The round's answer lives in the context's memory (PlanMemory::round) until
// the next round's.
const RoundSolution& solve_round(const RoundContext& c, const Iterate& point, double radius,
                                 ExpertResult& result, bool warm_start_per_gap = false) {
  RoundSolution& best = c.memory.round;
  best.solution.clear();
  best.occupancy.clear();
  best.solution.status = MiqpStatus::Infeasible;
  if (c.time_limit_s - elapsed_ms(c.start) / 1000.0 <= 0.0) {
    // A round begun past the limit would overrun it by a whole MIQP.
    best.solution.status = MiqpStatus::TimeLimit;
    best.solution.message = "no time left for the round";
    return best;
  }
  if (*c.qp_iterations_spent >= c.qp_iteration_limit) {
    best.solution.status = MiqpStatus::WorkLimit;
    char message[96];
    std::snprintf(message, sizeof message, "the plan's %ld interior-point iterations are spent",
                  c.qp_iteration_limit);
    best.solution.message = message;
    return best;
  }
  c.memory.round_start.assign(result.prediction);
  LaneChangeSolution work;
  const std::vector<Gap>& gaps = gaps_in_order(c, result, point);
  // The least bound over the gaps, for a round that a budget cuts.
  double bound = kInfinity;
  LaneChangeSolution& s = c.memory.gap_solution;
  for (const Gap& gap : gaps) {
    if (warm_start_per_gap) {
      warm_start(c.scenario, c.config, c.memory.round_start, gap, c.memory.gap_point);
    }
    const double cutoff =
        best.solution.has_solution() ? cutoff_below(best.solution.objective) : kInfinity;
    solve_gap(c, gap, warm_start_per_gap ? c.memory.gap_point : point, radius, cutoff, result, s);
    add_work(work, s);
    if (warm_start_per_gap && s.status == MiqpStatus::Infeasible &&
        paced_warm_start(c.scenario, c.config, c.memory.round_start, gap, c.memory.gap_point)) {
      solve_gap(c, gap, c.memory.gap_point, radius, cutoff, result, s);
      add_work(work, s);
    }
    const bool better = s.status == MiqpStatus::Optimal && s.has_solution() &&
                        (!best.solution.has_solution() || s.objective < best.solution.objective);
    const bool failed = s.status != MiqpStatus::Infeasible && s.status != MiqpStatus::Cutoff &&
                        s.status != MiqpStatus::Optimal;
    if (s.status != MiqpStatus::Infeasible) bound = std::min(bound, s.best_bound);
    if (failed && &gap != &gaps.back()) bound = -kInfinity;  // gaps left unsolved
    if (better || failed) {
      std::swap(best.solution, s);
      occupancy_of(c.memory.problem, best.solution.modes, best.occupancy);
      best.gap = gap;
      std::swap(result.prediction, c.memory.gap_cars);
      if (failed) break;
    } else if (!best.solution.has_solution()) {
      // A round that finds nothing reports what its first gap saw.
      if (gap == gaps.front()) std::swap(result.prediction, c.memory.gap_cars);
      if (gaps.size() == 1) best.solution.message = s.message;
    }
  }
  if (!best.solution.has_solution() && best.solution.status == MiqpStatus::Infeasible &&
      gaps.size() > 1) {
    best.solution.message = "no gap of the target lane is feasible";
  }
  // A round solved to the end is optimal within the gap tolerances.
  const bool solved_to_the_end = best.solution.status == MiqpStatus::Optimal;
  best.solution.best_bound = solved_to_the_end ? best.solution.objective : bound;
  best.solution.nodes = work.nodes;
  best.solution.qp_iterations = work.qp_iterations;
  best.solution.incumbent_qps = work.incumbent_qps;
  best.solution.solve_ms = work.solve_ms;
  return best;
}

RoundReport report_of(const LaneChangeSolution& s) {
  return {s.status, s.objective, kInfinity, s.nodes, s.qp_iterations, s.incumbent_qps, s.solve_ms};
}

bool solved(const LaneChangeSolution& s) {
  return s.status == MiqpStatus::Optimal && s.has_solution();
}

void adopt(ExpertResult& result, const RoundSolution& round) {
  result.gap = round.gap;
  result.path = round.solution.path;
  result.modes = round.solution.modes;
  result.occupancy = round.occupancy;
  result.objective = round.solution.objective;
  result.best_bound = round.solution.best_bound;
}

// A round that fails ends the plan. One stopped by the plan's budget with
// an incumbent leaves that as the plan's path (anytime): feasible for the
// round's MIQP, if not proven optimal nor converged.
void fail_round(ExpertResult& result, const RoundSolution& round) {
  const LaneChangeSolution& solution = round.solution;
  const bool budget =
      solution.status == MiqpStatus::TimeLimit || solution.status == MiqpStatus::WorkLimit;
  if (budget && solution.has_solution()) adopt(result, round);
  result.status = status_of_failed_round(solution.status);
  char head[64];
  std::snprintf(head, sizeof head, "round %d: ", result.iterations());
  result.reason = head;
  result.reason += lanechange::expert::to_string(solution.status);
  if (!solution.message.empty()) {
    result.reason += " (";
    result.reason += solution.message;
    result.reason += ')';
  }
}

// The paper's successive linearization. Returns with a final status, or with
// Cycling or IterationLimit and `previous` holding the linearization point of
// the last round (the trust region starts from there). With `point_is_plan`
// (PlanHints::path_is_plan) the first round may converge on `point`.
// The rounds start from the context's memory.point; with Cycling or
// IterationLimit, memory.previous holds the last round's point.
void plain_rounds(const RoundContext& c, ExpertResult& result, bool point_is_plan) {
  const ExpertSettings& e = c.config.expert;
  Iterate& point = c.memory.point;
  Iterate& two_back = c.memory.two_back;  // the solution of the round before the last
  for (int round = 1; round <= e.max_iterations; ++round) {
    const RoundSolution& round_solution =
        solve_round(c, point, kInfinity, result, round == 1 && c.first_point_is_warm_start);
    const LaneChangeSolution& solution = round_solution.solution;
    RoundReport report = report_of(solution);
    if (!solved(solution)) {
      result.rounds.push_back(report);
      fail_round(result, round_solution);
      return;
    }
    // A round converges when its solution lies within the tolerance of the
    // path it was linearized about: the round before's, or a given plan.
    if (round > 1) report.max_change = largest_position_change(solution.path, result.path);
    if (round == 1 && point_is_plan)
      report.max_change = largest_position_change(solution.path, point);
    const double repeat = round > 2 ? largest_position_change(solution.path, two_back) : kInfinity;
    const bool cycling = repeat <= e.cycle_tolerance && report.max_change > e.convergence_tolerance;
    result.rounds.push_back(report);
    std::swap(two_back, result.path);
    adopt(result, round_solution);
    point = solution.path;
    if (report.max_change <= e.convergence_tolerance) {
      result.status = PlanStatus::Converged;
      return;
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
      std::swap(c.memory.previous, two_back);
      return;
    }
  }
  result.status = PlanStatus::IterationLimit;
  char reason[128];
  std::snprintf(reason, sizeof reason, "not converged after %d rounds (last change %.3f m)",
                e.max_iterations, result.rounds.back().max_change);
  result.reason = reason;
  std::swap(c.memory.previous, two_back);
}

// True when the step from `point` to `next` turns back on the step that led
// from `previous` to `point` (negative inner product of the x and y moves):
// the linearization about `point` contradicts the one before, so neither is to
// be trusted that far.
bool reverses(const Iterate& next, const Iterate& point, const Iterate& previous) {
  if (previous.states.empty()) return false;
  double inner = 0.0;
  for (std::size_t k = 0; k < point.states.size(); ++k) {
    for (int c : {kX, kY}) {
      inner +=
          (next.states[k][c] - point.states[k][c]) * (point.states[k][c] - previous.states[k][c]);
    }
  }
  return inner < 0.0;
}

// The states the controls of `path` reach through the nonlinear discrete
// model. A linearization about them is exact there, so a box around them
// always holds a path with their dynamics, however small the box; a box around
// a round's own solution would not (it is off its own linearization by up to
// the defect, decimetres in the rounds that fail).
void rollout(const Scenario& scenario, const Iterate& path, double dt, Iterate& out) {
  out.controls = path.controls;
  out.states.clear();
  EgoState z = scenario.ego;
  for (std::size_t k = 0; k < path.states.size(); ++k) {
    out.states.emplace_back(z.x, z.y, z.v, z.theta);
    if (k < path.controls.size()) {
      z = step_trapezoidal(z, {path.controls[k][kA], path.controls[k][kOmega]}, dt);
    }
  }
}

// Rounds within a box around the rollout of the last solution, where the plain
// rounds failed. A round converges by the plain test: its solution is within
// the tolerance of the path it was linearized about. With the box slack, that
// is a fixed point of the plain rounds restricted to the box; once the box is
// smaller than the tolerance the test holds by construction, and the plan is
// a path within the tolerance of a trajectory of the nonlinear model, the best
// within the box about it (docs/expert.md counts both kinds). A step that
// reverses the last one, or fails to contract, shrinks the box; an empty box
// grows it again.
void trust_region_rounds(const RoundContext& c, ExpertResult& result) {
  const ExpertSettings& e = c.config.expert;
  const int plain = result.iterations();
  Iterate& previous = c.memory.previous;
  Iterate& point = c.memory.point;
  rollout(c.scenario, result.path, c.dt, point);
  double radius = e.trust_radius;
  double last_change = result.rounds.back().max_change;
  for (int extra = 1; extra <= e.trust_rounds; ++extra) {
    const RoundSolution& round_solution = solve_round(c, point, radius, result);
    const LaneChangeSolution& solution = round_solution.solution;
    RoundReport report = report_of(solution);
    report.trust_radius = radius;
    if (!solved(solution)) {
      result.rounds.push_back(report);
      if (solution.status == MiqpStatus::Infeasible) {
        radius /= e.trust_shrink;
        continue;
      }
      fail_round(result, round_solution);
      return;
    }
    report.max_change = largest_position_change(solution.path, point);
    result.rounds.push_back(report);
    adopt(result, round_solution);
    if (report.max_change <= e.convergence_tolerance) {
      result.status = PlanStatus::Converged;
      result.reason.clear();
      return;
    }
    // A step inside the box that is no shorter than the last one does not
    // contract (rounds that drift, as under IDM, where the follower answers
    // each new path): a smaller box makes it.
    const bool stalls = report.max_change < radius && report.max_change >= last_change;
    if (stalls || reverses(solution.path, point, previous)) radius *= e.trust_shrink;
    last_change = report.max_change;
    std::swap(previous, point);
    rollout(c.scenario, solution.path, c.dt, point);
  }
  result.status = PlanStatus::IterationLimit;
  char reason[160];
  std::snprintf(reason, sizeof reason,
                "not converged after %d rounds and %d in a trust region (last change %.3f m, "
                "radius %.3f m)",
                plain, e.trust_rounds, result.rounds.back().max_change, radius);
  result.reason = reason;
}

// Recorded traffic may start the ego closer than Eq. 1 allows. The plan then
// fails where no node can restore the distance in time, and the reason says
// so rather than blaming the lane sequence.
std::string start_inside_safe_distance(const Scenario& s, const ExpertSettings& e) {
  const double half_width = footprint_half_width(s, e);
  const double boundary = 0.5 * s.lane_width;
  const bool in_ego_lane = s.ego.y - half_width < boundary;
  const bool in_target_lane = s.ego.y + half_width > boundary;
  const auto describe = [](const char* car, double gap, double needed) {
    char text[128];
    std::snprintf(text, sizeof text,
                  "the ego starts inside the %s's safe distance (%.1f m, %.1f m needed)", car, gap,
                  needed);
    return std::string(text);
  };
  const Lane lane_of_ego[] = {Lane::Ego, Lane::Target};
  const bool in_lane[] = {in_ego_lane, in_target_lane};
  for (int l = 0; l < 2; ++l) {
    if (!in_lane[l]) continue;
    for (CarIndex c = 0; c < s.car_count(); ++c) {
      if (s.cars[c].lane != lane_of_ego[l]) continue;
      const CarState& car = s.car(c);
      const double ahead_by = car.x - s.ego.x;
      if (ahead_by >= 0) {
        const SafeDistance d =
            s.centre_safe_distance(c, l == 0 ? s.safe_distance.leader : s.safe_distance.target);
        const double needs = d.standstill + d.time_headway * s.ego.v;
        if (ahead_by < needs) return describe(s.cars[c].id.c_str(), ahead_by, needs);
      } else {
        const SafeDistance d = s.centre_safe_distance(c, s.safe_distance.follower);
        const double needs = d.standstill + d.time_headway * car.v;
        if (-ahead_by < needs) return describe(s.cars[c].id.c_str(), -ahead_by, needs);
      }
    }
  }
  return "";
}

// Room for a plan of `scenario` in the lists that its rounds trade with one
// another (points, solutions, the result's path), made before the first
// round: a later plan then allocates nothing whatever its rounds do.
void reserve_for_plan(const Scenario& scenario, const Config& config, PlanMemory& memory,
                      ExpertResult& result) {
  const auto nodes = static_cast<std::size_t>(scenario.steps) + 1;
  for (Iterate* path : {&memory.point, &memory.gap_point, &memory.two_back, &memory.previous,
                        &memory.gap_solution.path, &memory.round.solution.path, &result.path}) {
    path->states.reserve(nodes);
    path->controls.reserve(nodes);
  }
  for (std::vector<int>* modes : {&memory.mode_hint, &memory.gap_solution.modes,
                                  &memory.round.solution.modes, &result.modes}) {
    modes->reserve(nodes);
  }
  result.occupancy.reserve(nodes);
  memory.round.occupancy.reserve(nodes);
  for (Gap* gap : {&memory.round.gap, &result.gap}) {
    gap->behind.reserve(scenario.car_count());
    gap->ahead.reserve(scenario.car_count());
  }
  result.rounds.reserve(static_cast<std::size_t>(config.expert.max_iterations) +
                        static_cast<std::size_t>(config.expert.trust_rounds) + 1);
  constexpr std::size_t kReasonLength = 256;  // the longest reason with its numbers
  result.reason.reserve(kReasonLength);
  memory.gap_solution.message.reserve(kReasonLength);
  memory.round.solution.message.reserve(kReasonLength);
}

}  // namespace

void ExpertResult::clear() {
  status = PlanStatus::SolverError;
  reason.clear();
  path.states.clear();
  path.controls.clear();
  modes.clear();
  occupancy.clear();
  gap.behind.clear();
  gap.ahead.clear();
  objective = kInfinity;
  best_bound = -kInfinity;
  rounds.clear();
  total_ms = 0.0;
}

TrafficPrediction prediction_along(const Scenario& scenario, const Config& config,
                                   int predicted_steps, double dt, const Iterate& point) {
  if (!traffic_reacts(scenario, config)) {
    return predict_traffic(scenario, config, predicted_steps, dt);
  }
  std::vector<EgoFootprint> ego_path;
  footprint_of(point, ego_path);
  return predict_traffic(scenario, config, predicted_steps, dt, &ego_path);
}

ExpertResult ExpertPlanner::plan(const Scenario& scenario, const PlanLimits& limits,
                                 const PlanHints& hints) const {
  ExpertResult result;
  plan(scenario, limits, hints, result);
  return result;
}

void ExpertPlanner::plan(const Scenario& scenario, const PlanLimits& limits, const PlanHints& hints,
                         ExpertResult& result) const {
  const auto start = Clock::now();
  const Config config = effective_config(config_, scenario);
  const double dt = scenario.horizon / scenario.steps;
  const auto owned = hints.workspace == nullptr ? solver_->make_workspace() : nullptr;
  LaneChangeWorkspace* workspace = hints.workspace == nullptr ? owned.get() : hints.workspace;
  const auto nodes = static_cast<std::size_t>(scenario.steps) + 1;
  const bool modes_fit = hints.modes != nullptr && hints.modes->size() == nodes;
  long qp_iterations_spent = 0;
  std::unique_ptr<PlanMemory> own_memory;
  if (hints.memory == nullptr) own_memory = std::make_unique<PlanMemory>();
  const RoundContext context{scenario,
                             config,
                             *solver_,
                             workspace,
                             start,
                             limits.time_limit_s,
                             limits.qp_iterations,
                             &qp_iterations_spent,
                             predicted_steps_of(scenario, config),
                             dt,
                             modes_fit ? hints.modes : nullptr,
                             hints.gap,
                             !hint_path_fits(scenario, hints),
                             hints.memory != nullptr ? *hints.memory : *own_memory};
  result.clear();
  reserve_for_plan(scenario, config, context.memory, result);
  predict_traffic(scenario, config, context.predicted_steps, dt, nullptr, context.memory.traffic,
                  result.prediction);
  context.memory.previous.states.clear();
  first_point(scenario, config, hints, result.prediction, context.memory);
  plain_rounds(context, result, hints.path_is_plan && hint_path_fits(scenario, hints));
  const bool failed_to_converge =
      result.status == PlanStatus::Cycling || result.status == PlanStatus::IterationLimit;
  if (failed_to_converge && config.expert.globalisation == Globalisation::TrustRegion) {
    trust_region_rounds(context, result);
  }
  if (result.status == PlanStatus::Infeasible) {
    const std::string why = start_inside_safe_distance(scenario, config.expert);
    if (!why.empty()) result.reason += "; " + why;
  }
  result.total_ms = elapsed_ms(start);
}

LinearizedRound ExpertPlanner::first_round(const Scenario& scenario, const PlanHints& hints) const {
  const Config config = effective_config(config_, scenario);
  const double dt = scenario.horizon / scenario.steps;
  const int predicted_steps = predicted_steps_of(scenario, config);
  TrafficPrediction prediction = predict_traffic(scenario, config, predicted_steps, dt);
  const Gap gap = hints.gap != nullptr ? *hints.gap : paper_gap(scenario);
  LinearizedRound out;
  out.point =
      hint_path_fits(scenario, hints) ? *hints.path : warm_start(scenario, config, prediction, gap);
  if (traffic_reacts(scenario, config)) {
    prediction = prediction_along(scenario, config, predicted_steps, dt, out.point);
  }
  out.qp = build_lane_change_qp(scenario, config, out.point, prediction, gap);
  return out;
}

void poses_along(const Iterate& path, const EgoState& start, int steps, double dt,
                 std::vector<EgoState>& out) {
  out.clear();
  EgoState pose = start;
  for (int k = 0; k <= steps; ++k) {
    const Control& u = path.controls[std::min(k, steps - 1)];
    pose.a = u[kA];
    out.push_back(pose);
    if (k < steps) pose = step_trapezoidal(pose, {u[kA], u[kOmega]}, dt);
  }
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
  t.target_side = scenario.target_side;
  poses_along(result.path, scenario.ego, steps, t.dt, t.ego);
  double defect = 0.0;
  for (int k = 0; k <= steps; ++k) {
    t.t.push_back(k * t.dt);
    const Control& u = result.path.controls[std::min(k, steps - 1)];
    t.controls.push_back({u[kA], u[kOmega]});
    const State& z = result.path.states[k];
    const EgoState& pose = t.ego[static_cast<std::size_t>(k)];
    defect = std::max({defect, std::abs(pose.x - z[kX]), std::abs(pose.y - z[kY])});
  }
  t.others.dt = t.dt;
  t.others.cars.resize(result.prediction.car_count());
  t.cars = tracked_cars(scenario);
  for (CarIndex c = 0; c < result.prediction.car_count(); ++c) {
    const CarTrack& full = result.prediction.car(c);
    CarTrack& track = t.others.cars[c];
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
      t.reason = "collision with the " + scenario.cars[collision->car].id +
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
    if (std::isfinite(r.trust_radius)) rounds.back()["trust_radius"] = r.trust_radius;
  }
  const auto car_name = [&scenario](std::optional<CarIndex> c) {
    return c ? nlohmann::json(scenario.cars[*c].id) : nlohmann::json();
  };
  t.details = {{"objective", result.objective},
               {"best_bound", std::isfinite(result.best_bound) ? nlohmann::json(result.best_bound)
                                                               : nlohmann::json()},
               {"iterations", result.iterations()},
               {"status", to_string(result.status)},
               {"solver", solver_->name()},
               {"linearization_defect", defect},
               {"gap",
                {{"behind", car_name(result.gap.car_behind())},
                 {"ahead", car_name(result.gap.car_ahead())}}},
               {"rounds", rounds}};
  return t;
}

}  // namespace lanechange::expert
