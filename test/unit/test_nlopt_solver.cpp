// The NLopt cross-check: exact gradients of the direct method (against central differences),
// and on the seed's examples a feasible first-order optimal (KKT) point.
#include <gtest/gtest.h>

#include <Eigen/QR>
#include <algorithm>
#include <memory>
#include <random>

#include "attitude_planner/io/scene.hpp"
#include "attitude_planner/planner.hpp"
#include "planning/problem/verdict.hpp"
#include "planning/transcription/direct_method.hpp"

namespace ap = attitude_planner;

namespace {

ap::PlanningProblem seedProblem(const std::string& scene, int steps, ap::SchemeKind scheme) {
  ap::PlanningProblem p = ap::loadScene(AP_SOURCE_DIR "/scenes/" + scene).problem;
  p.steps = steps;
  p.scheme = scheme;
  return p;
}

/// A problem that exercises every term: nonzero Ω_0 (F_0 ≠ I), a generic R_0 and R_N.
ap::PlanningProblem genericProblem(ap::SchemeKind scheme) {
  ap::PlanningProblem p = seedProblem("slew_up.yaml", 12, scheme);
  p.initial_attitude = ap::so3::exp(ap::Vector3(0.3, -0.7, 0.2));
  p.initial_velocity = ap::Vector3(0.2, -0.1, 0.15);
  p.final_attitude = ap::so3::exp(ap::Vector3(-1.1, 0.4, 0.9));
  return p;
}

Eigen::VectorXd randomTorques(int steps, double scale, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> normal(0.0, scale);
  Eigen::VectorXd x(3 * (steps - 1));
  for (int i = 0; i < x.size(); ++i) x(i) = normal(rng);
  return x;
}

class BothSchemes : public ::testing::TestWithParam<ap::SchemeKind> {};

}  // namespace

TEST_P(BothSchemes, CarriedMomentumJacobianMatchesCentralDifferences) {
  const ap::DiscreteScheme scheme(GetParam(), seedProblem("slew_up.yaml", 16, GetParam()).inertia,
                                  0.1);
  const ap::Matrix3 F = ap::so3::exp(ap::Vector3(0.05, -0.08, 0.11));
  const ap::Matrix3 D = ap::carriedMomentumJacobian(scheme, F);
  const double eps = 1e-6;
  for (int i = 0; i < 3; ++i) {
    const ap::Vector3 e = eps * ap::Vector3::Unit(i);
    auto G = [&](const ap::Matrix3& Fp) -> ap::Vector3 {
      return Fp.transpose() * scheme.momentum<double>(Fp);
    };
    const ap::Vector3 fd =
        (G(F * ap::so3::exp(e)) - G(F * ap::so3::exp(ap::Vector3(-e)))) / (2 * eps);
    EXPECT_LT((fd - D.col(i)).norm(), 1e-7 * D.norm()) << "column " << i;
  }
  // The transpose-and-hat term matters: dropping it is a detectable error.
  EXPECT_GT(ap::so3::hat(ap::Vector3(F.transpose() * scheme.momentum<double>(F))).norm(),
            1e-3 * D.norm());
}

TEST_P(BothSchemes, ConstraintJacobianMatchesCentralDifferences) {
  const ap::PlanningProblem p = genericProblem(GetParam());
  const Eigen::VectorXd x = randomTorques(p.steps, 0.3, 7);
  const ap::TerminalConstraints c = ap::evaluateTerminalConstraints(p, x, true);
  ASSERT_EQ(c.jacobian.rows(), 6);
  ASSERT_EQ(c.jacobian.cols(), x.size());
  const double eps = 1e-6;
  Eigen::MatrixXd fd(6, x.size());
  for (int j = 0; j < x.size(); ++j) {
    Eigen::VectorXd xp = x, xm = x;
    xp(j) += eps;
    xm(j) -= eps;
    fd.col(j) = (ap::evaluateTerminalConstraints(p, xp, false).value -
                 ap::evaluateTerminalConstraints(p, xm, false).value) /
                (2 * eps);
  }
  const double scale = fd.cwiseAbs().maxCoeff();
  EXPECT_GT(scale, 1e-3);
  EXPECT_LT((fd - c.jacobian).cwiseAbs().maxCoeff(), 1e-7 * scale)
      << "analytic\n"
      << c.jacobian.leftCols(6) << "\nfinite differences\n"
      << fd.leftCols(6);
}

TEST_P(BothSchemes, ConstraintValueIsTheReplayedTerminalMiss) {
  const ap::PlanningProblem p = genericProblem(GetParam());
  const Eigen::VectorXd x = randomTorques(p.steps, 0.3, 11);
  const ap::TerminalConstraints c = ap::evaluateTerminalConstraints(p, x, false);
  ap::PlanResult replay;
  ap::evaluatePlan(p, ap::torqueSequenceFromUnknowns(x), &replay);
  EXPECT_NEAR(c.value.head<3>().norm(), replay.terminal_attitude_error, 1e-14);
  EXPECT_NEAR(c.value.tail<3>().norm(), replay.terminal_velocity_error, 1e-14);
  EXPECT_GT(replay.terminal_attitude_error, 1e-3);  // not trivially zero
}

INSTANTIATE_TEST_SUITE_P(Schemes, BothSchemes,
                         ::testing::Values(ap::SchemeKind::Paper, ap::SchemeKind::Variational),
                         [](const auto& info) { return ap::schemeName(info.param); });

namespace {

struct SeedCase {
  const char* scene;
  int steps;
  ap::SchemeKind scheme;
};

class SeedExamples : public ::testing::TestWithParam<SeedCase> {};

/// A parameterized test's name: scene, N and scheme ("rest_to_rest_N16_paper").
std::string seedCaseName(const ::testing::TestParamInfo<SeedCase>& info) {
  const std::string scene = info.param.scene;
  return scene.substr(0, scene.find('.')) + "_N" + std::to_string(info.param.steps) + "_" +
         ap::schemeName(info.param.scheme);
}

}  // namespace

TEST_P(SeedExamples, NloptReachesAFeasibleKktPoint) {
  const SeedCase sc = GetParam();
  const ap::PlanningProblem p = seedProblem(sc.scene, sc.steps, sc.scheme);
  ap::SolverOptions options;
  options.solver = ap::SolverKind::Nlopt;
  options.max_iterations = 2000;
  const ap::PlanResult r = ap::planManeuver(p, options);
  EXPECT_TRUE(r.converged()) << r.message();
  EXPECT_EQ(r.solver, "nlopt");
  EXPECT_LE(r.terminal_attitude_error, 1e-10) << r.message();
  EXPECT_LE(r.terminal_velocity_error, 1e-10) << r.message();
  EXPECT_GT(r.cost, 0.0);

  // KKT: ∇f = τ lies in the row space of the constraint Jacobian (checked here with a QR
  // projection of our own, not the solver's residual).
  const Eigen::VectorXd x = ap::unknownsFromTorqueSequence(r.maneuver.torque);
  const Eigen::MatrixXd C = ap::evaluateTerminalConstraints(p, x, true).jacobian;
  const Eigen::HouseholderQR<Eigen::MatrixXd> qr(C.transpose());
  const Eigen::MatrixXd Q = qr.householderQ() * Eigen::MatrixXd::Identity(x.size(), 6);
  const Eigen::VectorXd outside = x - Q * (Q.transpose() * x);
  EXPECT_LT(outside.norm(), 1e-6 * x.norm()) << r.message();

  // And a small feasible-direction check: moving along the constraints' null space (then
  // re-projecting to feasibility by Gauss–Newton) never lowers the cost.
  std::mt19937 rng(3);
  std::normal_distribution<double> normal(0.0, 1.0);
  for (int trial = 0; trial < 3; ++trial) {
    Eigen::VectorXd d(x.size());
    for (int i = 0; i < d.size(); ++i) d(i) = normal(rng);
    d -= Q * (Q.transpose() * d);
    Eigen::VectorXd y = x + 1e-3 * x.norm() / d.norm() * d;
    for (int gn = 0; gn < 8; ++gn) {
      const ap::TerminalConstraints c = ap::evaluateTerminalConstraints(p, y, true);
      y -= c.jacobian.transpose() * (c.jacobian * c.jacobian.transpose()).ldlt().solve(c.value);
    }
    ASSERT_LT(ap::evaluateTerminalConstraints(p, y, false).value.norm(), 1e-11);
    EXPECT_GE(0.5 * y.squaredNorm(), r.cost * (1 - 1e-12)) << "trial " << trial;
  }
}

INSTANTIATE_TEST_SUITE_P(
    Seed, SeedExamples,
    ::testing::Values(SeedCase{"rest_to_rest.yaml", 16, ap::SchemeKind::Paper},
                      SeedCase{"rest_to_rest.yaml", 32, ap::SchemeKind::Paper},
                      SeedCase{"slew_up.yaml", 16, ap::SchemeKind::Paper},
                      SeedCase{"slew_up.yaml", 32, ap::SchemeKind::Paper},
                      SeedCase{"rest_to_rest.yaml", 16, ap::SchemeKind::Variational},
                      SeedCase{"slew_up.yaml", 16, ap::SchemeKind::Variational},
                      SeedCase{"slew_up.yaml", 32, ap::SchemeKind::Variational}),
    seedCaseName);

TEST(NloptSolver, CancellationStopsAndIsReported) {
  const ap::PlanningProblem p = seedProblem("rest_to_rest.yaml", 16, ap::SchemeKind::Paper);
  ap::SolverOptions options;
  options.solver = ap::SolverKind::Nlopt;
  int calls = 0;
  options.on_iteration = [&](const ap::IterationInfo&) { return ++calls < 3; };
  const ap::PlanResult r = ap::planManeuver(p, options);
  EXPECT_FALSE(r.converged());
  EXPECT_EQ(calls, 3);
  EXPECT_NE(r.message().find("cancelled"), std::string::npos) << r.message();
}

TEST(NloptSolver, IterationLimitIsHonoredAndNotConverged) {
  const ap::PlanningProblem p = seedProblem("slew_up.yaml", 16, ap::SchemeKind::Paper);
  ap::SolverOptions options;
  options.solver = ap::SolverKind::Nlopt;
  options.max_iterations = 3;
  const ap::PlanResult r = ap::planManeuver(p, options);
  EXPECT_FALSE(r.converged());
  EXPECT_LE(r.iterations, 3);
  EXPECT_NE(r.message().find("NLOPT_MAXEVAL_REACHED"), std::string::npos) << r.message();
}

namespace {

class CrossCheck : public ::testing::TestWithParam<SeedCase> {};

}  // namespace

// The two solvers share only the dynamics and the replay: Newton on the optimality conditions
// (newton_solver.cpp) and SLSQP on the direct method must find the same optimum.
TEST_P(CrossCheck, NewtonAndNloptAgreeOnCostAndTorques) {
  const SeedCase sc = GetParam();
  const ap::PlanningProblem p = seedProblem(sc.scene, sc.steps, sc.scheme);
  ap::SolverOptions newton_options;
  newton_options.solver = ap::SolverKind::Structured;
  const ap::PlanResult newton = ap::planManeuver(p, newton_options);
  ap::SolverOptions nlopt_options;
  nlopt_options.solver = ap::SolverKind::Nlopt;
  nlopt_options.max_iterations = 2000;
  const ap::PlanResult nlopt = ap::planManeuver(p, nlopt_options);
  ASSERT_TRUE(newton.converged()) << newton.message();
  ASSERT_TRUE(nlopt.converged()) << nlopt.message();
  EXPECT_NEAR(nlopt.cost, newton.cost, 1e-8 * newton.cost);
  double torque_scale = 0.0, torque_difference = 0.0;
  for (int k = 0; k <= p.steps; ++k) {
    torque_scale = std::max(torque_scale, newton.maneuver.torque[k].cwiseAbs().maxCoeff());
    torque_difference =
        std::max(torque_difference,
                 (newton.maneuver.torque[k] - nlopt.maneuver.torque[k]).cwiseAbs().maxCoeff());
  }
  EXPECT_LT(torque_difference, 1e-6 * torque_scale)
      << "newton cost " << newton.cost << ", nlopt cost " << nlopt.cost;
}

INSTANTIATE_TEST_SUITE_P(
    Seed, CrossCheck,
    ::testing::Values(SeedCase{"rest_to_rest.yaml", 16, ap::SchemeKind::Paper},
                      SeedCase{"rest_to_rest.yaml", 32, ap::SchemeKind::Paper},
                      SeedCase{"rest_to_rest.yaml", 64, ap::SchemeKind::Paper},
                      SeedCase{"slew_up.yaml", 16, ap::SchemeKind::Paper},
                      SeedCase{"slew_up.yaml", 32, ap::SchemeKind::Paper},
                      SeedCase{"slew_up.yaml", 64, ap::SchemeKind::Paper},
                      SeedCase{"rest_to_rest.yaml", 32, ap::SchemeKind::Variational},
                      SeedCase{"slew_up.yaml", 32, ap::SchemeKind::Variational}),
    seedCaseName);

TEST(NloptSolver, RefusesHorizonsTooLongForADenseSolverWithAReason) {
  const ap::PlanningProblem p = seedProblem("rest_to_rest.yaml", 5000, ap::SchemeKind::Paper);
  ap::SolverOptions options;
  options.solver = ap::SolverKind::Nlopt;
  // Refused before solving, as invalid input naming `steps` (a node answers INVALID_INPUT).
  try {
    ap::planManeuver(p, options);
    ADD_FAILURE() << "N = 5000 with nlopt was not refused";
  } catch (const ap::InvalidInput& e) {
    EXPECT_EQ(e.field(), "steps") << e.what();
    EXPECT_NE(std::string(e.what()).find("5000 > 1024"), std::string::npos) << e.what();
  }
}

// Effects are refused the same way (the cross-check's Jacobians have no effect torques): invalid
// input naming `solver`, not a solve that failed to converge.
TEST(NloptSolver, RefusesEffectsAsInvalidInputNamingTheSolver) {
  ap::PlanningProblem p = seedProblem("rest_to_rest.yaml", 16, ap::SchemeKind::Paper);
  auto effects = std::make_shared<ap::EffectModel>();
  effects->add(std::make_unique<ap::GravityGradient>(3.986004418e14, 7.0e6, p.inertia));
  p.effects = effects;
  ap::SolverOptions options;
  options.solver = ap::SolverKind::Nlopt;
  try {
    ap::planManeuver(p, options);
    ADD_FAILURE() << "effects with nlopt were not refused";
  } catch (const ap::InvalidInput& e) {
    EXPECT_EQ(e.field(), "solver") << e.what();
  }
}

TEST(NloptSolver, ExhaustedTimeBudgetIsNotConvergence) {
  // A budget no solve can meet (1 ns): the result must say so rather than claim convergence.
  const ap::PlanningProblem p = seedProblem("rest_to_rest.yaml", 32, ap::SchemeKind::Paper);
  ap::SolverOptions options;
  options.solver = ap::SolverKind::Nlopt;
  options.time_budget_s = 1e-9;
  const ap::PlanResult r = ap::planManeuver(p, options);
  EXPECT_FALSE(r.converged());
  EXPECT_NE(r.message().find("NLOPT_MAXTIME_REACHED"), std::string::npos) << r.message();
}
