#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <future>
#include <nlohmann/json.hpp>
#include <random>

#include "baselines/mpc.hpp"
#include "lanechange/baselines/baselines.hpp"
#include "lanechange/error.hpp"
#include "lanechange/sampler.hpp"
#include "rollout_checks.hpp"
#include "test_helpers.hpp"

namespace lanechange {
namespace {

using baselines::MpcNlp;
using sim::Outcome;

// Without a time limit, so outcomes do not depend on the machine (or the
// sanitizers' slowdown).
Config untimed_mpc_config() {
  Config config = testing::untimed_config();
  config.mpc.time_limit_ms = 1e5;
  return config;
}

// A program with cars close enough for the circle rows to matter, at a point
// off the guess so that no term vanishes.
struct ProgramAtAPoint {
  Ipopt::SmartPtr<MpcNlp> nlp = new MpcNlp;
  std::vector<double> x;
  std::vector<double> lambda;
  Ipopt::Index n = 0;
  Ipopt::Index m = 0;
  Ipopt::Index jacobian_nonzeros = 0;
  Ipopt::Index hessian_nonzeros = 0;

  ProgramAtAPoint() {
    Config config;
    Scenario s = testing::open_road_scenario();
    s.steps = 8;
    s.horizon = 0.8;
    s.follower() = {-4.0, 8.0, 0.0};
    s.target() = {9.0, 8.0, 0.0};
    s.leader() = {8.0, 7.0, 0.0};
    const baselines::MpcPlan guess = baselines::cold_guess(s);
    nlp->update(baselines::build_mpc_problem(s, config, guess), guess);
    Ipopt::TNLP::IndexStyleEnum style{};
    nlp->get_nlp_info(n, m, jacobian_nonzeros, hessian_nonzeros, style);
    x = nlp->pack(guess);
    std::mt19937 random(3);
    std::uniform_real_distribution<double> noise(-0.3, 0.3);
    for (double& value : x) value += noise(random);
    lambda.resize(static_cast<std::size_t>(m));
    for (double& value : lambda) value = noise(random) * 10.0;
  }
  double lagrangian(const std::vector<double>& at, double obj_factor) {
    double f = 0.0;
    nlp->eval_f(n, at.data(), true, f);
    std::vector<double> g(static_cast<std::size_t>(m));
    nlp->eval_g(n, at.data(), true, m, g.data());
    double total = obj_factor * f;
    for (std::size_t i = 0; i < g.size(); ++i) total += lambda[i] * g[i];
    return total;
  }
  std::vector<double> lagrangian_gradient(const std::vector<double>& at, double obj_factor) {
    std::vector<double> grad(static_cast<std::size_t>(n));
    nlp->eval_grad_f(n, at.data(), true, grad.data());
    for (double& value : grad) value *= obj_factor;
    std::vector<Ipopt::Index> rows(static_cast<std::size_t>(jacobian_nonzeros));
    std::vector<Ipopt::Index> cols(rows.size());
    std::vector<double> values(rows.size());
    nlp->eval_jac_g(n, nullptr, true, m, jacobian_nonzeros, rows.data(), cols.data(), nullptr);
    nlp->eval_jac_g(n, at.data(), true, m, jacobian_nonzeros, nullptr, nullptr, values.data());
    for (std::size_t e = 0; e < values.size(); ++e) grad[cols[e]] += lambda[rows[e]] * values[e];
    return grad;
  }
};

TEST(Mpc, DerivativesMatchFiniteDifferences) {
  ProgramAtAPoint p;
  ASSERT_GT(p.m, 4 * 8 + 2);  // circle rows are present
  constexpr double kStep = 1e-6;
  // The Lagrangian's gradient (with the Jacobian) against central differences.
  const double obj_factor = 0.7;
  const std::vector<double> grad = p.lagrangian_gradient(p.x, obj_factor);
  for (Ipopt::Index j = 0; j < p.n; ++j) {
    auto up = p.x, down = p.x;
    up[j] += kStep;
    down[j] -= kStep;
    const double fd = (p.lagrangian(up, obj_factor) - p.lagrangian(down, obj_factor)) / (2 * kStep);
    EXPECT_NEAR(grad[j], fd, 1e-5 * (1.0 + std::abs(fd))) << "variable " << j;
  }
  // The Hessian of the Lagrangian against differences of its gradient.
  std::vector<Ipopt::Index> rows(static_cast<std::size_t>(p.hessian_nonzeros));
  std::vector<Ipopt::Index> cols(rows.size());
  std::vector<double> values(rows.size());
  p.nlp->eval_h(p.n, nullptr, true, obj_factor, p.m, nullptr, true, p.hessian_nonzeros, rows.data(),
                cols.data(), nullptr);
  p.nlp->eval_h(p.n, p.x.data(), true, obj_factor, p.m, p.lambda.data(), true, p.hessian_nonzeros,
                nullptr, nullptr, values.data());
  std::vector<std::vector<double>> dense(p.n, std::vector<double>(p.n, 0.0));
  for (std::size_t e = 0; e < values.size(); ++e) {
    ASSERT_GE(rows[e], cols[e]) << "the lower triangle only";
    dense[rows[e]][cols[e]] += values[e];
  }
  for (Ipopt::Index j = 0; j < p.n; ++j) {
    auto up = p.x, down = p.x;
    up[j] += kStep;
    down[j] -= kStep;
    const auto g_up = p.lagrangian_gradient(up, obj_factor);
    const auto g_down = p.lagrangian_gradient(down, obj_factor);
    for (Ipopt::Index i = j; i < p.n; ++i) {
      const double fd = (g_up[i] - g_down[i]) / (2 * kStep);
      EXPECT_NEAR(dense[i][j], fd, 1e-4 * (1.0 + std::abs(fd))) << i << ", " << j;
    }
  }
}

// A rollout of the MPC, checked for consistency.
sim::Rollout consistent_rollout(const Scenario& s) {
  const Config config = untimed_mpc_config();
  const auto mpc = baselines::make_planner("mpc", config);
  sim::Rollout r = sim::simulate(s, *mpc, config);
  testing::expect_consistent(r, s);
  return r;
}

TEST(Mpc, ChangesLanesIntoAWideOpenGap) {
  const sim::Rollout r = consistent_rollout(testing::open_road_scenario());
  EXPECT_EQ(r.outcome, Outcome::WellPosed) << r.reason;
  EXPECT_FALSE(r.trajectory.collision);
  EXPECT_GT(r.manoeuvre_over_at, 0.0);
  EXPECT_EQ(r.metrics.fallbacks, 0);
}

// Two threads' rollouts must not wait for each other's Ipopt solves inside
// their timed steps: a second thread's session waits at its start until
// the first session ends. One thread's own sessions do not wait for
// themselves.
TEST(Mpc, SessionsOnOtherThreadsWaitForTheirTurnAtTheStart) {
  const Config config = untimed_mpc_config();
  const auto mpc = baselines::make_planner("mpc", config);
  const Scenario scene = testing::open_road_scenario();
  auto first = mpc->start(scene);
  auto nested = mpc->start(scene);  // the same thread: no deadlock
  std::atomic<bool> started{false};
  auto other = std::async(std::launch::async, [&] {
    const auto session = mpc->start(scene);
    started = true;
  });
  EXPECT_EQ(other.wait_for(std::chrono::milliseconds(100)), std::future_status::timeout);
  EXPECT_FALSE(started);
  nested.reset();
  EXPECT_EQ(other.wait_for(std::chrono::milliseconds(50)), std::future_status::timeout);
  first.reset();
  other.get();
  EXPECT_TRUE(started);
}

TEST(Mpc, StaysInItsLaneWithoutCollisionWhereThereIsNoGap) {
  const sim::Rollout r = consistent_rollout(testing::no_gap_scenario());
  EXPECT_EQ(r.outcome, Outcome::Aborted) << r.reason;
  EXPECT_FALSE(r.trajectory.collision);
  EXPECT_GT(r.metrics.fallbacks, 0);
}

// A truck's circles are wider and reach further along the lane than a car's.
TEST(Mpc, ATrucksCirclesKeepTheirOwnClearance) {
  const Config config;
  Scenario s = testing::open_road_scenario();
  s.leader() = {12.0, 8.0, 0.0};
  const baselines::MpcPlan guess = baselines::cold_guess(s);
  const auto car = baselines::build_mpc_problem(s, config, guess);
  s.cars[car_of(Role::Leader)].size = VehicleSize{12.0, 2.5};
  const auto truck = baselines::build_mpc_problem(s, config, guess);
  const auto widest = [](const baselines::MpcProblemData& d) {
    double out = 0.0;
    for (const auto& node : d.obstacles) {
      for (const auto& c : node) out = std::max(out, c.clearance);
    }
    return out;
  };
  EXPECT_GT(widest(truck), widest(car));
  const auto reach = [](const baselines::MpcProblemData& d) {
    double out = 0.0;
    for (const auto& node : d.obstacles) {
      for (const auto& c : node) {
        if (c.y == 0.0) out = std::max(out, c.x - node.front().x);
      }
    }
    return out;
  };
  EXPECT_GT(reach(truck), reach(car));
  // The ego's own circles are the same either way.
  EXPECT_EQ(truck.ego_offsets, car.ego_offsets);
  EXPECT_DOUBLE_EQ(truck.ego_radius, car.ego_radius);
}

TEST(Mpc, SampledRolloutsAreConsistent) {
  const ScenarioSampler sampler(untimed_mpc_config(), 5);
  for (std::uint64_t i = 0; i < 3; ++i) {
    const Scenario s = sampler.sample(i);
    SCOPED_TRACE("scenario " + std::to_string(i));
    (void)consistent_rollout(s);
  }
}

TEST(Mpc, ASolveFromTheShiftedSolutionIsFasterThanFromScratch) {
  const Config config = untimed_mpc_config();
  Scenario s = testing::open_road_scenario();
  baselines::MpcSolver solver(config.mpc);
  const baselines::MpcPlan cold = baselines::cold_guess(s);
  const auto first = baselines::solve_mpc(solver, s, config, cold);
  ASSERT_EQ(first.status, baselines::MpcStatus::Solved) << first.message;
  s.ego = step_exact(s.ego, first.plan.controls[0], config.dt());
  for (CarIndex c = 0; c < 3; ++c) s.car(c).x += s.car(c).v * config.dt();
  const auto warm = baselines::shifted(first.plan, 1, s.steps, config.dt(), s.ego);
  const auto second = baselines::solve_mpc(solver, s, config, warm);
  ASSERT_EQ(second.status, baselines::MpcStatus::Solved) << second.message;
  EXPECT_LT(second.iterations, first.iterations);
}

TEST(Mpc, ConfigRoundTripsAndRejectsBadValues) {
  Config config;
  config.mpc.circles = 4;
  config.mpc.margin = 0.5;
  nlohmann::json j = config;
  EXPECT_EQ(config_from_json(j).mpc.circles, 4);
  EXPECT_EQ(config_from_json(j).mpc.margin, 0.5);
  for (const char* bad : {R"({"mpc": {"circles": 0}})", R"({"mpc": {"margin": -1}})",
                          R"({"mpc": {"time_limit_ms": 0}})", R"({"mpc": {"tolerance": 0}})",
                          R"({"mpc": {"max_iterations": 0}})", R"({"mpc": {"circle": 3}})"}) {
    EXPECT_THROW((void)config_from_json(nlohmann::json::parse(bad)), InputError) << bad;
  }
}

}  // namespace
}  // namespace lanechange
