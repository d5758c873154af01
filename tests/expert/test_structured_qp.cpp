// The Riccati interior-point method on random stage-structured QPs, and the
// dual bound behind its objective cutoff: the bound must never pass the
// optimum, and it must end solves whose optimum is far above the cutoff.
#include <gtest/gtest.h>

#include <random>

#include "lanechange/expert/structured_qp.hpp"

namespace lc = lanechange::expert;

namespace {

constexpr int kSteps = 30;

// A stable random system with box controls, soft state rows and a terminal
// equality; its cost has curvature `curvature` in the controls alone.
lc::StructuredQp random_qp(unsigned seed, const Eigen::Vector2d& curvature, bool feasible) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  auto random = [&](auto& matrix, double scale) {
    for (int i = 0; i < matrix.rows(); ++i)
      for (int j = 0; j < matrix.cols(); ++j) matrix(i, j) = scale * normal(rng);
  };
  lc::StructuredQp qp;
  qp.stages.resize(kSteps + 1);
  random(qp.initial_state, 1.0);
  for (int k = 0; k <= kSteps; ++k) {
    lc::QpStage& st = qp.stages[k];
    st.A = 0.9 * Eigen::Matrix<double, 5, 5>::Identity();
    Eigen::Matrix<double, 5, 5> drift;
    random(drift, 0.05);
    st.A += drift;
    random(st.B, 0.3);
    random(st.c, 0.05);
    Eigen::Matrix<double, lc::kQpStage, lc::kQpStage> root;
    random(root, 0.5);
    root.rightCols<2>().setZero();  // keep the control-only curvature exactly `curvature`
    st.H = root.transpose() * root;
    st.H.topLeftCorner<5, 5>() += 0.1 * Eigen::Matrix<double, 5, 5>::Identity();
    if (k < kSteps) {
      st.H(5, 5) += curvature[0];
      st.H(6, 6) += curvature[1];
      st.control_curvature = curvature;
      for (int c = 0; c < 2; ++c) {
        lc::QpRow upper, lower;
        upper.g[5 + c] = 1.0;
        upper.d = 1.0;
        lower.g[5 + c] = -1.0;
        lower.d = 1.0;
        st.rows.push_back(upper);
        st.rows.push_back(lower);
      }
    }
    random(st.h, 1.0);
    lc::QpRow state_row;
    random(state_row.g, 1.0);
    state_row.g.tail<2>().setZero();
    state_row.d = feasible ? 20.0 + std::abs(normal(rng)) : -200.0;
    state_row.soft = true;
    if (k > 0) st.rows.push_back(state_row);
  }
  qp.has_terminal_equality = true;
  qp.terminal_g[1] = 1.0;
  qp.terminal_d = 0.5;
  return qp;
}

lc::QpResult solve(const lc::StructuredQp& qp, double cutoff) {
  lc::QpWorkspace ws;
  ws.setup(qp);
  lc::QpSettings settings;
  settings.objective_cutoff = cutoff;
  return lc::solve_structured_qp(qp, ws, settings);
}

}  // namespace

TEST(StructuredQp, CutoffAboveTheOptimumNeverStopsTheSolve) {
  for (unsigned seed = 1; seed <= 20; ++seed) {
    for (const Eigen::Vector2d& curvature :
         {Eigen::Vector2d(0.0, 0.0), Eigen::Vector2d(0.5, 1e-6)}) {
      const lc::StructuredQp qp = random_qp(seed, curvature, true);
      const lc::QpResult exact = solve(qp, std::numeric_limits<double>::infinity());
      ASSERT_EQ(exact.status, lc::QpStatus::Optimal) << "seed " << seed;
      const lc::QpResult bounded =
          solve(qp, exact.objective + 1e-7 * (1.0 + std::abs(exact.objective)));
      EXPECT_EQ(bounded.status, lc::QpStatus::Optimal) << "seed " << seed;
      EXPECT_NEAR(bounded.objective, exact.objective, 1e-8 * (1.0 + std::abs(exact.objective)));
      EXPECT_LE(bounded.lower_bound, exact.objective + 1e-9 * (1.0 + std::abs(exact.objective)));
    }
  }
}

TEST(StructuredQp, CutoffFarBelowTheOptimumEndsTheSolveEarly) {
  for (unsigned seed = 1; seed <= 20; ++seed) {
    const lc::StructuredQp qp = random_qp(seed, {0.5, 1e-6}, true);
    const lc::QpResult exact = solve(qp, std::numeric_limits<double>::infinity());
    ASSERT_EQ(exact.status, lc::QpStatus::Optimal);
    const double cutoff = exact.objective - 0.2 * std::abs(exact.objective) - 1.0;
    const lc::QpResult bounded = solve(qp, cutoff);
    EXPECT_EQ(bounded.status, lc::QpStatus::Cutoff) << "seed " << seed;
    EXPECT_GE(bounded.lower_bound, cutoff);
    EXPECT_LT(bounded.iterations, exact.iterations) << "seed " << seed;
  }
}

TEST(StructuredQp, RowsThatCannotHoldAreInfeasibleOrCutOff) {
  for (unsigned seed = 1; seed <= 10; ++seed) {
    const lc::StructuredQp qp = random_qp(seed, {0.5, 1e-6}, false);
    EXPECT_EQ(solve(qp, std::numeric_limits<double>::infinity()).status, lc::QpStatus::Infeasible);
    const lc::QpResult bounded = solve(qp, 1e3);
    EXPECT_TRUE(bounded.status == lc::QpStatus::Cutoff ||
                bounded.status == lc::QpStatus::Infeasible);
  }
}

TEST(StructuredQp, CoarseStopComesEarlyAndCloseToTheOptimum) {
  for (unsigned seed = 1; seed <= 20; ++seed) {
    const lc::StructuredQp qp = random_qp(seed, {0.5, 1e-6}, true);
    const lc::QpResult exact = solve(qp, std::numeric_limits<double>::infinity());
    ASSERT_EQ(exact.status, lc::QpStatus::Optimal);
    lc::QpWorkspace ws;
    ws.setup(qp);
    lc::QpSettings settings;
    settings.coarse_below = exact.objective + 1.0 + std::abs(exact.objective);
    const lc::QpResult coarse = lc::solve_structured_qp(qp, ws, settings);
    EXPECT_EQ(coarse.status, lc::QpStatus::Coarse) << "seed " << seed;
    EXPECT_LT(coarse.iterations, exact.iterations) << "seed " << seed;
    // The stop bounds the mean complementarity product, so the gap to the
    // optimum is about that bound times the number of products.
    double products = 0.0;
    for (const auto& stage : qp.stages) {
      for (const auto& row : stage.rows) products += row.soft ? 2.0 : 1.0;
    }
    EXPECT_NEAR(coarse.objective, exact.objective, settings.coarse_tolerance * products)
        << "seed " << seed;
    // Below the optimum nothing qualifies: the solve runs to the end.
    settings.coarse_below = exact.objective - 1.0 - std::abs(exact.objective);
    EXPECT_EQ(lc::solve_structured_qp(qp, ws, settings).status, lc::QpStatus::Optimal);
  }
}

// A successive linearization's next round: the same rows, slightly moved
// costs and dynamics. Started from the last solution, the method lands on
// the cold start's optimum.
TEST(StructuredQp, AWarmStartReachesTheColdOptimum) {
  int fewer = 0;
  for (unsigned seed = 1; seed <= 20; ++seed) {
    const lc::StructuredQp qp = random_qp(seed, {0.5, 1e-6}, true);
    lc::StructuredQp next = qp;
    for (auto& stage : next.stages) {
      stage.h *= 1.05;
      stage.c *= 0.95;
    }
    lc::QpWorkspace ws;
    ws.setup(qp);
    ASSERT_EQ(lc::solve_structured_qp(qp, ws, {}).status, lc::QpStatus::Optimal);
    ws.setup(next);
    lc::QpSettings warm;
    warm.warm_start = true;
    const lc::QpResult from_last = lc::solve_structured_qp(next, ws, warm);
    const lc::QpResult cold = solve(next, std::numeric_limits<double>::infinity());
    ASSERT_EQ(from_last.status, lc::QpStatus::Optimal) << "seed " << seed;
    EXPECT_NEAR(from_last.objective, cold.objective, 1e-7 * (1.0 + std::abs(cold.objective)))
        << "seed " << seed;
    fewer += from_last.iterations < cold.iterations ? 1 : 0;
  }
  EXPECT_GE(fewer, 10);  // most of them
}

// A re-plan a step on: the same problem without its first stage, from the
// state the last solution reached there. Advanced by that stage, the warm
// start lines each stage up with the one of the last solution that now lies
// there, and lands on the cold start's optimum, mostly sooner. A stage whose
// rows changed starts centred.
TEST(StructuredQp, AWarmStartAStageOnReachesTheColdOptimum) {
  int fewer = 0;
  for (unsigned seed = 1; seed <= 20; ++seed) {
    const lc::StructuredQp qp = random_qp(seed, {0.5, 1e-6}, true);
    lc::QpWorkspace ws;
    ws.setup(qp);
    ASSERT_EQ(lc::solve_structured_qp(qp, ws, {}).status, lc::QpStatus::Optimal);
    lc::StructuredQp next = qp;
    next.stages.erase(next.stages.begin());
    next.initial_state = ws.solution()[1].head<lc::kQpStates>();
    if (seed % 2 == 0) {  // a changed stage: one more row at stage 3
      lc::QpRow extra = next.stages[3].rows.back();
      extra.d += 5.0;
      next.stages[3].rows.push_back(extra);
    }
    std::vector<Eigen::Vector2d> controls;
    for (int k = 1; k < kSteps; ++k) controls.emplace_back(ws.solution()[k].tail<2>());
    ws.advance(1);
    ws.setup(next);
    ws.set_initial_controls(controls);
    lc::QpSettings warm;
    warm.warm_start = true;
    const lc::QpResult from_last = lc::solve_structured_qp(next, ws, warm);
    lc::QpWorkspace cold_ws;  // the same controls, no multipliers
    cold_ws.setup(next);
    cold_ws.set_initial_controls(controls);
    const lc::QpResult cold = lc::solve_structured_qp(next, cold_ws, {});
    ASSERT_EQ(from_last.status, lc::QpStatus::Optimal) << "seed " << seed;
    EXPECT_NEAR(from_last.objective, cold.objective, 1e-7 * (1.0 + std::abs(cold.objective)))
        << "seed " << seed;
    fewer += from_last.iterations < cold.iterations ? 1 : 0;
  }
  EXPECT_GE(fewer, 15);
}

// The two forms of the Riccati recursion solve the same Newton systems, so
// they reach the same optimum; the Schur form falls back on the square-root
// form where it loses definiteness, so it never fails where that one holds.
TEST(StructuredQp, BothRiccatiFormsReachTheSameOptimum) {
  for (unsigned seed = 1; seed <= 20; ++seed) {
    for (const double accel_curvature : {0.5, 2.0}) {
      const lc::StructuredQp qp =
          random_qp(seed, {accel_curvature, accel_curvature == 2.0 ? 2.0 : 1e-6}, true);
      lc::QpResult result[2];
      int i = 0;
      for (const lc::RiccatiForm form : {lc::RiccatiForm::Schur, lc::RiccatiForm::SquareRoot}) {
        lc::QpWorkspace ws;
        ws.setup(qp);
        lc::QpSettings settings;
        settings.riccati = form;
        result[i++] = lc::solve_structured_qp(qp, ws, settings);
      }
      ASSERT_EQ(result[1].status, lc::QpStatus::Optimal) << "seed " << seed;
      EXPECT_EQ(result[0].status, result[1].status) << "seed " << seed;
      EXPECT_NEAR(result[0].objective, result[1].objective,
                  1e-7 * (1.0 + std::abs(result[1].objective)))
          << "seed " << seed;
      EXPECT_NEAR(result[0].iterations, result[1].iterations, 2) << "seed " << seed;
    }
  }
}

namespace {

// random_qp's problem with the lane-change dynamics' pattern (KinematicDynamics).
lc::StructuredQp random_kinematic_qp(unsigned seed) {
  lc::StructuredQp qp = random_qp(seed, {1.0, 1.0}, true);
  std::mt19937 rng(seed + 1000);
  std::uniform_real_distribution<double> coefficient(-0.3, 0.3);
  for (lc::QpStage& st : qp.stages) {
    st.A.setIdentity();
    st.A(4, 4) = 0.0;
    st.A.block<2, 2>(0, 2) << coefficient(rng), coefficient(rng), coefficient(rng),
        coefficient(rng);
    st.B.setZero();
    st.B.topRows<2>() << coefficient(rng), coefficient(rng), coefficient(rng), coefficient(rng);
    st.B(2, 0) = 0.1;
    st.B(3, 1) = 0.1;
    st.B(4, 0) = 1.0;
  }
  return qp;
}

}  // namespace

TEST(StructuredQp, KinematicFormFindsTheLaneChangePatternOnly) {
  lc::StructuredQp qp = random_kinematic_qp(3);
  lc::KinematicDynamics d;
  ASSERT_TRUE(lc::kinematic_form(qp.stages[0].A, qp.stages[0].B, d));
  EXPECT_EQ(d.x_theta, qp.stages[0].A(0, 3));
  EXPECT_EQ(d.y_omega, qp.stages[0].B(1, 1));
  EXPECT_EQ(d.memory_a, 1.0);
  Eigen::Matrix<double, 5, 5> A = qp.stages[0].A;
  A(2, 3) = 1e-9;  // theta would drive v
  EXPECT_FALSE(lc::kinematic_form(A, qp.stages[0].B, d));
  Eigen::Matrix<double, 5, 2> B = qp.stages[0].B;
  B(2, 1) = -1e-9;  // the yaw rate would drive v
  EXPECT_FALSE(lc::kinematic_form(qp.stages[0].A, B, d));
}

TEST(StructuredQp, KinematicSparsityTakesTheDenseSteps) {
  for (unsigned seed = 1; seed <= 20; ++seed) {
    const lc::StructuredQp qp = random_kinematic_qp(seed);
    lc::QpResult result[2];
    std::vector<lc::QpStageVector> solution[2];
    for (int sparse = 0; sparse < 2; ++sparse) {
      lc::QpWorkspace ws;
      ws.setup(qp);
      lc::QpSettings settings;
      settings.kinematic_sparsity = sparse == 1;
      result[sparse] = lc::solve_structured_qp(qp, ws, settings);
      solution[sparse] = ws.solution();
    }
    ASSERT_EQ(result[0].status, lc::QpStatus::Optimal) << "seed " << seed;
    EXPECT_EQ(result[1].status, result[0].status) << "seed " << seed;
    // The same steps up to rounding: a last step may fall either side of a tolerance.
    EXPECT_NEAR(result[1].iterations, result[0].iterations, 1) << "seed " << seed;
    EXPECT_NEAR(result[1].objective, result[0].objective,
                1e-9 * (1.0 + std::abs(result[0].objective)))
        << "seed " << seed;
    for (std::size_t k = 0; k < solution[0].size(); ++k) {
      EXPECT_LT((solution[1][k] - solution[0][k]).cwiseAbs().maxCoeff(), 1e-7)
          << "seed " << seed << ", stage " << k;
    }
  }
}
