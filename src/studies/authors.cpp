#include "lanechange/studies/authors.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <nlohmann/json.hpp>
#include <sstream>
#include <thread>

#include "lanechange/error.hpp"
#include "lanechange/run/markdown.hpp"
#include "lanechange/run/quantile.hpp"
#include "run/json_numbers.hpp"

namespace lanechange::studies {

// The comparison reads our expert's problem, solvers and plans throughout.
using namespace expert;

using nlohmann::json;

// ---------------------------------------------------------------- loading

namespace {

std::string join(const std::string& path, const std::string& key) {
  return path.empty() ? key : path + "." + key;
}

const json& member(const json& object, const std::string& path, const std::string& key) {
  if (!object.is_object()) throw InputError(path, "must be an object");
  const auto it = object.find(key);
  if (it == object.end()) throw InputError(join(path, key), "is missing");
  return *it;
}

double number(const json& j, const std::string& path) {
  if (!j.is_number()) throw InputError(path, "must be a number");
  const double value = j.get<double>();
  if (!std::isfinite(value)) throw InputError(path, "must be finite");
  return value;
}

std::vector<double> numbers(const json& j, const std::string& path, std::size_t size) {
  if (!j.is_array()) throw InputError(path, "must be an array of numbers");
  if (j.size() != size) {
    throw InputError(
        path, "must have " + std::to_string(size) + " entries, not " + std::to_string(j.size()));
  }
  std::vector<double> out;
  out.reserve(size);
  for (std::size_t i = 0; i < size; ++i) {
    out.push_back(number(j[i], path + "[" + std::to_string(i) + "]"));
  }
  return out;
}

void reject_unknown(const json& object, const std::string& path,
                    std::initializer_list<const char*> known) {
  for (const auto& item : object.items()) {
    if (std::none_of(known.begin(), known.end(), [&](const char* k) { return item.key() == k; })) {
      throw InputError(join(path, item.key()), "unknown field");
    }
  }
}

Iterate read_solution(const json& j, int steps) {
  const std::string path = "solution";
  if (!j.is_object()) throw InputError(path, "must be an object");
  reject_unknown(j, path, {"x", "y", "v", "theta", "a", "omega"});
  const auto nodes = static_cast<std::size_t>(steps) + 1;
  const auto x = numbers(member(j, path, "x"), path + ".x", nodes);
  const auto y = numbers(member(j, path, "y"), path + ".y", nodes);
  const auto v = numbers(member(j, path, "v"), path + ".v", nodes);
  const auto theta = numbers(member(j, path, "theta"), path + ".theta", nodes);
  const auto a = numbers(member(j, path, "a"), path + ".a", nodes - 1);
  const auto omega = numbers(member(j, path, "omega"), path + ".omega", nodes - 1);
  Iterate out;
  for (std::size_t k = 0; k < nodes; ++k) out.states.emplace_back(x[k], y[k], v[k], theta[k]);
  for (std::size_t k = 0; k + 1 < nodes; ++k) out.controls.emplace_back(a[k], omega[k]);
  return out;
}

TrafficPrediction read_prediction(const json& j, int steps, double dt) {
  const std::string path = "predicted_others";
  if (!j.is_object()) throw InputError(path, "must be an object");
  reject_unknown(j, path, {"leader", "follower", "target"});
  TrafficPrediction out;
  out.dt = dt;
  out.cars.resize(std::size(kRoles));
  for (Role car : kRoles) {
    const std::string name(to_string(car));
    std::string car_path = path;
    car_path += ".";
    car_path += name;
    const json& c = member(j, path, name);
    if (!c.is_object()) throw InputError(car_path, "must be an object");
    reject_unknown(c, car_path, {"x", "v"});
    CarTrack& track = out.cars[static_cast<std::size_t>(car)];
    track.x = numbers(member(c, car_path, "x"), car_path + ".x", steps + 1);
    track.v = numbers(member(c, car_path, "v"), car_path + ".v", steps + 1);
  }
  return out;
}

}  // namespace

AuthorsRecord authors_record_from_json(const json& in, const Config& config) {
  if (!in.is_object()) throw InputError("", "a record must be a JSON object");
  reject_unknown(
      in, "",
      {"id", "scenario", "status", "objective", "objective_terms", "solution", "predicted_others"});
  AuthorsRecord r;
  const json& id = member(in, "", "id");
  if (!id.is_string()) throw InputError("id", "must be a string");
  r.id = id.get<std::string>();
  try {
    r.scenario = scenario_from_json(member(in, "", "scenario"), config);
  } catch (const InputError& e) {
    // Name the field from the record's root.
    const std::string& inner = e.field();
    std::string problem = e.what();
    if (!inner.empty() && problem.rfind(inner + ": ", 0) == 0) problem.erase(0, inner.size() + 2);
    throw InputError(join("scenario", inner), problem);
  }
  const json& status = member(in, "", "status");
  if (!status.is_string()) throw InputError("status", "must be a string");
  const std::string s = status.get<std::string>();
  if (s == "solved") {
    r.solved = true;
  } else if (s != "no_solution") {
    throw InputError("status", "unknown value \"" + s + "\" (expected solved or no_solution)");
  }
  if (!r.solved) {
    for (const char* key : {"objective", "objective_terms", "solution", "predicted_others"}) {
      if (in.contains(key)) throw InputError(key, "must be absent when status is no_solution");
    }
    return r;
  }
  const int steps = r.scenario.steps;
  r.objective = number(member(in, "", "objective"), "objective");
  const auto terms = numbers(member(in, "", "objective_terms"), "objective_terms", 4);
  std::copy(terms.begin(), terms.end(), r.objective_terms.begin());
  r.solution = read_solution(member(in, "", "solution"), steps);
  r.predicted_others =
      read_prediction(member(in, "", "predicted_others"), steps, r.scenario.horizon / steps);
  return r;
}

std::vector<AuthorsRecord> load_authors_records(const std::string& path, const Config& config) {
  std::ifstream file(path);
  if (!file) throw InputError(path, "cannot open the records file");
  std::vector<AuthorsRecord> out;
  std::string text;
  int line = 0;
  while (std::getline(file, text)) {
    ++line;
    if (text.find_first_not_of(" \t\r\n") == std::string::npos) continue;
    const std::string where = path + ", line " + std::to_string(line);
    json j;
    try {
      j = json::parse(text);
    } catch (const json::exception& e) {
      throw InputError(where,
                       "line " + std::to_string(line) + " is not valid JSON (" + e.what() + ")");
    }
    try {
      AuthorsRecord r = authors_record_from_json(j, config);
      r.line = line;
      out.push_back(std::move(r));
    } catch (const InputError& e) {
      throw InputError(where, "line " + std::to_string(line) + ": " + e.what());
    }
  }
  return out;
}

// ---------------------------------------------------------------- evaluation

AuthorsTerms authors_objective_terms(const Iterate& path, const Config& config, double lane_width,
                                     double target_end_x) {
  const ExpertSettings& e = config.expert;
  const int n = static_cast<int>(path.controls.size());
  const double dt = config.dt();
  AuthorsTerms t{0.0, 0.0, 0.0, 0.0};
  for (int k = 0; k < n; ++k) t[kTermAccel] += path.controls[k][kA] * path.controls[k][kA];
  t[kTermAccel] *= e.weight_accel * dt;
  for (int k = 0; k < n; ++k) {
    const double dy = path.states[k][kY] - lane_width;
    t[kTermLateral] += dy * dy;
  }
  t[kTermLateral] *= e.weight_lateral * dt;
  const double dx = path.states[n][kX] - target_end_x;
  t[kTermTerminalX] = e.weight_terminal_x * dx * dx;
  for (int k = 0; k + 1 < n; ++k) {
    const double d = path.controls[k + 1][kA] - path.controls[k][kA];
    t[kTermJerk] += d * d;
  }
  t[kTermJerk] *=
      e.jerk_weighting == JerkWeighting::Difference ? e.weight_jerk * dt : e.weight_jerk / dt;
  return t;
}

double sum_of(const AuthorsTerms& terms) { return terms[0] + terms[1] + terms[2] + terms[3]; }

PathViolation path_violation(const LaneChangeQp& qp, const Iterate& path) {
  PathViolation v{0.0, 0.0, 0.0};
  v.dynamics = (path.states[0] - qp.initial_state).cwiseAbs().maxCoeff();
  for (int k = 0; k < qp.steps; ++k) {
    const StageDynamics& d = qp.dynamics[k];
    const State next = d.A * path.states[k] + d.B * path.controls[k] + d.c;
    v.dynamics = std::max(v.dynamics, (next - path.states[k + 1]).cwiseAbs().maxCoeff());
    v.bounds = std::max({v.bounds, (qp.control_lower - path.controls[k]).maxCoeff(),
                         (path.controls[k] - qp.control_upper).maxCoeff()});
  }
  for (int k = 1; k <= qp.steps; ++k) {
    v.bounds = std::max({v.bounds, (qp.state_lower[k] - path.states[k]).maxCoeff(),
                         (path.states[k] - qp.state_upper[k]).maxCoeff()});
  }
  if (qp.terminal_lateral_fixed) {
    v.bounds = std::max(v.bounds, std::abs(path.states[qp.steps][kY] - qp.lateral_reference));
  }
  for (int k = 0; k <= qp.steps; ++k) {
    const auto& modes = qp.node_modes[k];
    if (modes.empty()) continue;
    double best = kInfinity;
    for (const LaneMode& m : modes) {
      double worst = 0.0;
      for (const HalfSpace& h : m.rows) worst = std::max(worst, h.g.dot(path.states[k]) - h.upper);
      best = std::min(best, worst);
    }
    v.lanes = std::max(v.lanes, best);
  }
  return v;
}

std::string_view to_string(AuthorsAgreement a) {
  switch (a) {
    case AuthorsAgreement::Match: return "match";
    case AuthorsAgreement::OursLower: return "ours_lower";
    case AuthorsAgreement::OursHigher: return "ours_higher";
    case AuthorsAgreement::OnlyTheySolve: return "only_they_solve";
    case AuthorsAgreement::OnlyWeSolve: return "only_we_solve";
    case AuthorsAgreement::NeitherSolves: return "neither_solves";
  }
  return "?";
}

std::string_view to_string(AuthorsCause c) {
  switch (c) {
    case AuthorsCause::None: return "none";
    case AuthorsCause::TheirsNotOptimal: return "theirs_not_optimal";
    case AuthorsCause::OursSlip: return "ours_slip";
    case AuthorsCause::DifferentProblem: return "different_problem";
    case AuthorsCause::DifferentFixpoint: return "different_fixpoint";
    case AuthorsCause::OurFailure: return "our_failure";
    case AuthorsCause::Unexplained: return "unexplained";
  }
  return "?";
}

namespace {

// The cars as a round linearized about `point` sees them (planner.cpp).
TrafficPrediction prediction_along(const Scenario& s, const Config& config, const Iterate& point) {
  return expert::prediction_along(s, config, s.steps + config.expert.prediction_lead_steps,
                                  s.horizon / s.steps, point);
}

int first_cross_node(const Iterate& path, const Scenario& s) {
  const double touch = 0.5 * s.lane_width - 0.5 * s.vehicle.width;
  for (std::size_t k = 0; k < path.states.size(); ++k) {
    if (path.states[k][kY] >= touch) return static_cast<int>(k);
  }
  return -1;
}

double relative(double ours, double theirs) { return (ours - theirs) / std::abs(theirs); }

bool feasible(const PathViolation& v, const AuthorsComparisonSettings& st) {
  return v.constraints() <= st.feasibility_tolerance && v.dynamics <= st.dynamics_tolerance;
}

void classify(AuthorsComparison& c, const AuthorsComparisonSettings& st) {
  const bool ours = c.our_status == PlanStatus::Converged && std::isfinite(c.our_objective);
  if (!c.theirs_solved) {
    c.agreement = ours ? AuthorsAgreement::OnlyWeSolve : AuthorsAgreement::NeitherSolves;
    c.cause = ours ? AuthorsCause::Unexplained : AuthorsCause::None;
    return;
  }
  if (!ours) {
    c.agreement = AuthorsAgreement::OnlyTheySolve;
    c.cause = AuthorsCause::OurFailure;
    return;
  }
  c.relative_difference = relative(c.our_objective, c.their_objective);
  if (std::abs(c.relative_difference) <= st.tolerance) {
    c.agreement = AuthorsAgreement::Match;
    c.cause = AuthorsCause::None;
    return;
  }
  c.agreement =
      c.relative_difference < 0 ? AuthorsAgreement::OursLower : AuthorsAgreement::OursHigher;
  // The largest of the three parts of the difference names the cause.
  const double parts[] = {c.their_gap, c.prediction_effect, c.fixpoint_effect};
  if (!std::all_of(std::begin(parts), std::end(parts), [](double p) { return std::isfinite(p); })) {
    c.cause = AuthorsCause::Unexplained;
    return;
  }
  const auto largest =
      std::max_element(std::begin(parts), std::end(parts),
                       [](double a, double b) { return std::abs(a) < std::abs(b); }) -
      std::begin(parts);
  if (largest == 0) {
    // Below their objective: their solve missed the optimum of their own
    // last problem. Above it, with their path feasible there: our solver
    // missed a cheaper point; with it infeasible: we read the rules otherwise.
    if (c.their_gap < 0) {
      c.cause = AuthorsCause::TheirsNotOptimal;
    } else {
      c.cause = feasible(c.with_their_prediction.violation, st) ? AuthorsCause::OursSlip
                                                                : AuthorsCause::DifferentProblem;
    }
  } else if (largest == 1) {
    c.cause = AuthorsCause::DifferentProblem;
  } else {
    const bool cheaper_in_our_qp =
        std::isfinite(c.their_objective_in_our_qp) && feasible(c.their_violation_in_our_qp, st) &&
        relative(c.our_objective, c.their_objective_in_our_qp) > st.tolerance;
    c.cause = c.agreement == AuthorsAgreement::OursHigher && cheaper_in_our_qp
                  ? AuthorsCause::OursSlip
                  : AuthorsCause::DifferentFixpoint;
  }
}

TheirProblemCheck check_their_problem(const AuthorsRecord& r, const Config& config,
                                      const TrafficPrediction& prediction,
                                      const LaneChangeSolver& solver,
                                      const AuthorsComparisonSettings& st) {
  const Scenario& s = r.scenario;
  const LaneChangeQp qp = build_lane_change_qp(s, config, r.solution, prediction);
  TheirProblemCheck out;
  out.their_objective = qp.objective(r.solution);
  out.violation = path_violation(qp, r.solution);
  std::vector<int> modes(s.steps + 1, -1);
  for (int k = 0; k <= s.steps; ++k) {
    if (!qp.node_modes[k].empty()) modes[k] = qp.best_mode(r.solution, k);
  }
  MiqpSettings settings;
  settings.time_limit_s = st.limits.time_limit_s;
  const auto workspace = solver.make_workspace();
  const LaneChangeSolution solved =
      solver.solve(qp, settings, {workspace.get(), &modes, &r.solution.controls});
  out.status = solved.status;
  if (solved.status == MiqpStatus::Optimal && solved.has_solution()) {
    out.optimum = solved.objective;
    out.relative = relative(solved.objective, r.objective);
  }
  return out;
}

}  // namespace

TrafficPrediction their_prediction_on_our_grid(const AuthorsRecord& r) {
  TrafficPrediction out;
  out.dt = r.predicted_others.dt;
  out.cars.resize(std::size(kRoles));
  for (Role car : kRoles) {
    const auto i = static_cast<std::size_t>(car);
    const CarTrack& theirs = r.predicted_others.cars[i];
    CarTrack& track = out.cars[i];
    track.x.push_back(r.scenario.car(car).x);
    track.v.push_back(r.scenario.car(car).v);
    track.x.insert(track.x.end(), theirs.x.begin(), theirs.x.end());
    track.v.insert(track.v.end(), theirs.v.begin(), theirs.v.end());
    track.a.assign(track.x.size(), 0.0);
  }
  return out;
}

ExpertPlanner authors_planner(const Config& config) {
  return ExpertPlanner(config, std::make_shared<FastLaneChangeSolver>());
}

AuthorsComparison compare_with_authors(const AuthorsRecord& r, const ExpertPlanner& planner,
                                       const AuthorsComparisonSettings& st) {
  AuthorsComparison c;
  c.id = r.id;
  c.line = r.line;
  c.theirs_solved = r.solved;
  const Scenario& s = r.scenario;
  const Config config = effective_config(planner.config(), s);
  const int lead = config.expert.prediction_lead_steps;

  const ExpertResult ours = planner.plan(s, st.limits);
  c.our_status = ours.status;
  c.our_reason = ours.reason;
  c.iterations = ours.iterations();
  c.ms = ours.total_ms;
  if (ours.path.states.empty()) {
    c.our_label = Label::Failure;
  } else {
    c.our_label = planner.to_trajectory(ours, s).label;
  }
  const bool ours_solved = ours.status == PlanStatus::Converged && !ours.path.states.empty();
  if (ours_solved) {
    c.our_objective = ours.objective;
    const LaneChangeQp next = build_lane_change_qp(s, config, ours.path, ours.prediction);
    c.our_terms =
        authors_objective_terms(ours.path, config, s.lane_width, next.terminal_x_reference);
    c.our_first_cross_node = first_cross_node(ours.path, s);
  }

  if (r.solved) {
    c.their_objective = r.objective;
    c.their_terms = r.objective_terms;
    c.their_first_cross_node = first_cross_node(r.solution, s);
    // Our prediction along their path against theirs.
    const TrafficPrediction along = prediction_along(s, config, r.solution);
    for (Role car : kRoles) {
      const auto i = static_cast<std::size_t>(car);
      const CarTrack& mine = along.cars[i];
      const CarTrack& theirs = r.predicted_others.cars[i];
      double dx = 0.0, dv = 0.0;
      for (std::size_t k = 0; k < theirs.x.size(); ++k) {
        const std::size_t j = std::min(k + static_cast<std::size_t>(lead), mine.x.size() - 1);
        dx = std::max(dx, std::abs(mine.x[j] - theirs.x[k]));
        dv = std::max(dv, std::abs(mine.v[j] - theirs.v[k]));
      }
      c.prediction_max_dx[i] = dx;
      c.prediction_max_dv[i] = dv;
    }
    c.target_end_dx = r.predicted_others.car(s.index_of(Role::Target)).x.back() -
                      along.car(s.index_of(Role::Target)).x.back();

    if (st.diagnose) {
      c.with_their_prediction =
          check_their_problem(r, config, their_prediction_on_our_grid(r), planner.solver(), st);
      c.with_our_prediction = check_their_problem(r, config, along, planner.solver(), st);
    }
  }

  if (ours_solved && r.solved) {
    c.max_dx = c.max_dy = c.max_dv = 0.0;
    for (std::size_t k = 0; k < r.solution.states.size(); ++k) {
      const State d = ours.path.states[k] - r.solution.states[k];
      c.max_dx = std::max(c.max_dx, std::abs(d[kX]));
      c.max_dy = std::max(c.max_dy, std::abs(d[kY]));
      c.max_dv = std::max(c.max_dv, std::abs(d[kV]));
    }
    const bool disagree = std::abs(relative(c.our_objective, c.their_objective)) > st.tolerance;
    if (st.diagnose && (disagree || st.diagnose_agreeing)) {
      // Our last round: linearized about the round before (the planner
      // stopped one round short gives it), the cars predicted along it.
      Iterate point;
      if (ours.iterations() >= 2) {
        Config shorter = planner.config();
        shorter.expert.max_iterations = ours.iterations() - 1;
        const ExpertPlanner one_short(
            shorter, std::shared_ptr<const LaneChangeSolver>(&planner.solver(),
                                                             [](const LaneChangeSolver*) {}));
        point = one_short.plan(s, st.limits).path;
      } else {
        const double dt = s.horizon / s.steps;
        point = warm_start(s, config, predict_traffic(s, config, s.steps + lead, dt));
      }
      if (!point.states.empty()) {
        const LaneChangeQp last =
            build_lane_change_qp(s, config, point, prediction_along(s, config, point));
        c.our_qp_rebuild_error = last.objective(ours.path) - ours.objective;
        c.their_objective_in_our_qp = last.objective(r.solution);
        c.their_violation_in_our_qp = path_violation(last, r.solution);
      }
    }
  }
  if (ours_solved && r.solved) {
    const double a = c.with_their_prediction.optimum;
    const double b = c.with_our_prediction.optimum;
    c.their_gap = (a - r.objective) / std::abs(r.objective);
    c.prediction_effect = (b - a) / std::abs(r.objective);
    c.fixpoint_effect = (c.our_objective - b) / std::abs(r.objective);
  }
  classify(c, st);
  return c;
}

std::vector<AuthorsComparison> compare_with_authors(const std::vector<AuthorsRecord>& records,
                                                    const ExpertPlanner& planner,
                                                    const AuthorsComparisonSettings& settings,
                                                    AuthorsProgress progress) {
  std::vector<AuthorsComparison> out(records.size());
  std::atomic<std::size_t> next{0};
  std::atomic<std::size_t> done{0};
  std::mutex report;
  auto work = [&] {
    for (std::size_t i = next++; i < records.size(); i = next++) {
      out[i] = compare_with_authors(records[i], planner, settings);
      const std::size_t finished = ++done;
      if (progress != nullptr) {
        const std::lock_guard lock(report);
        progress(finished, records.size());
      }
    }
  };
  const int threads = std::max(1, settings.threads);
  std::vector<std::thread> pool;
  for (int t = 1; t < threads; ++t) pool.emplace_back(work);
  work();
  for (auto& t : pool) t.join();
  return out;
}

// ---------------------------------------------------------------- summary

std::vector<Quantile> quantiles(std::vector<double> values, const std::vector<double>& qs) {
  std::erase_if(values, [](double v) { return !std::isfinite(v); });
  std::sort(values.begin(), values.end());
  std::vector<Quantile> out;
  out.reserve(qs.size());
  for (double q : qs) {
    out.push_back({q, values.empty() ? kNotANumber : run::nearest_rank_sorted(values, q)});
  }
  return out;
}

AuthorsSummary summarize(const std::vector<AuthorsComparison>& all, double tolerance) {
  AuthorsSummary s;
  s.tolerance = tolerance;
  s.qs = {0.0, 0.01, 0.05, 0.1, 0.25, 0.5, 0.75, 0.9, 0.95, 0.99, 1.0};
  std::vector<double> rel, abs_rel, dx, dy, gap, pred_effect, fix_effect, pf, pl, pt, tend, ms;
  std::vector<int> cause_count(7, 0);
  std::vector<std::pair<std::string, int>> statuses;
  for (const AuthorsComparison& c : all) {
    ++s.records;
    ms.push_back(c.ms);
    s.total_plan_s += c.ms / 1000.0;
    ++cause_count[static_cast<std::size_t>(c.cause)];
    switch (c.agreement) {
      case AuthorsAgreement::Match: ++s.match; break;
      case AuthorsAgreement::OursLower: ++s.ours_lower; break;
      case AuthorsAgreement::OursHigher: ++s.ours_higher; break;
      case AuthorsAgreement::OnlyTheySolve: ++s.only_they_solve; break;
      case AuthorsAgreement::OnlyWeSolve: ++s.only_we_solve; break;
      case AuthorsAgreement::NeitherSolves: ++s.neither_solves; break;
    }
    if (!c.theirs_solved) {
      ++s.theirs_no_solution;
      continue;
    }
    ++s.theirs_solved;
    const std::string status(to_string(c.our_status));
    auto it = std::find_if(statuses.begin(), statuses.end(),
                           [&](const auto& p) { return p.first == status; });
    if (it == statuses.end()) {
      statuses.emplace_back(status, 1);
    } else {
      ++it->second;
    }
    gap.push_back(c.with_their_prediction.relative);
    pl.push_back(c.prediction_max_dx[static_cast<std::size_t>(Role::Leader)]);
    pf.push_back(c.prediction_max_dx[static_cast<std::size_t>(Role::Follower)]);
    pt.push_back(c.prediction_max_dx[static_cast<std::size_t>(Role::Target)]);
    tend.push_back(c.target_end_dx);
    if (!std::isfinite(c.relative_difference)) continue;
    ++s.both_solved;
    if (c.relative_difference <= tolerance) ++s.at_most_tolerance_above;
    rel.push_back(c.relative_difference);
    abs_rel.push_back(std::abs(c.relative_difference));
    dx.push_back(c.max_dx);
    dy.push_back(c.max_dy);
    pred_effect.push_back(c.prediction_effect);
    fix_effect.push_back(c.fixpoint_effect);
  }
  const auto share = [](int n, int d) { return d > 0 ? static_cast<double>(n) / d : 0.0; };
  s.share_at_most_tolerance_above = share(s.at_most_tolerance_above, s.theirs_solved);
  s.share_within_tolerance = share(s.match, s.theirs_solved);
  s.share_no_solution_agreed = share(s.neither_solves, s.theirs_no_solution);
  s.acceptance_met = s.share_at_most_tolerance_above >= 0.9 &&
                     (s.theirs_no_solution == 0 || s.share_no_solution_agreed > 0.5);
  for (int i = 0; i < 7; ++i) {
    if (cause_count[i] > 0) s.causes.emplace_back(static_cast<AuthorsCause>(i), cause_count[i]);
  }
  s.our_statuses = statuses;
  s.relative_difference = quantiles(rel, s.qs);
  s.abs_relative_difference = quantiles(abs_rel, s.qs);
  s.max_dx = quantiles(dx, s.qs);
  s.max_dy = quantiles(dy, s.qs);
  s.their_gap = quantiles(gap, s.qs);
  s.prediction_effect = quantiles(pred_effect, s.qs);
  s.fixpoint_effect = quantiles(fix_effect, s.qs);
  s.prediction_leader_dx = quantiles(pl, s.qs);
  s.prediction_follower_dx = quantiles(pf, s.qs);
  s.prediction_target_dx = quantiles(pt, s.qs);
  s.target_end_dx = quantiles(tend, s.qs);
  s.plan_ms = quantiles(ms, s.qs);
  return s;
}

// ---------------------------------------------------------------- output

namespace {

json terms_json(const AuthorsTerms& t) {
  return json::array({run::number_or_null(t[0]), run::number_or_null(t[1]),
                      run::number_or_null(t[2]), run::number_or_null(t[3])});
}

json violation_json(const PathViolation& v) {
  return {{"dynamics", run::number_or_null(v.dynamics)},
          {"bounds", run::number_or_null(v.bounds)},
          {"lanes", run::number_or_null(v.lanes)}};
}

json check_json(const TheirProblemCheck& t) {
  return {{"their_objective", run::number_or_null(t.their_objective)},
          {"violation", violation_json(t.violation)},
          {"status", to_string(t.status)},
          {"optimum", run::number_or_null(t.optimum)},
          {"relative", run::number_or_null(t.relative)}};
}

json quantiles_json(const std::vector<Quantile>& qs) {
  json out = json::object();
  for (const Quantile& q : qs) {
    char key[16];
    std::snprintf(key, sizeof key, "p%g", 100.0 * q.q);
    out[key] = run::number_or_null(q.value);
  }
  return out;
}

}  // namespace

void to_json(json& out, const AuthorsComparison& c) {
  json pdx = json::object(), pdv = json::object();
  for (Role car : kRoles) {
    const auto i = static_cast<std::size_t>(car);
    pdx[std::string(to_string(car))] = run::number_or_null(c.prediction_max_dx[i]);
    pdv[std::string(to_string(car))] = run::number_or_null(c.prediction_max_dv[i]);
  }
  out = {{"id", c.id},
         {"line", c.line},
         {"theirs_solved", c.theirs_solved},
         {"our_status", to_string(c.our_status)},
         {"our_reason", c.our_reason},
         {"our_label", to_string(c.our_label)},
         {"iterations", c.iterations},
         {"ms", c.ms},
         {"our_objective", run::number_or_null(c.our_objective)},
         {"our_terms", terms_json(c.our_terms)},
         {"their_objective", run::number_or_null(c.their_objective)},
         {"their_terms", terms_json(c.their_terms)},
         {"relative_difference", run::number_or_null(c.relative_difference)},
         {"max_dx", run::number_or_null(c.max_dx)},
         {"max_dy", run::number_or_null(c.max_dy)},
         {"max_dv", run::number_or_null(c.max_dv)},
         {"our_first_cross_node", c.our_first_cross_node},
         {"their_first_cross_node", c.their_first_cross_node},
         {"their_objective_in_our_qp", run::number_or_null(c.their_objective_in_our_qp)},
         {"their_violation_in_our_qp", violation_json(c.their_violation_in_our_qp)},
         {"our_qp_rebuild_error", run::number_or_null(c.our_qp_rebuild_error)},
         {"with_their_prediction", check_json(c.with_their_prediction)},
         {"with_our_prediction", check_json(c.with_our_prediction)},
         {"their_gap", run::number_or_null(c.their_gap)},
         {"prediction_effect", run::number_or_null(c.prediction_effect)},
         {"fixpoint_effect", run::number_or_null(c.fixpoint_effect)},
         {"prediction_max_dx", pdx},
         {"prediction_max_dv", pdv},
         {"target_end_dx", run::number_or_null(c.target_end_dx)},
         {"agreement", to_string(c.agreement)},
         {"cause", to_string(c.cause)}};
}

void to_json(json& out, const AuthorsSummary& s) {
  json causes = json::object();
  for (const auto& [cause, n] : s.causes) causes[std::string(to_string(cause))] = n;
  json statuses = json::object();
  for (const auto& [name, n] : s.our_statuses) statuses[name] = n;
  out = {{"tolerance", s.tolerance},
         {"records", s.records},
         {"theirs_solved", s.theirs_solved},
         {"theirs_no_solution", s.theirs_no_solution},
         {"both_solved", s.both_solved},
         {"only_they_solve", s.only_they_solve},
         {"only_we_solve", s.only_we_solve},
         {"neither_solves", s.neither_solves},
         {"match", s.match},
         {"ours_lower", s.ours_lower},
         {"ours_higher", s.ours_higher},
         {"at_most_tolerance_above", s.at_most_tolerance_above},
         {"share_at_most_tolerance_above", s.share_at_most_tolerance_above},
         {"share_within_tolerance", s.share_within_tolerance},
         {"share_no_solution_agreed", s.share_no_solution_agreed},
         {"acceptance_met", s.acceptance_met},
         {"causes", causes},
         {"our_statuses_on_their_solved", statuses},
         {"relative_difference", quantiles_json(s.relative_difference)},
         {"abs_relative_difference", quantiles_json(s.abs_relative_difference)},
         {"max_dx", quantiles_json(s.max_dx)},
         {"max_dy", quantiles_json(s.max_dy)},
         {"their_gap", quantiles_json(s.their_gap)},
         {"prediction_effect", quantiles_json(s.prediction_effect)},
         {"fixpoint_effect", quantiles_json(s.fixpoint_effect)},
         {"prediction_leader_dx", quantiles_json(s.prediction_leader_dx)},
         {"prediction_follower_dx", quantiles_json(s.prediction_follower_dx)},
         {"prediction_target_dx", quantiles_json(s.prediction_target_dx)},
         {"target_end_dx", quantiles_json(s.target_end_dx)},
         {"plan_ms", quantiles_json(s.plan_ms)},
         {"total_plan_s", s.total_plan_s}};
}

namespace {

const std::vector<run::Align> kCountColumns = {run::Align::Left, run::Align::Right};

std::string counts_markdown(const AuthorsSummary& s) {
  run::Table table{{"count", "records"}, {}};
  const std::pair<const char*, int> rows[] = {
      {"records", s.records},
      {"theirs solved", s.theirs_solved},
      {"theirs no_solution", s.theirs_no_solution},
      {"both solved", s.both_solved},
      {"only they solve", s.only_they_solve},
      {"only we solve", s.only_we_solve},
      {"neither solves", s.neither_solves},
      {"match (|rel| <= tol)", s.match},
      {"ours lower (rel < -tol)", s.ours_lower},
      {"ours higher (rel > tol)", s.ours_higher},
  };
  for (const auto& [name, n] : rows) table.rows.push_back({name, std::to_string(n)});
  return run::markdown(table, kCountColumns);
}

std::string verdict_markdown(const AuthorsSummary& s) {
  const auto pct = [](int n, int d) { return d > 0 ? 100.0 * n / d : 0.0; };
  char buf[256];
  std::snprintf(buf, sizeof buf,
                "\nOf their %d solved records, ours is at most %.1f%% above theirs on %d "
                "(%.1f%%; bar 90%%); within +-%.1f%% on %d (%.1f%%).\n",
                s.theirs_solved, 100 * s.tolerance, s.at_most_tolerance_above,
                100 * s.share_at_most_tolerance_above, 100 * s.tolerance, s.match,
                pct(s.match, s.theirs_solved));
  std::string out = buf;
  std::snprintf(buf, sizeof buf,
                "Of their %d no_solution records, we fail too on %d (%.1f%%). Acceptance: %s.\n",
                s.theirs_no_solution, s.neither_solves, 100 * s.share_no_solution_agreed,
                s.acceptance_met ? "met" : "NOT met");
  return out + buf;
}

std::string quantiles_markdown(const AuthorsSummary& s) {
  run::Table table{{"quantile"}, {}};
  std::vector<run::Align> align = {run::Align::Left};
  char buf[64];
  for (double q : s.qs) {
    std::snprintf(buf, sizeof buf, "p%g", 100 * q);
    table.header.emplace_back(buf);
    align.push_back(run::Align::Right);
  }
  const std::pair<const char*, const std::vector<Quantile>*> rows[] = {
      {"relative difference (ours - theirs) / theirs", &s.relative_difference},
      {"abs relative difference", &s.abs_relative_difference},
      {"max abs dx (m)", &s.max_dx},
      {"max abs dy (m)", &s.max_dy},
      {"their gap: (optimum of their last problem - theirs) / theirs", &s.their_gap},
      {"prediction effect (share of their objective)", &s.prediction_effect},
      {"fixpoint effect (share of their objective)", &s.fixpoint_effect},
      {"prediction leader max abs dx (m)", &s.prediction_leader_dx},
      {"prediction follower max abs dx (m)", &s.prediction_follower_dx},
      {"prediction target max abs dx (m)", &s.prediction_target_dx},
      {"target end x, theirs - ours (m)", &s.target_end_dx},
      {"plan time (ms)", &s.plan_ms},
  };
  for (const auto& [name, qs] : rows) {
    std::vector<std::string> row = {name};
    for (const Quantile& q : *qs) {
      std::snprintf(buf, sizeof buf, "%.4g", q.value);
      row.emplace_back(buf);
    }
    table.rows.push_back(std::move(row));
  }
  return run::markdown(table, align);
}

}  // namespace

std::string to_markdown(const AuthorsSummary& s) {
  run::Table statuses{{"our status on their solved records", "count"}, {}};
  for (const auto& [name, n] : s.our_statuses) statuses.rows.push_back({name, std::to_string(n)});
  run::Table causes{{"cause", "count"}, {}};
  for (const auto& [cause, n] : s.causes) {
    causes.rows.push_back({std::string(to_string(cause)), std::to_string(n)});
  }
  char total[64];
  std::snprintf(total, sizeof total, "\nTotal plan time %.1f s.\n", s.total_plan_s);
  return counts_markdown(s) + verdict_markdown(s) + "\n" + run::markdown(statuses, kCountColumns) +
         "\n" + run::markdown(causes, kCountColumns) + "\n" + quantiles_markdown(s) + total;
}

std::string run_authors_study(const AuthorsStudyOptions& o) {
  const std::vector<AuthorsRecord> records = load_authors_records(o.records_path, o.config);
  std::filesystem::create_directories(o.out_dir);
  const std::filesystem::path out(o.out_dir);
  const auto start = std::chrono::steady_clock::now();
  const auto results =
      compare_with_authors(records, authors_planner(o.config), o.settings, o.progress);
  const double wall =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::ofstream lines(out / "comparisons.jsonl");
  for (const AuthorsComparison& c : results) lines << nlohmann::json(c).dump() << "\n";
  const AuthorsSummary summary = summarize(results, o.settings.tolerance);
  nlohmann::json j = summary;
  j["wall_s"] = wall;
  j["threads"] = o.settings.threads;
  std::ofstream summary_json(out / "summary.json");
  summary_json << j.dump(2) << "\n";
  const std::string md = to_markdown(summary);
  std::ofstream markdown(out / "summary.md");
  markdown << md;
  lines.close();
  summary_json.close();
  markdown.close();
  if (!lines || !summary_json || !markdown)
    throw InputError("--out", o.out_dir + " cannot be written");
  char wall_line[120];
  std::snprintf(wall_line, sizeof wall_line, "Wall time %g s on %d thread(s).\n", wall,
                o.settings.threads);
  return md + wall_line;
}

}  // namespace lanechange::studies
