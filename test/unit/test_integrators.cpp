// Integrators: each scheme satisfies its defining equations, Jacobians match finite
// differences, long runs stay on SO(3) and conserve what they should.
#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include <Eigen/SVD>

#include "attitude_planner/dynamics/simulation.hpp"
#include "attitude_planner/errors.hpp"
#include "dynamics/principal_branch.hpp"
#include "support/robustness_cases.hpp"

using namespace attitude_planner;

namespace {

const Matrix3 kSeedInertia = robustness::seedInertia();

std::vector<Vector3> randomTorques(int N, double scale, unsigned seed) {
  std::mt19937 rng(seed);
  std::normal_distribution<double> n(0.0, scale);
  std::vector<Vector3> torque(N + 1, Vector3::Zero());
  for (int k = 1; k < N; ++k) torque[k] = Vector3(n(rng), n(rng), n(rng));
  return torque;
}

Maneuver run(SchemeKind kind, const Matrix3& J, double h, const Vector3& omega0,
             const std::vector<Vector3>& torque, const Matrix3& R0 = Matrix3::Identity()) {
  SimulationInput input;
  input.initial_attitude = R0;
  input.initial_velocity = omega0;
  input.torque = torque;
  return simulate(DiscreteScheme(kind, J, h), input);
}

double energy(const Maneuver& m, const Matrix3& J, int k) {
  return 0.5 * m.angular_velocity[k].dot(J * m.angular_velocity[k]);
}

}  // namespace

TEST(Integrators, PaperStepSatisfiesSeedEquation18) {
  // J Ω_k = exp(hΩ_k)ᵀ (h τ_k + J Ω_{k−1}) and R_{k+1} = R_k exp(hΩ_k), literally.
  const double h = 0.1;
  const auto torque = randomTorques(50, 2.0, 1);
  const Maneuver m = run(SchemeKind::Paper, kSeedInertia, h, Vector3(0.2, -0.1, 0.3), torque);
  for (int k = 1; k < 50; ++k) {
    const Vector3& w = m.angular_velocity[k];
    const Vector3 lhs = kSeedInertia * w;
    const Vector3 rhs = so3::exp(Vector3(h * w)).transpose() *
                        (h * torque[k] + kSeedInertia * m.angular_velocity[k - 1]);
    EXPECT_LE((lhs - rhs).norm(), 1e-13 * lhs.norm() + 1e-15) << "k = " << k;
    EXPECT_LE((m.attitude[k + 1] - m.attitude[k] * so3::exp(Vector3(h * w))).norm(), 1e-14);
  }
}

TEST(Integrators, VariationalStepSatisfiesLeeLeokMcClamrochEquations) {
  // h (JΩ_k)^ = F_k J_d − J_d F_kᵀ,  J Ω_k = F_{k−1}ᵀ J Ω_{k−1} + h τ_k,  R_{k+1} = R_k F_k.
  const double h = 0.1;
  const Matrix3 Jd = 0.5 * kSeedInertia.trace() * Matrix3::Identity() - kSeedInertia;
  const auto torque = randomTorques(50, 2.0, 2);
  const Maneuver m = run(SchemeKind::Variational, kSeedInertia, h, Vector3(0.2, -0.1, 0.3), torque);
  for (int k = 0; k < 50; ++k) {
    const Matrix3 F = m.attitude[k].transpose() * m.attitude[k + 1];
    const Vector3 Pi = kSeedInertia * m.angular_velocity[k];
    EXPECT_LE((h * so3::hat(Pi) - (F * Jd - Jd * F.transpose())).norm(), 1e-13) << "k = " << k;
    if (k > 0) {
      const Matrix3 F_prev = m.attitude[k - 1].transpose() * m.attitude[k];
      const Vector3 expected =
          F_prev.transpose() * kSeedInertia * m.angular_velocity[k - 1] + h * torque[k];
      EXPECT_LE((Pi - expected).norm(), 1e-12 * Pi.norm()) << "k = " << k;
    }
  }
}

// The paper step's Newton iteration forms its Jacobian's Jr⁻¹ coefficient from the log's own
// quaternion, and keeps one Jacobian for both polishing steps. A wrong Jacobian still converges,
// but linearly: from a guess 1e-3 rad off, quadratic steps reach the tolerance within four
// steps (then two polishing ones), at angles from the series' range to near π.
TEST(Integrators, PaperStepSolveConvergesQuadraticallyAtEveryAngle) {
  const double h = 0.1;
  const DiscreteScheme scheme(SchemeKind::Paper, kSeedInertia, h);
  std::mt19937 rng(7);
  std::normal_distribution<double> n(0.0, 1.0);
  for (double angle : {1e-6, 5e-5, 2e-4, 1e-2, 0.3, 1.5, 2.5, 3.1}) {
    for (int trial = 0; trial < 5; ++trial) {
      const Matrix3 F = so3::exp(Vector3(angle * Vector3(n(rng), n(rng), n(rng)).normalized()));
      const Matrix3 guess =
          F * so3::exp(Vector3(1e-3 * Vector3(n(rng), n(rng), n(rng)).normalized()));
      StepSolveReport report;
      const Matrix3 solved = scheme.solveStep(scheme.momentum<double>(F), guess, &report);
      EXPECT_TRUE(report.converged) << "angle " << angle;
      EXPECT_LE(report.iterations, 6) << "angle " << angle;
      EXPECT_LE(so3::angleBetween(solved, F), 1e-12) << "angle " << angle;
    }
  }
}

TEST(Integrators, MomentumJacobianMatchesFiniteDifferences) {
  std::mt19937 rng(4);
  std::normal_distribution<double> n(0.0, 1.0);
  for (SchemeKind kind : {SchemeKind::Paper, SchemeKind::Variational}) {
    const DiscreteScheme scheme(kind, kSeedInertia, 0.05);
    for (int trial = 0; trial < 20; ++trial) {
      const Matrix3 F = so3::exp(Vector3(0.3 * Vector3(n(rng), n(rng), n(rng))));
      const Matrix3 D = scheme.momentumJacobian<double>(F);
      const double eps = 1e-6;
      for (int i = 0; i < 3; ++i) {
        const Vector3 e = eps * Vector3::Unit(i);
        const Vector3 fd = (scheme.momentum<double>(Matrix3(F * so3::exp(e))) -
                            scheme.momentum<double>(Matrix3(F * so3::exp(Vector3(-e))))) /
                           (2 * eps);
        EXPECT_LE((fd - D.col(i)).norm(), 1e-7 * D.norm()) << schemeName(kind);
      }
    }
  }
}

TEST(Integrators, StepsShorterThanThePrincipalBranchRadiusAreOnTheBranchWithMargin) {
  // principalBranchRadius's bound, against the momentum Jacobian itself: random inertias
  // (random principal axes, condition numbers up to the limit, bodies that violate the triangle
  // inequality too) and random steps shorter than the radius have σ_min(h ∂μ/∂ε) ≥ λ_min(J)/2.
  std::mt19937 rng(6565);
  std::normal_distribution<double> n(0.0, 1.0);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  const double h = 0.3;
  for (int body = 0; body < 60; ++body) {
    const double spread = std::pow(kPrincipalBranchConditionLimit, u(rng));
    const Vector3 moments(1.0, 1.0 + (spread - 1.0) * u(rng), spread);
    const Matrix3 axes = so3::exp(Vector3(n(rng), n(rng), n(rng)));
    const Matrix3 J = axes * moments.asDiagonal() * axes.transpose();
    for (SchemeKind kind : {SchemeKind::Paper, SchemeKind::Variational, SchemeKind::SecondOrder}) {
      const DiscreteScheme scheme(kind, J, h);
      const double radius = principalBranchRadius(scheme);
      ASSERT_GT(radius, 0.0) << schemeName(kind);
      for (int step = 0; step < 40; ++step) {
        const Vector3 omega = u(rng) * radius * Vector3(n(rng), n(rng), n(rng)).normalized();
        const Matrix3 D = h * scheme.momentumJacobianOfStep(so3::exp(omega), omega);
        const double least = Eigen::JacobiSVD<Matrix3>(D).singularValues()(2);
        EXPECT_GE(least, 0.5 * moments.minCoeff() * (1 - 1e-12)) << schemeName(kind);
        EXPECT_TRUE(scheme.onPrincipalBranch(omega)) << schemeName(kind);
      }
    }
  }
  // Isotropic: the radius lies inside the branch (the fold at π/2), and a body past the
  // condition limit gets none.
  const DiscreteScheme isotropic(SchemeKind::SecondOrder, 2.0 * Matrix3::Identity(), h);
  EXPECT_GT(principalBranchRadius(isotropic), 0.2);
  EXPECT_LT(principalBranchRadius(isotropic), M_PI / 2);
  const Matrix3 slender = Vector3(1.0, 2e3, 2e3).asDiagonal();
  EXPECT_EQ(principalBranchRadius(DiscreteScheme(SchemeKind::Paper, slender, h)), 0.0);
}

TEST(Integrators, PrincipalBranchEndsAtTheFoldOfTheMomentum) {
  // Isotropic J = jI, ω = θa: variational and second_order μ = (j/h) sin θ a, so the branch
  // through the identity ends at θ = π/2 and the step π − φ aliases the step φ (the same μ);
  // paper μ = (j/h) θ a, invertible for every θ < π.
  std::mt19937 rng(11);
  std::normal_distribution<double> n(0.0, 1.0);
  const Matrix3 J = 3.0 * Matrix3::Identity();
  for (int trial = 0; trial < 20; ++trial) {
    const Vector3 a = Vector3(n(rng), n(rng), n(rng)).normalized();
    const double phi = 0.05 + 1.4 * std::abs(std::sin(n(rng)));  // in (0.05, 1.45)
    for (SchemeKind kind : {SchemeKind::Variational, SchemeKind::SecondOrder}) {
      const DiscreteScheme scheme(kind, J, 0.2);
      EXPECT_TRUE(scheme.onPrincipalBranch(Vector3((M_PI / 2 - 1e-6) * a)));
      EXPECT_FALSE(scheme.onPrincipalBranch(Vector3((M_PI / 2 + 1e-6) * a)));
      EXPECT_TRUE(scheme.onPrincipalBranch(Vector3(phi * a)));
      EXPECT_FALSE(scheme.onPrincipalBranch(Vector3((M_PI - phi) * a)));
      const Vector3 slow = scheme.momentumOfStep(Vector3(phi * a));
      const Vector3 aliased = scheme.momentumOfStep(Vector3((M_PI - phi) * a));
      EXPECT_LE((slow - aliased).norm(), 1e-12 * slow.norm()) << schemeName(kind);
    }
    const DiscreteScheme paper(SchemeKind::Paper, J, 0.2);
    EXPECT_TRUE(paper.onPrincipalBranch(Vector3((M_PI - 1e-3) * a)));
    EXPECT_TRUE(paper.onPrincipalBranch(Vector3(phi * a)));
  }
}

// The 1e6-step torque-free drift test lives in the hard-case catalog
// (TorqueFreeMillionSteps in test/support/robustness_cases.cpp, asserted by test_hard_cases).

TEST(Integrators, VariationalEnergyDoesNotDriftOver2000Seconds) {
  const Matrix3 J = Vector3(1, 2, 3).asDiagonal();
  const int N = 200000;
  const Maneuver m = run(SchemeKind::Variational, J, 0.01, Vector3(0.6, 0.5, 0.4),
                         std::vector<Vector3>(N + 1, Vector3::Zero()));
  const double E0 = energy(m, J, 0);
  double worst = 0;
  for (int k = 0; k < N; ++k) worst = std::max(worst, std::abs(energy(m, J, k) - E0) / E0);
  EXPECT_LE(worst, 1e-11);
}

TEST(Integrators, PaperEnergyDecaysToMajorAxisSpin) {
  // Finding (docs/results/integrators.md): the printed scheme conserves momentum but dissipates
  // energy; the body ends in pure spin about the major axis, E = |π|²/(2 J_max).
  const Matrix3 J = Vector3(1, 2, 3).asDiagonal();
  const int N = 200000;
  const Maneuver m = run(SchemeKind::Paper, J, 0.01, Vector3(0.6, 0.5, 0.4),
                         std::vector<Vector3>(N + 1, Vector3::Zero()));
  const double momentum2 = (J * Vector3(0.6, 0.5, 0.4)).squaredNorm();
  double previous = energy(m, J, 0);
  int increases = 0;
  for (int k = 1000; k < N; k += 1000) {
    const double e = energy(m, J, k);
    if (e > previous * (1 + 1e-12)) ++increases;
    previous = e;
  }
  EXPECT_EQ(increases, 0);
  EXPECT_NEAR(energy(m, J, N - 1), momentum2 / 6.0, 1e-4 * momentum2 / 6.0);
  EXPECT_LT(energy(m, J, N - 1), 0.75 * energy(m, J, 0));
}

TEST(Integrators, So2CheckErrorDecreasesAtObservedOrder) {
  // Seed Fig. 1 on SO(3) about a principal axis: θ̇ = ω, ω̇ = τ, τ = sin(πt/2), θ0 = 3, ω0 = 4.
  for (SchemeKind kind : {SchemeKind::Paper, SchemeKind::Variational}) {
    std::vector<double> theta_error, omega_error;
    for (int N : {1000, 2000}) {
      const double h = 10.0 / N;
      auto torque = std::vector<Vector3>(N + 1, Vector3::Zero());
      for (int k = 1; k < N; ++k) torque[k] = Vector3(0, 0, std::sin(M_PI * k * h / 2));
      const Maneuver m = run(kind, Matrix3::Identity(), h, Vector3(0, 0, 4), torque,
                             so3::fromAxisAngle(Vector3::UnitZ(), 3.0));
      double et = 0, ew = 0;
      for (int k = 0; k < N; ++k) {
        const double t = k * h;
        const double theta = 3 + 4 * t + 2 / M_PI * t - 4 / (M_PI * M_PI) * std::sin(M_PI * t / 2);
        const double omega = 4 + 2 / M_PI * (1 - std::cos(M_PI * t / 2));
        et = std::max(
            et, so3::angleBetween(so3::fromAxisAngle(Vector3::UnitZ(), theta), m.attitude[k]));
        ew = std::max(ew, std::abs(m.angular_velocity[k].z() - omega));
      }
      theta_error.push_back(et);
      omega_error.push_back(ew);
    }
    // Measured (docs/results/integrators.md): θ converges at order 2, ω at order 1 (left-point
    // torque).
    EXPECT_NEAR(std::log2(theta_error[0] / theta_error[1]), 2.0, 0.1) << schemeName(kind);
    EXPECT_NEAR(std::log2(omega_error[0] / omega_error[1]), 1.0, 0.1) << schemeName(kind);
  }
}

TEST(Integrators, EquivarianceUnderWorldRotation) {
  const auto torque = randomTorques(40, 1.0, 8);
  const Matrix3 Q = so3::exp(Vector3(0.3, -2.0, 1.1));
  for (SchemeKind kind : {SchemeKind::Paper, SchemeKind::Variational}) {
    const Maneuver a = run(kind, kSeedInertia, 0.1, Vector3(0.1, 0.2, -0.3), torque);
    const Maneuver b = run(kind, kSeedInertia, 0.1, Vector3(0.1, 0.2, -0.3), torque, Q);
    for (int k = 0; k <= 40; ++k) {
      EXPECT_LE((b.attitude[k] - Q * a.attitude[k]).norm(), 1e-13);
      EXPECT_LE((b.angular_velocity[k] - a.angular_velocity[k]).norm(), 1e-12);
    }
  }
}

TEST(Integrators, StepTooLargeIsAClearErrorNotNaN) {
  // paper: one step may not rotate by more than π
  EXPECT_THROW(
      DiscreteScheme(SchemeKind::Paper, kSeedInertia, 1.0).stepFromVelocity(Vector3(4, 0, 0)),
      StepTooLarge);
  // variational: μ(F) is bounded over SO(3), so a large momentum has no step at all
  const DiscreteScheme variational(SchemeKind::Variational, kSeedInertia, 1.0);
  try {
    variational.stepFromVelocity(Vector3(50, 0, 0));
    FAIL() << "expected StepTooLarge";
  } catch (const StepTooLarge& e) {
    EXPECT_NE(std::string(e.what()).find("increase steps"), std::string::npos) << e.what();
  }
  // and inside a simulation, the step index is named
  auto torque = std::vector<Vector3>(11, Vector3::Zero());
  torque[3] = Vector3(500, 0, 0);
  try {
    run(SchemeKind::Variational, kSeedInertia, 1.0, Vector3::Zero(), torque);
    FAIL() << "expected StepTooLarge";
  } catch (const StepTooLarge& e) {
    EXPECT_NE(std::string(e.what()).find("k = 3"), std::string::npos) << e.what();
  }
}

TEST(Integrators, BoundaryTorquesMustBeZero) {
  auto torque = std::vector<Vector3>(5, Vector3::Zero());
  torque[0] = Vector3(1, 0, 0);
  EXPECT_THROW(run(SchemeKind::Paper, kSeedInertia, 0.1, Vector3::Zero(), torque), InvalidInput);
}

TEST(Integrators, BothSchemesConvergeToTheContinuousFreeRigidBody) {
  // Reference: RK4 on (R, Ω) with a tiny step, re-projected to SO(3).
  const Matrix3 J = kSeedInertia, Jinv = J.inverse();
  const Vector3 omega0(0.4, -0.3, 0.5);
  const double T = 2.0;
  auto rhs = [&](const Vector3& w) { return Vector3(Jinv * (J * w).cross(w)); };
  Matrix3 R = Matrix3::Identity();
  Vector3 w = omega0;
  const int M = 200000;
  const double dt = T / M;
  for (int i = 0; i < M; ++i) {  // Lie–Euler on R with RK4 on Ω: R error O(dt) = 1e-5 × small
    const Vector3 k1 = rhs(w), k2 = rhs(w + dt / 2 * k1), k3 = rhs(w + dt / 2 * k2),
                  k4 = rhs(w + dt * k3);
    const Vector3 w_next = w + dt / 6 * (k1 + 2 * k2 + 2 * k3 + k4);
    R = R * so3::exp(Vector3(dt / 2 * (w + w_next)));
    w = w_next;
  }
  for (SchemeKind kind : {SchemeKind::Paper, SchemeKind::Variational}) {
    std::vector<double> errors;
    for (int N : {100, 200, 400}) {
      const Maneuver m = run(kind, J, T / N, omega0, std::vector<Vector3>(N + 1, Vector3::Zero()));
      errors.push_back(so3::angleBetween(R, m.attitude[N]));
    }
    const double order = std::log2(errors[1] / errors[2]);
    // paper: first order; variational (LGVI): second order
    EXPECT_NEAR(order, kind == SchemeKind::Paper ? 1.0 : 2.0, 0.15)
        << schemeName(kind) << " errors " << errors[0] << " " << errors[1] << " " << errors[2];
  }
}
