#include "baselines/mpc.hpp"

#include <algorithm>
#include <cmath>
#include <coin/IpSolveStatistics.hpp>
#include <limits>
#include <mutex>
#include <optional>

#include "expert/coin_glue.hpp"
#include "lanechange/expert/bonmin_solver.hpp"
#include "lanechange/traffic.hpp"
#include "planner/miqp_planner.hpp"

namespace lanechange::baselines {

namespace {

using expert::coin::milliseconds_since;
using expert::coin::set_option;
using planner::ActStatus;
using planner::Decision;
using planner::Observation;

// n equal circles along the body: each covers its slice of the length and
// the full width, so the union covers the box.
struct Circles {
  std::vector<double> offsets;
  double radius = 0.0;
};

Circles body_circles(const VehicleSize& size, int count) {
  Circles circles;
  const double slice = size.length / count;
  for (int i = 0; i < count; ++i) circles.offsets.push_back(-0.5 * size.length + (i + 0.5) * slice);
  circles.radius = std::hypot(0.5 * size.width, 0.5 * slice);
  return circles;
}

std::vector<EgoFootprint> footprint_of(const MpcPlan& plan) {
  std::vector<EgoFootprint> path;
  for (const EgoState& z : plan.states) path.push_back({z.x, z.y, z.v});
  return path;
}

// A car's circles at a node enter the rows only where the guess passes
// within `gate` of touching them: the rows of far cars cost Ipopt time (its
// linear solves grow with them) and never bind. The rest are kept to check.
void add_obstacles(MpcProblemData& data, const Scenario& scene, const TrafficPrediction& cars,
                   const MpcSettings& settings, const MpcPlan& guess) {
  const auto nodes = static_cast<std::size_t>(data.steps) + 1;
  data.obstacles.assign(nodes, {});
  data.pruned.assign(nodes, {});
  for (CarIndex c = 0; c < scene.car_count(); ++c) {
    const VehicleSize size = scene.size_of(c);
    const Circles circles = body_circles(size, settings.circles);
    const double clearance = data.ego_radius + circles.radius + settings.margin;
    const double reach =
        0.5 * (scene.vehicle.length + size.length) + clearance + settings.gate_distance;
    for (std::size_t k = 1; k < nodes; ++k) {
      const double x = cars.car(c).x[k];
      const bool near = std::abs(guess.states[k].x - x) <= reach;
      for (const double offset : circles.offsets) {
        (near ? data.obstacles : data.pruned)[k].push_back(
            {x + offset, scene.lane_center(c), clearance});
      }
    }
  }
}

// The terminal set of the expert's fixed y(t_f) = w, placed in Eq. 1's gap:
// at least the follower's safe distance ahead of it, and the target's behind
// it (Eq. 1 at the last node); open on a side the scene has no car.
void add_terminal_gap(MpcProblemData& data, const Scenario& scene, const TrafficPrediction& cars) {
  const std::size_t end = static_cast<std::size_t>(data.steps);
  const SafetyMargins safe = scene.centre_safe_distances();
  constexpr double kOpen = std::numeric_limits<double>::infinity();  // Ipopt: no bound
  data.terminal_gap = true;
  data.gap_rear = -kOpen;
  data.gap_front = kOpen;
  if (scene.has(Role::Follower)) {
    const CarTrack& follower = cars.car(scene.index_of(Role::Follower));
    data.gap_rear =
        follower.x[end] + safe.follower.standstill + safe.follower.time_headway * follower.v[end];
  }
  if (scene.has(Role::Target)) {
    data.gap_front = cars.car(scene.index_of(Role::Target)).x[end] - safe.target.standstill;
  }
  data.target_headway = safe.target.time_headway;
}

MpcStatus status_of(Ipopt::ApplicationReturnStatus status) {
  switch (status) {
    case Ipopt::Solve_Succeeded:
    case Ipopt::Solved_To_Acceptable_Level: return MpcStatus::Solved;
    case Ipopt::Infeasible_Problem_Detected: return MpcStatus::Infeasible;
    case Ipopt::Maximum_Iterations_Exceeded: return MpcStatus::IterationLimit;
    case Ipopt::Maximum_CpuTime_Exceeded:
    case Ipopt::User_Requested_Stop: return MpcStatus::TimeLimit;
    default: return MpcStatus::NumericalError;
  }
}

std::string failure_message(Ipopt::ApplicationReturnStatus status) {
  switch (status) {
    case Ipopt::Infeasible_Problem_Detected: return "Ipopt converged to an infeasible point";
    case Ipopt::Maximum_Iterations_Exceeded: return "the iteration limit ran out";
    case Ipopt::Maximum_CpuTime_Exceeded: return "the CPU-time limit ran out";
    case Ipopt::User_Requested_Stop: return "the wall-time limit ran out";
    default: break;
  }
  std::string message = "Ipopt return status ";
  message += std::to_string(static_cast<int>(status));
  return message;
}

// The caller holds lock_coin_or_libraries().
Ipopt::SmartPtr<Ipopt::IpoptApplication> make_ipopt(const MpcSettings& settings) {
  Ipopt::SmartPtr<Ipopt::IpoptApplication> app =
      new Ipopt::IpoptApplication(/*create_console_out=*/false);
  Ipopt::OptionsList& options = *app->Options();
  set_option(options, "print_level", 0);
  set_option(options, "sb", "yes");
  set_option(options, "tol", settings.tolerance);
  set_option(options, "max_iter", settings.max_iterations);
  // Ipopt 3.11 has no wall-time option: the program's callback stops at the
  // wall deadline; the CPU limit is the backstop.
  set_option(options, "max_cpu_time", settings.time_limit_ms / 1000.0);
  set_option(options, "mu_strategy", "adaptive");
  // The start is the last solution shifted: already close, so a small
  // barrier parameter and push from the bounds keep it.
  set_option(options, "mu_init", 1e-2);
  set_option(options, "bound_push", 1e-4);
  set_option(options, "bound_frac", 1e-4);
  if (app->Initialize("") != Ipopt::Solve_Succeeded) {
    throw std::runtime_error("Ipopt failed to initialise");
  }
  return app;
}

}  // namespace

std::string_view to_string(MpcStatus status) {
  switch (status) {
    case MpcStatus::Solved: return "solved";
    case MpcStatus::Infeasible: return "infeasible";
    case MpcStatus::IterationLimit: return "iteration_limit";
    case MpcStatus::TimeLimit: return "time_limit";
    case MpcStatus::NumericalError: return "numerical_error";
    case MpcStatus::GateMissed: return "gate_missed";
  }
  return "unknown";
}

MpcProblemData build_mpc_problem(const Scenario& scene, const Config& base, const MpcPlan& guess) {
  const Config config = effective_config(base, scene);
  const ExpertSettings& e = config.expert;
  MpcProblemData data;
  data.steps = scene.steps;
  data.dt = scene.horizon / scene.steps;
  data.initial = scene.ego;
  data.previous_accel = scene.ego.a;
  data.accel_weight = e.weight_accel * data.dt;
  data.yaw_rate_weight = e.weight_yaw_rate * data.dt;
  data.jerk_weight = e.jerk_weighting == JerkWeighting::Derivative ? e.weight_jerk / data.dt
                                                                   : e.weight_jerk * data.dt;
  data.lateral_weight = e.weight_lateral * data.dt;
  data.lateral_reference = scene.lane_width;
  data.y_lower = -scene.limits.lateral_margin;
  data.y_upper = scene.lane_width + scene.limits.lateral_margin;
  data.v = scene.limits.v;
  data.a = scene.limits.a;
  data.omega = scene.limits.omega;
  const Circles circles = body_circles(scene.vehicle, config.mpc.circles);
  data.ego_offsets = circles.offsets;
  data.ego_radius = circles.radius;
  const auto path = footprint_of(guess);
  const TrafficPrediction cars = traffic_reacts(scene, config)
                                     ? predict_traffic(scene, config, data.steps, data.dt, &path)
                                     : predict_traffic(scene, config, data.steps, data.dt);
  add_obstacles(data, scene, cars, config.mpc, guess);
  if (config.mpc.terminal_gap) add_terminal_gap(data, scene, cars);
  return data;
}

namespace {

// The constant acceleration that brings the ego to the middle of the gap at
// the horizon, with the follower and target at constant speed: the terminal
// set's centre, so the cold start is not far from the rows it must meet.
double accel_into_gap(const Scenario& scene) {
  const double t = scene.horizon;
  const SafetyMargins safe = scene.centre_safe_distances();
  const double cruise = scene.ego.x + scene.ego.v * t;
  double aim = cruise;
  std::optional<double> rear;
  std::optional<double> front;
  if (scene.has(Role::Follower)) {
    const CarState& f = scene.follower();
    rear = f.x + f.v * t + safe.follower.standstill + safe.follower.time_headway * f.v;
  }
  if (scene.has(Role::Target)) {
    const CarState& g = scene.target();
    front = g.x + g.v * t - safe.target.standstill - safe.target.time_headway * g.v;
  }
  if (rear && front) {
    aim = 0.5 * (*rear + *front);
  } else if (rear) {
    aim = std::max(*rear, cruise);
  } else if (front) {
    aim = std::min(*front, cruise);
  }
  const double wanted = 2.0 * (aim - scene.ego.x - scene.ego.v * t) / (t * t);
  const double v_lo = (scene.limits.v.lo - scene.ego.v) / t;
  const double v_hi = (scene.limits.v.hi - scene.ego.v) / t;
  return std::clamp(wanted, std::max(scene.limits.a.lo, v_lo), std::min(scene.limits.a.hi, v_hi));
}

}  // namespace

MpcPlan cold_guess(const Scenario& scene) {
  const double dt = scene.horizon / scene.steps;
  const double a = accel_into_gap(scene);
  MpcPlan plan;
  const EgoState& z0 = scene.ego;
  const double rise = scene.lane_width - z0.y;
  for (int k = 0; k <= scene.steps; ++k) {
    const double s = static_cast<double>(k) / scene.steps;
    const double t = k * dt;
    const double v = z0.v + a * t;
    const double slope = 6.0 * s * (1.0 - s) * rise / scene.horizon;  // dy/dt of the smoothstep
    const double theta = std::atan2(slope, std::max(v, 1.0));
    plan.states.push_back(
        {z0.x + z0.v * t + 0.5 * a * t * t, z0.y + rise * s * s * (3.0 - 2.0 * s), v, theta, a});
  }
  plan.states.front() = z0;
  for (int k = 0; k < scene.steps; ++k) {
    const double turn = (plan.states[k + 1].theta - plan.states[k].theta) / dt;
    plan.controls.push_back({a, std::clamp(turn, scene.limits.omega.lo, scene.limits.omega.hi)});
  }
  return plan;
}

MpcPlan shifted(const MpcPlan& plan, int by, int steps, double dt, const EgoState& now) {
  MpcPlan out;
  const int last = static_cast<int>(plan.controls.size());
  for (int k = 0; k <= steps; ++k) {
    const int from = k + by;
    EgoState z = plan.states[static_cast<std::size_t>(std::min(from, last))];
    const int beyond = std::max(0, from - last);
    z.x += beyond * dt * z.v * std::cos(z.theta);
    z.y += beyond * dt * z.v * std::sin(z.theta);
    out.states.push_back(z);
    if (k < steps) {
      const EgoControl u = plan.controls[static_cast<std::size_t>(std::min(from, last - 1))];
      out.controls.push_back(from < last ? u : EgoControl{0.0, 0.0});
    }
  }
  out.states.front() = now;
  return out;
}

MpcResult solve_mpc(MpcSolver& solver, const Scenario& scene, const Config& config,
                    const MpcPlan& guess) {
  constexpr double kClearanceTolerance = 1e-3;  // m; Ipopt's own rows hold to ~1e-6
  const auto start = std::chrono::steady_clock::now();
  MpcResult result;
  MpcPlan start_from = guess;
  // Under a deadline of work the step's iterations are its budget, shared
  // by its solves, as the wall time is under a deadline of wall time.
  const bool work = config.closed_loop.deadline == Deadline::Work;
  int iterations_left = work ? config.mpc.step_iterations : config.mpc.max_iterations;
  for (int round = 0; round < 2; ++round) {
    const double left_ms = step_wall_limit_ms(config.closed_loop, config.mpc.time_limit_ms) -
                           milliseconds_since(start);
    MpcProblemData data = build_mpc_problem(scene, config, start_from);
    const MpcProblemData unsolved = data;
    result = solver.solve(std::move(data), start_from, left_ms,
                          std::max(1, std::min(iterations_left, config.mpc.max_iterations)));
    if (work) iterations_left -= result.iterations;
    if (result.status != MpcStatus::Solved) return result;
    if (clearance_violation(unsolved, result.plan, unsolved.pruned) <= kClearanceTolerance) {
      return result;
    }
    start_from = result.plan;
  }
  result.status = MpcStatus::GateMissed;
  result.message = "the solution reaches circles left out of the rows";
  return result;
}

MpcSolver::MpcSolver(const MpcSettings& settings) : settings_(settings), nlp_(new MpcNlp) {
  const auto lock = expert::lock_coin_or_libraries();
  app_ = make_ipopt(settings_);
}

MpcSolver::~MpcSolver() {
  const auto lock = expert::lock_coin_or_libraries();
  app_ = nullptr;
}

MpcResult MpcSolver::solve(MpcProblemData data, MpcPlan guess, double time_limit_ms,
                           int max_iterations) {
  MpcResult result;
  const double shortest_gap = data.gap_front - data.gap_rear - data.target_headway * data.v.lo;
  if (data.terminal_gap && shortest_gap < 0.0) {
    result.status = MpcStatus::Infeasible;
    result.message = "the predicted gap at the horizon is shorter than the safe distances";
    result.plan = std::move(guess);
    return result;
  }
  nlp_->update(std::move(data), std::move(guess));
  const auto lock = expert::lock_coin_or_libraries();
  const auto start = std::chrono::steady_clock::now();
  nlp_->set_deadline(start +
                     std::chrono::microseconds(static_cast<long long>(time_limit_ms * 1000.0)));
  set_option(*app_->Options(), "max_cpu_time", std::max(time_limit_ms, 1.0) / 1000.0);
  set_option(*app_->Options(), "max_iter", max_iterations);
  const Ipopt::ApplicationReturnStatus status = app_->OptimizeTNLP(nlp_);
  result.solve_ms = milliseconds_since(start);
  result.status = status_of(status);
  result.plan = nlp_->solution();
  result.objective = nlp_->objective();
  if (Ipopt::SmartPtr<Ipopt::SolveStatistics> stats = app_->Statistics(); IsValid(stats)) {
    result.iterations = stats->IterationCount();
  }
  if (result.status != MpcStatus::Solved) result.message = failure_message(status);
  return result;
}

// Ipopt's solves are serialised process-wide (MUMPS is not thread-safe). Two
// mpc rollouts on two threads would wait for each other's solves inside their
// timed steps, and a wait over the 100 ms budget hands the step to the
// fallback: mpc's results depended on --jobs (docs/baselines.md). A session
// therefore takes the turn when it starts, outside the steps, and keeps it
// for its rollout. The other threads' planners run meanwhile. Recursive: a
// thread's nested sessions share the turn it holds.
namespace {
std::recursive_mutex& mpc_turn_mutex() {
  static std::recursive_mutex m;
  return m;
}
}  // namespace

MpcRolloutTurn::MpcRolloutTurn() { mpc_turn_mutex().lock(); }

MpcRolloutTurn::~MpcRolloutTurn() { mpc_turn_mutex().unlock(); }

MpcSession::MpcSession(const Config& config)
    : config_(config), keeper_(config), solver_(config.mpc) {}

Decision MpcSession::act(const Observation& o) {
  const std::string failure = replan(o);
  if (plan_) {
    const int offset = o.step - plan_step_;
    const bool fresh = offset <= config_.closed_loop.stale_plan_steps;
    if (offset < static_cast<int>(plan_->controls.size()) && (failure.empty() || fresh)) {
      Decision d{plan_->controls[static_cast<std::size_t>(offset)], ActStatus::Planned, ""};
      if (!failure.empty()) {
        d.reason = "re-plan failed (";
        d.reason += failure;
        d.reason += "): following the last plan";
      }
      return d;
    }
  }
  std::string why = "no feasible plan: ";
  why += failure.empty() ? "the last plan has run out" : failure;
  return {fallback_control(keeper_, o), ActStatus::Fallback, why};
}

MpcPlan MpcSession::starting_point(int step, const Scenario& scene) const {
  const double dt = scene.horizon / scene.steps;
  const int age = plan_ ? step - plan_step_ : 0;
  // A plan followed open loop for longer than the stale steps has drifted.
  if (plan_ && age <= config_.closed_loop.stale_plan_steps) {
    return shifted(*plan_, age, scene.steps, dt, scene.ego);
  }
  // A solve cut short by a limit goes on from where it stopped, so a hard
  // start is spread over several steps instead of starting over every step.
  const bool unfinished =
      last_.status == MpcStatus::TimeLimit || last_.status == MpcStatus::IterationLimit;
  if (unfinished && last_step_ == step - 1 && !last_.plan.controls.empty()) {
    return shifted(last_.plan, 1, scene.steps, dt, scene.ego);
  }
  return cold_guess(scene);
}

std::string MpcSession::replan(const Observation& o) {
  const Scenario scene = planner::scene_now(o, config_);
  last_ = solve_mpc(solver_, scene, config_, starting_point(o.step, scene));
  last_step_ = o.step;
  if (last_.status != MpcStatus::Solved) {
    std::string why(to_string(last_.status));
    if (!last_.message.empty()) {
      why += ": ";
      why += last_.message;
    }
    return why;
  }
  plan_ = last_.plan;
  plan_step_ = o.step;
  return "";
}

std::unique_ptr<planner::PlannerSession> MpcPlanner::start(const Scenario& /*scene*/) const {
  return std::make_unique<MpcSession>(config_);
}

std::shared_ptr<const planner::ClosedLoopPlanner> make_mpc_planner(const Config& config) {
  return std::make_shared<MpcPlanner>(config);
}

}  // namespace lanechange::baselines
