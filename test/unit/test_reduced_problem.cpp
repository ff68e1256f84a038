// The reduced problem's gradient and exact Hessian against finite differences of its cost.
#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <random>

#include "attitude_planner/reduced_problem.hpp"

using namespace attitude_planner;

namespace {

PlanningProblem randomProblem(SchemeKind scheme, int N) {
  PlanningProblem p;
  p.inertia << 13.25, -7.80, -11.40, -7.80, 16.25, 4.71, -11.40, 4.71, 18.37;
  p.allow_nonphysical_inertia = true;
  p.duration = 6.0;
  p.steps = N;
  p.initial_velocity = Vector3(0.1, -0.2, 0.3);
  p.final_attitude = so3::fromAxisAngle(Vector3(1, 2, 3), 2.0);
  p.final_velocity = Vector3(0.3, 0.2, -0.1);
  p.scheme = scheme;
  return p;
}

// With effects strong enough to matter against the control torques (T = 6 s): a fast "orbit".
PlanningProblem withEffects(PlanningProblem p) {
  auto model = std::make_shared<EffectModel>();
  model->add(std::make_unique<GravityGradient>(1.0, 1.0, p.inertia));  // n = 1 rad/s
  model->add(std::make_unique<DisturbanceTorque>(Vector3(0.5, -0.2, 0.3), true));
  p.effects = model;
  return p;
}

// Interior attitudes moved off the geodesic, so torques and curvature are generic.
ReducedProblem perturbedProblem(SchemeKind scheme, int N, unsigned seed, bool effects = false) {
  ReducedProblem rp(effects ? withEffects(randomProblem(scheme, N)) : randomProblem(scheme, N));
  std::mt19937 rng(seed);
  std::normal_distribution<double> n(0.0, 0.05);
  Eigen::VectorXd delta(rp.unknowns());
  for (int i = 0; i < delta.size(); ++i) delta(i) = n(rng);
  rp.setCurrent(rp.retract(delta, 1.0));
  return rp;
}

}  // namespace

TEST(ReducedProblem, GradientMatchesFiniteDifferencesOfTheCost) {
  for (SchemeKind scheme : {SchemeKind::Paper, SchemeKind::Variational}) {
    for (bool effects : {false, true}) {
      const ReducedProblem rp = perturbedProblem(scheme, 9, 1, effects);
      Eigen::VectorXd g;
      double scale;
      const double c = rp.evaluate(&g, nullptr, &scale);
      EXPECT_NEAR(c, rp.cost(rp.current()), 1e-12 * c);
      const double eps = 1e-6;
      for (int i = 0; i < rp.unknowns(); ++i) {
        Eigen::VectorXd e = Eigen::VectorXd::Zero(rp.unknowns());
        e(i) = eps;
        const double fd = (rp.cost(rp.retract(e, 1.0)) - rp.cost(rp.retract(e, -1.0))) / (2 * eps);
        EXPECT_NEAR(g(i), fd, 1e-6 * g.cwiseAbs().maxCoeff())
            << schemeName(scheme) << " effects " << effects << " i = " << i;
      }
    }
  }
}

TEST(ReducedProblem, HessianMatchesSecondDifferencesOfTheCost) {
  // Second differences of δ ↦ C(R exp δ) along pairs of unit directions: the exact Hessian of
  // the retracted cost, independent of how evaluate() assembles it.
  for (SchemeKind scheme : {SchemeKind::Paper, SchemeKind::Variational}) {
    for (bool effects : {false, true}) {
      const ReducedProblem rp = perturbedProblem(scheme, 8, 2, effects);
      const int n = rp.unknowns();
      Eigen::VectorXd g;
      double scale;
      BandedSymmetricMatrix H(n, 8);
      rp.evaluate(&g, &H, &scale);
      const Eigen::MatrixXd dense = H.toDense();
      const double eps = 1e-4;
      const auto C = [&](const Eigen::VectorXd& d) { return rp.cost(rp.retract(d, 1.0)); };
      double worst = 0;
      for (int i = 0; i < n; ++i) {
        for (int j = 0; j < n; ++j) {
          Eigen::VectorXd ei = Eigen::VectorXd::Zero(n), ej = Eigen::VectorXd::Zero(n);
          ei(i) = eps;
          ej(j) = eps;
          const double fd = (C(ei + ej) - C(ei - ej) - C(ej - ei) + C(-ei - ej)) / (4 * eps * eps);
          worst = std::max(worst, std::abs(fd - dense(i, j)));
        }
      }
      EXPECT_LE(worst, 1e-5 * dense.cwiseAbs().maxCoeff())
          << schemeName(scheme) << " effects " << effects;
    }
  }
}

TEST(ReducedProblem, BandedCholeskyMatchesDenseSolve) {
  const ReducedProblem rp = perturbedProblem(SchemeKind::Paper, 12, 3);
  Eigen::VectorXd g;
  double scale;
  BandedSymmetricMatrix H(rp.unknowns(), 8);
  rp.evaluate(&g, &H, &scale);
  // shift by the most negative eigenvalue (away from optima the Hessian may be indefinite)
  const double lowest =
      Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(H.toDense()).eigenvalues()(0);
  H.addToDiagonal(std::max(0.0, -lowest) + 1e-3 * H.maxAbsDiagonal());
  Eigen::VectorXd x = g;
  ASSERT_TRUE(H.solvePositiveDefinite(&x));
  const Eigen::VectorXd dense = H.toDense().ldlt().solve(g);
  EXPECT_LE((x - dense).norm(), 1e-10 * dense.norm());
  // an indefinite matrix is refused
  BandedSymmetricMatrix indefinite(3, 1);
  indefinite.add(0, 0, 1.0);
  indefinite.add(1, 1, -1.0);
  indefinite.add(2, 2, 1.0);
  Eigen::VectorXd b = Eigen::VectorXd::Ones(3);
  EXPECT_FALSE(indefinite.solvePositiveDefinite(&b));
}

TEST(BandedLinearSystem, PivotedLuMatchesDenseSolveOnAnIndefiniteMatrix) {
  std::mt19937 rng(5);
  std::normal_distribution<double> n(0.0, 1.0);
  const int size = 40, p = 5;
  BandedLinearSystem A(size, p);
  Eigen::MatrixXd dense = Eigen::MatrixXd::Zero(size, size);
  for (int i = 0; i < size; ++i) {
    for (int j = std::max(0, i - p); j <= std::min(size - 1, i + p); ++j) {
      // zero diagonal in places: pivoting is required
      const double v = (i == j && i % 3 == 0) ? 0.0 : n(rng);
      A.add(i, j, v);
      dense(i, j) = v;
    }
  }
  Eigen::VectorXd b(size);
  for (int i = 0; i < size; ++i) b(i) = n(rng);
  Eigen::VectorXd x = b;
  ASSERT_TRUE(A.solve(&x));
  const Eigen::VectorXd reference = dense.fullPivLu().solve(b);
  EXPECT_LE((x - reference).norm(), 1e-10 * reference.norm());
  BandedLinearSystem singular(3, 1);
  Eigen::VectorXd c = Eigen::VectorXd::Ones(3);
  EXPECT_FALSE(singular.solve(&c));
}
