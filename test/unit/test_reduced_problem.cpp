// The reduced problem's gradient and exact Hessian against finite differences of its cost.
#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/LU>
#include <Eigen/QR>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <random>
#include <stdexcept>

#include "attitude_planner/dynamics/simulation.hpp"
#include "attitude_planner/planner.hpp"
#include "lie/dual.hpp"
#include "planning/linalg/banded_matrix.hpp"
#include "planning/transcription/reduced_problem.hpp"
#include "support/perturbed_problem.hpp"

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
  model->add(std::make_unique<DisturbanceTorque>(Vector3(0.5, -0.2, 0.3), TorqueFrame::World));
  p.effects = model;
  return p;
}

// Interior attitudes moved off the geodesic, so torques and curvature are generic.
ReducedProblem perturbedProblem(SchemeKind scheme, int N, unsigned seed, bool effects = false) {
  return test_support::perturbedReducedProblem(
      effects ? withEffects(randomProblem(scheme, N)) : randomProblem(scheme, N), seed);
}

using Dual3 = Dual<3>;

/// F exp(ε^) to first order in a dual ε (value 0, unit derivatives): F + Σ_e ε_e F ê_e^.
so3::Mat3<Dual3> perturbedByDual(const Matrix3& F) {
  so3::Mat3<Dual3> Fd;
  for (int e = 0; e < 3; ++e) {
    const Matrix3 dF = F * so3::hat(Vector3(Vector3::Unit(e)));
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) {
        Fd(r, c).v = F(r, c);
        Fd(r, c).d(e) = dF(r, c);
      }
    }
  }
  return Fd;
}

}  // namespace

// The closed-form second derivative of μ (the Newton Hessian's curvature term) against forward-mode
// dual numbers pushed through the first-derivative formula momentumJacobian, for both schemes,
// steps from 1e-6 rad (series branches) to 2.5 rad, and a non-diagonal inertia.
TEST(DiscreteScheme, MomentumJacobianContractionMatchesDualNumbers) {
  Matrix3 J;
  J << 13.25, -7.80, -11.40, -7.80, 16.25, 4.71, -11.40, 4.71, 18.37;
  std::mt19937 rng(7);
  std::normal_distribution<double> n(0.0, 1.0);
  for (SchemeKind kind : {SchemeKind::Paper, SchemeKind::Variational}) {
    const DiscreteScheme scheme(kind, J, 0.05);
    for (double angle : {1e-6, 1e-3, 0.05, 0.3, 0.49, 0.51, 1.0, 2.5}) {
      const Vector3 axis = Vector3(n(rng), n(rng), n(rng)).normalized();
      const Matrix3 F = so3::exp(Vector3(angle * axis));
      const Vector3 tau(n(rng), n(rng), n(rng));
      const so3::Mat3<Dual3> D = scheme.momentumJacobian<Dual3>(perturbedByDual(F));
      Matrix3 expected = Matrix3::Zero();  // (m, e) = Σ_i τ_i ∂D(i, m)/∂ε_e
      for (int i = 0; i < 3; ++i) {
        for (int m = 0; m < 3; ++m) expected.row(m) += tau(i) * D(i, m).d.transpose();
      }
      const Matrix3 actual = scheme.momentumJacobianContraction(F, Vector3(angle * axis), tau);
      EXPECT_LE((actual - expected).norm(), 1e-10 * expected.norm())
          << schemeName(kind) << " angle " << angle << "\nactual\n"
          << actual << "\nexpected\n"
          << expected;
    }
  }
}

// The step's terms, formed once per step for the Hessian's two contractions of it, give the same
// values (bit for bit) as the Jacobian and contraction formed from the step alone: both schemes,
// the series branch (below kSmallAngle), both sides of the derivative's switch and near π.
TEST(DiscreteScheme, StepJacobianTermsGiveTheStepsOwnJacobianAndContraction) {
  Matrix3 J;
  J << 13.25, -7.80, -11.40, -7.80, 16.25, 4.71, -11.40, 4.71, 18.37;
  std::mt19937 rng(11);
  std::normal_distribution<double> n(0.0, 1.0);
  for (SchemeKind kind : {SchemeKind::Paper, SchemeKind::Variational}) {
    const DiscreteScheme scheme(kind, J, 0.05);
    for (double angle : {0.0, 1e-6, 1e-3, 0.3, 0.49, 0.51, 1.0, 2.5, 3.1}) {
      const Vector3 omega = angle * Vector3(n(rng), n(rng), n(rng)).normalized();
      const Matrix3 F = so3::exp(omega);
      const DiscreteScheme::StepJacobianTerms step = scheme.stepJacobianTerms(F, omega);
      EXPECT_EQ(scheme.momentumJacobianOfStep(step), scheme.momentumJacobianOfStep(F, omega))
          << schemeName(kind) << " angle " << angle;
      if (kind == SchemeKind::Paper) {
        EXPECT_EQ(step.Jr_inverse, so3::rightJacobianInverse<double>(omega));
      }
      for (int trial = 0; trial < 3; ++trial) {
        const Vector3 tau(n(rng), n(rng), n(rng));
        const Matrix3 expected =
            DiscreteScheme(kind, J, 0.05).momentumJacobianContraction(so3::exp(omega), omega, tau);
        EXPECT_EQ(scheme.momentumJacobianContraction(step, tau), expected)
            << schemeName(kind) << " angle " << angle;
      }
    }
  }
}

// dc/dθ² of Jr⁻¹'s coefficient (series below θ = 0.5, closed form above) against a 40-digit
// reference, on both sides of the switch and up to near 2π. The reference values come from
//   python3 -c "import mpmath as mp; mp.mp.dps = 40;
//     c = lambda s: (1 - (mp.sqrt(s)/2)*mp.cot(mp.sqrt(s)/2))/s; print(mp.diff(c, mp.mpf(t)**2))"
// (double-precision dual numbers of the closed form are no reference: they lose 1e-12 at θ = 0.1).
TEST(So3, RightJacobianInverseCoefficientDerivativeMatchesHighPrecisionReference) {
  const std::vector<std::pair<double, double>> reference = {
      {0.1, 0.0013895505126496710231},    {0.2, 0.0013915383651395815729},
      {0.4999, 0.0014055728668932968521}, {0.5001, 0.0014055863455872639213},
      {1.0, 0.0014575928456183325112},    {2.0, 0.0016992357303663318005},
      {3.0, 0.002269674848916882159},     {6.0, 0.16546225215639466996}};
  for (const auto& [theta, expected] : reference) {
    EXPECT_NEAR(so3::rightJacobianInverseCoefficientDerivative(theta * theta), expected,
                1e-12 * expected)  // the closed form just above θ = 0.5 loses 2e-13
        << "theta " << theta;
  }
}

TEST(ReducedProblem, GradientMatchesFiniteDifferencesOfTheCost) {
  for (SchemeKind scheme : {SchemeKind::Paper, SchemeKind::Variational, SchemeKind::SecondOrder}) {
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
  // the retracted cost, independent of how evaluate() assembles it. second_order adds the end
  // torques τ_0(R_1), τ_N(R_{N−1}) with weight ½.
  for (SchemeKind scheme : {SchemeKind::Paper, SchemeKind::Variational, SchemeKind::SecondOrder}) {
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

// evaluate() forms only the band's lower triangle, from the stencils' unsymmetrized curvature;
// the same Hessian, to round-off, as the full symmetric blocks JᵀJ + second that forEachStencil
// hands every other reader, summed densely here: all schemes, with and without effects (whose
// curvature enters the middle block), on grids whose end stencils cut fixed nodes off.
TEST(ReducedProblem, HessianIsTheSumOfTheStencilsSymmetricBlocks) {
  for (SchemeKind scheme : {SchemeKind::Paper, SchemeKind::Variational, SchemeKind::SecondOrder}) {
    for (bool effects : {false, true}) {
      const ReducedProblem rp = perturbedProblem(scheme, 11, 4, effects);
      const int n = rp.unknowns();
      Eigen::VectorXd g;
      double scale;
      BandedSymmetricMatrix H(n, ReducedProblem::kHalfBandwidth);
      rp.evaluate(&g, &H, &scale);
      Eigen::MatrixXd expected = Eigen::MatrixXd::Zero(n, n);
      rp.forEachStencil(true, [&](const ReducedProblem::Stencil& st) {
        const Eigen::Matrix<double, 9, 9> block = st.jacobian.transpose() * st.jacobian + st.second;
        for (int s = 0; s < 3; ++s) {
          for (int t = 0; t < 3; ++t) {
            const int vs = rp.variableIndex(st.k - 1 + s), vt = rp.variableIndex(st.k - 1 + t);
            if (vs >= 0 && vt >= 0) expected.block<3, 3>(vs, vt) += block.block<3, 3>(3 * s, 3 * t);
          }
        }
      });
      const double tolerance = 1e-13 * expected.cwiseAbs().maxCoeff();
      EXPECT_LE((H.toDense() - expected).cwiseAbs().maxCoeff(), tolerance)
          << schemeName(scheme) << " effects " << effects;
    }
  }
}

namespace {

bool sameBits(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) {
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(double)) == 0;
}

}  // namespace

// The accepted trial's evaluation from the step forms its cost kept (StepForms) gives the bits
// of the evaluation that forms them itself; forms of other steps, or of another h, are not read.
TEST(ReducedProblem, EvaluationFromTheTrialsKeptStepFormsGivesTheSameBits) {
  for (SchemeKind scheme : {SchemeKind::Paper, SchemeKind::Variational, SchemeKind::SecondOrder}) {
    for (bool effects : {false, true}) {
      ReducedProblem rp = perturbedProblem(scheme, 12, 5, effects);
      const int n = rp.unknowns();
      Eigen::VectorXd g0, g1;
      double scale0, scale1;
      BandedSymmetricMatrix H0(n, ReducedProblem::kHalfBandwidth),
          H1(n, ReducedProblem::kHalfBandwidth);
      rp.evaluate(&g0, &H0, &scale0);
      const ReducedProblem::StepVectors trial = rp.retract(-0.1 * g0 / g0.norm(), 1.0);
      ReducedProblem::StepForms forms;
      const double trial_cost = rp.cost(trial, &forms);
      EXPECT_EQ(trial_cost, rp.cost(trial));
      rp.setCurrent(trial);
      const double c0 = rp.evaluate(&g0, &H0, &scale0);
      const double c1 = rp.evaluate(&g1, &H1, &scale1, &forms);
      const std::string what = schemeName(scheme) + (effects ? " with effects" : "");
      EXPECT_EQ(c0, c1) << what;
      EXPECT_EQ(c0, trial_cost) << what;
      EXPECT_EQ(scale0, scale1) << what;
      EXPECT_TRUE(sameBits(g0, g1)) << what;
      EXPECT_TRUE(sameBits(H0.toDense(), H1.toDense())) << what;
      // Forms of steps that are not the iterate's (one step moved in its last bit) are not read.
      ReducedProblem::StepVectors other = trial;
      other[rp.firstFreeNode()].x() = std::nextafter(other[rp.firstFreeNode()].x(), 1.0);
      rp.cost(other, &forms);
      rp.evaluate(&g1, &H1, &scale1, &forms);
      EXPECT_TRUE(sameBits(g0, g1)) << what;
      EXPECT_TRUE(sameBits(H0.toDense(), H1.toDense())) << what;
      // Nor those kept at another h (μ reads h).
      ReducedProblem at_other_h = rp;
      at_other_h.setTimeStep(1.25 * rp.timeStep());
      at_other_h.cost(trial, &forms);  // the same steps, μ at 1.25 h
      rp.evaluate(&g1, &H1, &scale1, &forms);
      EXPECT_TRUE(sameBits(g0, g1)) << what;
    }
  }
}

namespace {

/// The Hessian of `rp` at its iterate and its gradient, shifted by the most negative eigenvalue
/// (away from optima the Hessian may be indefinite) so that it is positive definite.
BandedSymmetricMatrix definiteHessian(const ReducedProblem& rp, Eigen::VectorXd* g) {
  double scale;
  BandedSymmetricMatrix H(rp.unknowns(), 8);
  rp.evaluate(g, &H, &scale);
  const double lowest =
      Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd>(H.toDense()).eigenvalues()(0);
  H.addToDiagonal(std::max(0.0, -lowest) + 1e-3 * H.maxAbsDiagonal());
  return H;
}

}  // namespace

TEST(ReducedProblem, BandedCholeskyMatchesDenseSolve) {
  const ReducedProblem rp = perturbedProblem(SchemeKind::Paper, 12, 3);
  Eigen::VectorXd g;
  const BandedSymmetricMatrix H = definiteHessian(rp, &g);
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

// The factor's order of work (column by column) is free, its arithmetic is not: every entry is
// L(i, j) = (A(i, j) − Σ_k L(i, k) L(j, k)) / L(j, j), the sum over k = max(0, i − p) .. j − 1 in
// ascending order, as a row-by-row textbook factorization forms it; then the same substitutions.
// Bit for bit on a Newton Hessian and on random banded SPD matrices of several bandwidths.
TEST(ReducedProblem, BandedCholeskyFormsEachEntryAsTheTextbookSumInAscendingOrder) {
  const auto textbook = [](const Eigen::MatrixXd& A, int p, Eigen::VectorXd b) {
    const int n = static_cast<int>(A.rows());
    Eigen::MatrixXd L = Eigen::MatrixXd::Zero(n, n);
    for (int i = 0; i < n; ++i) {
      for (int j = std::max(0, i - p); j <= i; ++j) {
        double s = A(i, j);
        for (int k = std::max(0, i - p); k < j; ++k) s -= L(i, k) * L(j, k);
        L(i, j) = j < i ? s / L(j, j) : std::sqrt(s);
      }
    }
    for (int i = 0; i < n; ++i) {
      double s = b(i);
      for (int k = std::max(0, i - p); k < i; ++k) s -= L(i, k) * b(k);
      b(i) = s / L(i, i);
    }
    for (int i = n - 1; i >= 0; --i) {
      double s = b(i);
      for (int k = i + 1; k <= std::min(n - 1, i + p); ++k) s -= L(k, i) * b(k);
      b(i) = s / L(i, i);
    }
    return b;
  };
  std::mt19937 rng(5);
  std::normal_distribution<double> normal(0.0, 1.0);
  std::vector<BandedSymmetricMatrix> matrices;
  Eigen::VectorXd g;
  matrices.push_back(definiteHessian(perturbedProblem(SchemeKind::Paper, 40, 3), &g));
  for (const int p : {1, 3, 8}) {
    const int n = 30;
    BandedSymmetricMatrix A(n, p);
    for (int i = 0; i < n; ++i) {
      for (int j = std::max(0, i - p); j < i; ++j) A.add(i, j, normal(rng));
      A.add(i, i, 4.0 * p + std::abs(normal(rng)));  // diagonally dominant: definite
    }
    matrices.push_back(A);
  }
  for (const BandedSymmetricMatrix& A : matrices) {
    Eigen::VectorXd b(A.size());
    for (int i = 0; i < b.size(); ++i) b(i) = normal(rng);
    BandedCholesky cholesky;
    ASSERT_TRUE(cholesky.factor(A));
    Eigen::VectorXd x = b;
    cholesky.solve(&x);
    const Eigen::VectorXd expected = textbook(A.toDense(), A.bandwidth(), b);
    for (int i = 0; i < b.size(); ++i)
      EXPECT_EQ(x(i), expected(i)) << "bandwidth " << A.bandwidth();
  }
}

TEST(ReducedProblem, BandedCholeskyFactorSolvesSeveralRightHandSides) {
  // One factorization, several solves (kept for a second solve with the same factor: a
  // predictor–corrector).
  const ReducedProblem rp = perturbedProblem(SchemeKind::Paper, 12, 3);
  Eigen::VectorXd g;
  const BandedSymmetricMatrix H = definiteHessian(rp, &g);
  BandedCholesky cholesky;
  ASSERT_TRUE(cholesky.factor(H));
  std::mt19937 rng(3);
  std::normal_distribution<double> n(0.0, 1.0);
  for (int trial = 0; trial < 3; ++trial) {
    Eigen::VectorXd b(rp.unknowns());
    for (int i = 0; i < b.size(); ++i) b(i) = n(rng);
    Eigen::VectorXd x = b;
    cholesky.solve(&x);
    EXPECT_LE((x - H.toDense().ldlt().solve(b)).norm(), 1e-10 * x.norm());
  }
  BandedSymmetricMatrix indefinite(2, 1);
  indefinite.add(0, 0, 1.0);
  indefinite.add(1, 1, -1.0);
  EXPECT_FALSE(cholesky.factor(indefinite));
}

// The interior point's situation (kExtendedPrecisionAboveSteps): a banded SPD matrix S plus
// rank-one terms w g gᵀ with w up to 1e12·|S| (constraints at their bounds) and beyond. The
// step's part along the rank-one terms' null space depends on S alone. Reference:
// Sherman–Morrison–Woodbury through S's own (well-conditioned) dense factorization, in double.
// Formed and factored in double-double (ExtendedBandedMatrix) the solve keeps it to the
// reference's own accuracy at w = 1e12 and at w = 1e20, where long double's 64-bit significand
// (ε = 5e-20) would keep nothing; in double only a few digits are left at w = 1e12 (measured
// here: 7e-5 relative; long double: 4e-8).
TEST(BandedSymmetric, ExtendedPrecisionKeepsTheCurvatureUnderHugeRankOneTerms) {
  for (const double weight : {1e12, 1e20}) {
    const int n = 60, p = 8;
    std::mt19937 rng(16);
    std::normal_distribution<double> normal(0.0, 1.0);
    Eigen::MatrixXd S = Eigen::MatrixXd::Zero(n, n);
    for (int i = 0; i < n; ++i) {
      S(i, i) = 4.0;
      for (int j = std::max(0, i - 2); j < i; ++j) S(i, j) = S(j, i) = 0.5 * normal(rng) / 3.0;
    }
    // Rank-one terms, each local (within the band): g over 9 consecutive unknowns.
    struct Term {
      int offset;
      Eigen::Matrix<double, 9, 1> g;
    };
    std::vector<Term> terms;
    for (int offset = 0; offset + 9 <= n; offset += 5) {
      Eigen::Matrix<double, 9, 1> g;
      for (int i = 0; i < 9; ++i) g(i) = normal(rng);
      terms.push_back({offset, g});
    }
    Eigen::VectorXd b(n);
    for (int i = 0; i < n; ++i) b(i) = normal(rng);
    // Reference: x = S⁻¹b − S⁻¹G (W⁻¹ + GᵀS⁻¹G)⁻¹ GᵀS⁻¹b, with W⁻¹ = 1/weight tiny.
    const int m = static_cast<int>(terms.size());
    Eigen::MatrixXd G = Eigen::MatrixXd::Zero(n, m);
    for (int t = 0; t < m; ++t) G.block(terms[t].offset, t, 9, 1) = terms[t].g;
    const Eigen::LLT<Eigen::MatrixXd> s_factor(S);
    const Eigen::MatrixXd SG = s_factor.solve(G);
    const Eigen::VectorXd Sb = s_factor.solve(b);
    Eigen::MatrixXd capacitance = G.transpose() * SG;
    capacitance.diagonal().array() += 1.0 / weight;
    const Eigen::VectorXd reference = Sb - SG * capacitance.ldlt().solve(G.transpose() * Sb);
    // The null-space part: the component of x orthogonal to range(G).
    const Eigen::MatrixXd Q = G.householderQr().householderQ() * Eigen::MatrixXd::Identity(n, m);
    const auto null_part = [&](const Eigen::VectorXd& x) {
      return Eigen::VectorXd(x - Q * (Q.transpose() * x));
    };
    const auto solveIn = [&](auto matrix, bool* factored) {
      for (int i = 0; i < n; ++i)
        for (int j = std::max(0, i - p); j <= i; ++j)
          if (S(i, j) != 0.0) matrix.add(i, j, S(i, j));
      for (const Term& t : terms) matrix.template addRankOne<9>(t.offset, t.g, weight, 0, 9);
      Eigen::VectorXd x = b;
      *factored = matrix.solvePositiveDefinite(&x);
      return x;
    };
    bool extended_factored = false, plain_factored = false;
    const Eigen::VectorXd extended = solveIn(ExtendedBandedMatrix(n, p), &extended_factored);
    const Eigen::VectorXd plain = solveIn(BandedSymmetricMatrix(n, p), &plain_factored);
    ASSERT_TRUE(extended_factored);
    const double scale = null_part(reference).norm();
    const double extended_error = (null_part(extended) - null_part(reference)).norm() / scale;
    // Expected: ~ε·w|g|²/λ_min(S) with ε = 1.2e-32 (~3e-12 at w = 1e20; long double: ~1).
    EXPECT_LE(extended_error, 1e-10) << "w = " << weight;
    if (plain_factored) {
      const double plain_error = (null_part(plain) - null_part(reference)).norm() / scale;
      EXPECT_GE(plain_error, 1e3 * extended_error) << "w = " << weight;
      std::printf("w = %.0e, null-space part, relative error: double-double %.2e, double %.2e\n",
                  weight, extended_error, plain_error);
    } else {
      std::printf(
          "w = %.0e, null-space part, relative error: double-double %.2e, double: not "
          "positive definite\n",
          weight, extended_error);
    }
  }
}

// Double-double arithmetic (double_double.hpp): the error-free transformations are exact, and
// ÷, √ agree with long double (an independent 64-bit computation) to its own precision and leave
// double-double residuals ≤ 1e-30.
TEST(DoubleDouble, SumsAndProductsAreExact) {
  const DoubleDouble sum = DoubleDouble::twoSum(1e16, 1.0);
  EXPECT_EQ(sum.hi(), 1e16);
  EXPECT_EQ(sum.lo(), 1.0);
  const double a = 1.0 + std::ldexp(1.0, -30), b = 1.0 + std::ldexp(1.0, -31);
  const DoubleDouble product = DoubleDouble::twoProduct(a, b);  // 1 + 2⁻³⁰ + 2⁻³¹ + 2⁻⁶¹
  EXPECT_EQ(product.hi(), 1.0 + std::ldexp(1.0, -30) + std::ldexp(1.0, -31));
  EXPECT_EQ(product.lo(), std::ldexp(1.0, -61));
  // A small term survives a cancellation that double loses.
  const DoubleDouble one(1.0);
  EXPECT_EQ(static_cast<double>((one + 1e-25) - one), 1e-25);
  EXPECT_EQ(static_cast<double>((one * 3.0 + 1e-20) - DoubleDouble(3.0)), 1e-20);
}

TEST(DoubleDouble, DivisionAndRootMatchLongDoubleAndLeaveTinyResiduals) {
  std::mt19937 rng(28);
  std::uniform_real_distribution<double> mantissa(1.0, 10.0);
  std::uniform_int_distribution<int> exponent(-30, 30);
  const auto value = [&] {
    return DoubleDouble(std::ldexp(mantissa(rng), exponent(rng))) + std::ldexp(mantissa(rng), -80);
  };
  const auto asLong = [](DoubleDouble x) {
    return static_cast<long double>(x.hi()) + static_cast<long double>(x.lo());
  };
  for (int trial = 0; trial < 1000; ++trial) {
    const DoubleDouble x = value(), y = value();
    const DoubleDouble q = x / y;
    EXPECT_LE(std::abs(static_cast<double>((x - q * y) / x)), 1e-30);
    EXPECT_LE(std::abs(static_cast<double>((asLong(q) - asLong(x) / asLong(y)) / asLong(q))),
              2e-19);
    const DoubleDouble r = sqrt(x);
    EXPECT_LE(std::abs(static_cast<double>((r * r - x) / x)), 1e-30);
    EXPECT_LE(std::abs(static_cast<double>((asLong(r) - std::sqrt(asLong(x))) / asLong(r))), 2e-19);
    EXPECT_TRUE(q > DoubleDouble(0.0));
    EXPECT_TRUE(x - y < x);
  }
  // The Cholesky inner products' accumulation (DoubleDoubleDifference) against term-by-term
  // double-double arithmetic: within 1e-30 of |s| + Σ|a_k b_k|.
  for (int trial = 0; trial < 200; ++trial) {
    DoubleDouble a[8], b[8], exact = value();
    DoubleDouble magnitude = abs(exact);
    DoubleDoubleDifference accumulated(exact);
    for (int k = 0; k < 8; ++k) {
      a[k] = value();
      b[k] = value();
      accumulated.subtractProduct(a[k], b[k]);
      exact = exact - a[k] * b[k];
      magnitude = magnitude + abs(a[k] * b[k]);
    }
    EXPECT_LE(std::abs(static_cast<double>((accumulated.value() - exact) / magnitude)), 1e-30);
  }
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

namespace {
double relativeTorqueDistance(const std::vector<Vector3>& a, const std::vector<Vector3>& b) {
  double num = 0, den = 0;
  for (size_t k = 1; k + 1 < b.size(); ++k) {
    num += (a[k] - b[k]).squaredNorm();
    den += b[k].squaredNorm();
  }
  return std::sqrt(num / den);
}

struct CarriedOver {
  double steps;      ///< torque distance of initializeFromCoarser's guess from the fine solution
  double resampled;  ///< the same for the coarse attitudes resampled (resampleAttitudes)
};

CarriedOver carriedTorqueError(SchemeKind scheme, int coarse_steps, int fine_steps) {
  const PlanningProblem coarse_problem = randomProblem(scheme, coarse_steps);
  const PlanningProblem fine_problem = randomProblem(scheme, fine_steps);
  const PlanResult coarse = planManeuver(coarse_problem), fine = planManeuver(fine_problem);
  EXPECT_TRUE(coarse.converged() && fine.converged()) << coarse.message() << fine.message();
  ReducedProblem c(coarse_problem);
  c.setInteriorFromAttitudes(coarse.maneuver.attitude);
  ReducedProblem f(fine_problem);
  const ReducedProblem fresh(fine_problem);
  f.initializeFromCoarser(c.current());
  // The fixed boundary steps are kept and the interior still ends exactly on R_{N−1}.
  EXPECT_EQ(f.current().front(), fresh.current().front());
  EXPECT_EQ(f.current().back(), fresh.current().back());
  EXPECT_LE(so3::angleBetween(f.attitudes(f.current())[fine_steps - 1],
                              fresh.attitudes(fresh.current())[fine_steps - 1]),
            1e-13);
  ReducedProblem r(fine_problem);
  r.setInteriorFromAttitudes(resampleAttitudes(coarse.maneuver, fine_steps));
  return {relativeTorqueDistance(f.torques(f.current()), fine.maneuver.torque),
          relativeTorqueDistance(r.torques(r.current()), fine.maneuver.torque)};
}
}  // namespace

// Grid continuation: the coarse solution carried to a 4× finer grid is a guess whose torques
// are within about the coarse solution's own discretization error (8 % here at N = 32: the
// solutions themselves converge only like 1/N) and far closer than resampled attitudes, whose
// torques jump at the coarse nodes and the ends.
TEST(ReducedProblem, CoarseSolutionCarriedToAFinerGridIsCloseAndKeepsTheEnds) {
  for (SchemeKind scheme : {SchemeKind::Paper, SchemeKind::Variational}) {
    const CarriedOver e128 = carriedTorqueError(scheme, 32, 128);
    const CarriedOver e512 = carriedTorqueError(scheme, 128, 512);
    EXPECT_LE(e128.steps, 0.2) << schemeName(scheme);
    EXPECT_LE(e512.steps, 0.6 * e128.steps) << schemeName(scheme);
    EXPECT_LE(e128.steps, 0.5 * e128.resampled) << schemeName(scheme);
    EXPECT_LE(e512.steps, 0.5 * e512.resampled) << schemeName(scheme);
    std::printf(
        "%s: carried-over torque error %.3g (32 -> 128), %.3g (128 -> 512); resampled "
        "attitudes %.3g, %.3g\n",
        schemeName(scheme).c_str(), e128.steps, e512.steps, e128.resampled, e512.resampled);
  }
}

// The coasting start's building block: a guess of every step is taken as the interior, and the gap
// it leaves at the fixed end is closed. Guessing the very torque-free motion whose end the problem
// asks for leaves no gap, so the interior is that motion: zero torques to round-off, for every
// scheme's fixed ends (end torques too).
TEST(ReducedProblem, StepsOfATorqueFreeMotionToItsOwnEndAreKeptExactly) {
  for (SchemeKind scheme : {SchemeKind::Paper, SchemeKind::Variational, SchemeKind::SecondOrder}) {
    PlanningProblem p = randomProblem(scheme, 64);
    p.initial_velocity = Vector3(0.9, -0.4, 0.6);
    const DiscreteScheme discrete(scheme, p.inertia, p.duration / p.steps);
    SimulationInput input;
    input.initial_attitude = p.initial_attitude;
    input.initial_velocity = p.initial_velocity;
    input.torque.assign(p.steps + 1, Vector3::Zero());
    const Maneuver coast = simulate(discrete, input);
    p.final_attitude = coast.attitude.back();
    p.final_velocity = coast.angular_velocity.back();
    ReducedProblem rp(p);
    ReducedProblem::StepVectors guess(p.steps);
    for (int j = 0; j < p.steps; ++j) {
      guess[j] = so3::log(Matrix3(coast.attitude[j].transpose() * coast.attitude[j + 1]));
    }
    rp.initializeFromSteps(guess);
    double worst_torque = 0.0, worst_step = 0.0;
    for (const Vector3& tau : rp.torques(rp.current()))
      worst_torque = std::max(worst_torque, tau.norm());
    for (int j = 0; j < p.steps; ++j)
      worst_step = std::max(worst_step, (rp.current()[j] - guess[j]).norm());
    const double momentum = (p.inertia * p.initial_velocity).norm();
    EXPECT_LE(worst_torque, 1e-9 * momentum / discrete.timeStep()) << schemeName(scheme);
    EXPECT_LE(worst_step, 1e-12) << schemeName(scheme);
    // A guess that ends elsewhere is closed onto the fixed end: R_N is the problem's.
    for (Vector3& step : guess) step *= 0.5;
    rp.initializeFromSteps(guess);
    const std::vector<Matrix3> R = rp.attitudes(rp.current());
    EXPECT_LE(so3::angleBetween(R.back(), p.final_attitude), 1e-12) << schemeName(scheme);
    EXPECT_THROW(rp.initializeFromSteps(ReducedProblem::StepVectors(3)), InvalidInput);
  }
}

namespace {
/// Stops (throws) at its `stop_at`-th poll; counts the polls.
class StopAtPoll : public Interruption {
 public:
  explicit StopAtPoll(int stop_at) : stop_at_(stop_at) {}
  void poll() const override {
    if (++polls_ >= stop_at_) throw std::runtime_error("stopped");
  }
  int polls() const { return polls_; }

 private:
  int stop_at_;
  mutable int polls_ = 0;
};
}  // namespace

TEST(BandedLinearSystem, StorageIsZeroedInPolledChunksSoAStopIsNotHeldUpByIt) {
  // Allocating and zeroing the augmented Newton system (~160 MB at N = 1e5) polls the stop
  // every kColumnsBetweenPolls rows: a stop raised meanwhile ends it there.
  const int size = 10 * kColumnsBetweenPolls + 7, p = 3;
  const StopAtPoll never(1 << 30);
  BandedLinearSystem A(size, p, &never);
  EXPECT_EQ(never.polls(), 11);  // one poll per chunk of rows, the last chunk partial
  for (int i = 0; i < size; i += 97) {
    for (int j = std::max(0, i - p); j <= std::min(size - 1, i + p); ++j) EXPECT_EQ(A(i, j), 0.0);
  }
  for (int i = 0; i < size; ++i) A.add(i, i, 1.0 + i);
  const StopAtPoll never_again(1 << 30);
  A.setZero(&never_again);
  EXPECT_EQ(never_again.polls(), 11);
  for (int i = 0; i < size; ++i) ASSERT_EQ(A(i, i), 0.0) << i;
  const StopAtPoll third(3);
  EXPECT_THROW(BandedLinearSystem(size, p, &third), std::runtime_error);
  EXPECT_EQ(third.polls(), 3);
  const StopAtPoll fifth(5);
  EXPECT_THROW(A.setZero(&fifth), std::runtime_error);
  EXPECT_EQ(fifth.polls(), 5);
}
