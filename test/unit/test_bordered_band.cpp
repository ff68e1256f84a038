// The bordered banded solve (Schur complement on a dense border) against a dense LU solve in long
// double, on seeded random symmetric band + border matrices: positive definite, indefinite
// border (saddle points), ill-conditioned bands, in every precision the banded Cholesky has.
#include <gtest/gtest.h>

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <cmath>
#include <limits>
#include <random>

#include "planning/linalg/bordered_band.hpp"

using namespace attitude_planner;

namespace {

using DenseLD = Eigen::Matrix<long double, Eigen::Dynamic, Eigen::Dynamic>;
using VectorLD = Eigen::Matrix<long double, Eigen::Dynamic, 1>;

/// Machine epsilon of the factor's arithmetic (double-double: ~2⁻¹⁰⁴).
template <typename Scalar>
double scalarEpsilon() {
  if constexpr (std::is_same_v<Scalar, DoubleDouble>) return 1.2e-32;
  return static_cast<double>(std::numeric_limits<Scalar>::epsilon());
}

enum class BandKind { DiagonallyDominant, Biharmonic };
enum class BorderKind { PositiveDefinite, Indefinite, Singular };

/// A test case: K = [[A, B], [Bᵀ, D]] in a dense long double copy too.
struct Case {
  Eigen::MatrixXd A_dense, B, D;
  int bandwidth = 0;
};

/// A random symmetric band of half bandwidth p: diagonally dominant (well conditioned), or the
/// biharmonic stencil (1, −4, 6, −4, 1) plus a small random part, condition ~ n⁴ (ill).
Eigen::MatrixXd randomBand(int n, int p, BandKind kind, std::mt19937* rng) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(n, n);
  if (kind == BandKind::DiagonallyDominant) {
    for (int i = 0; i < n; ++i) {
      for (int j = std::max(0, i - p); j < i; ++j) A(i, j) = A(j, i) = u(*rng);
    }
    for (int i = 0; i < n; ++i) A(i, i) = A.row(i).cwiseAbs().sum() + 0.5 + 0.5 * u(*rng);
    return A;
  }
  for (int i = 0; i < n; ++i) {
    A(i, i) = 6.0;
    if (i + 1 < n) A(i, i + 1) = A(i + 1, i) = -4.0;
    if (i + 2 < n) A(i, i + 2) = A(i + 2, i) = 1.0;
  }
  A(0, 0) = A(n - 1, n - 1) = 5.0;  // clamped ends: positive definite
  for (int i = 0; i < n; ++i) {
    for (int j = std::max(0, i - p); j <= i; ++j) {
      const double v = 1e-9 * u(*rng);
      A(i, j) += v;
      if (i != j) A(j, i) += v;
    }
    A(i, i) += 1e-9;
  }
  return A;
}

Case randomCase(int n, int p, int m, BandKind band, BorderKind border, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Case c;
  c.bandwidth = p;
  c.A_dense = randomBand(n, p, band, &rng);
  c.B = Eigen::MatrixXd::NullaryExpr(n, m, [&]() { return u(rng); });
  // D = BᵀA⁻¹B ± M, M symmetric positive definite: the Schur complement is ±M (zero: singular).
  const DenseLD BtAinvB = c.B.cast<long double>().transpose() *
                          c.A_dense.cast<long double>().ldlt().solve(c.B.cast<long double>());
  Eigen::MatrixXd G = Eigen::MatrixXd::NullaryExpr(m, m, [&]() { return u(rng); });
  const Eigen::MatrixXd M = G * G.transpose() + 0.5 * Eigen::MatrixXd::Identity(m, m);
  const double sign = border == BorderKind::PositiveDefinite
                          ? 1.0
                          : (border == BorderKind::Indefinite ? -1.0 : 0.0);
  c.D = BtAinvB.cast<double>() + sign * M;
  c.D = 0.5 * (c.D + c.D.transpose()).eval();
  return c;
}

template <typename Scalar>
BandedSymmetric<Scalar> bandOf(const Case& c) {
  const int n = static_cast<int>(c.A_dense.rows());
  BandedSymmetric<Scalar> A(n, c.bandwidth);
  for (int i = 0; i < n; ++i) {
    for (int j = std::max(0, i - c.bandwidth); j <= i; ++j) A.add(i, j, c.A_dense(i, j));
  }
  return A;
}

DenseLD denseOf(const Case& c) {
  const int n = static_cast<int>(c.A_dense.rows()), m = static_cast<int>(c.D.rows());
  DenseLD K(n + m, n + m);
  K << c.A_dense.cast<long double>(), c.B.cast<long double>(), c.B.transpose().cast<long double>(),
      c.D.cast<long double>();
  return K;
}

template <typename Scalar>
class BorderedBandTest : public ::testing::Test {};
using Precisions = ::testing::Types<double, long double, DoubleDouble>;
TYPED_TEST_SUITE(BorderedBandTest, Precisions);

/// Solves one case both ways; the bordered answer's error against the dense long double one
/// must be within the forward-error bound κ(K)·ε of the two arithmetics (times a modest factor).
template <typename Scalar>
void expectMatchesDense(const Case& c, const char* label) {
  const int n = static_cast<int>(c.A_dense.rows()), m = static_cast<int>(c.D.rows());
  std::mt19937 rng(n + 17 * m);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const Eigen::VectorXd rhs = Eigen::VectorXd::NullaryExpr(n + m, [&]() { return u(rng); });

  BorderedBandedFactor<Scalar> factor;
  ASSERT_TRUE(factor.factor(bandOf<Scalar>(c), c.B, c.D)) << label;
  Eigen::VectorXd x = rhs;
  factor.solve(&x);

  const DenseLD K = denseOf(c);
  const Eigen::PartialPivLU<DenseLD> lu(K);
  const VectorLD reference = lu.solve(rhs.cast<long double>());
  const double condition = 1.0 / static_cast<double>(lu.rcond());  // 1-norm estimate
  constexpr double kForwardErrorFactor = 100.0;
  const double bound =
      kForwardErrorFactor * condition *
      (scalarEpsilon<Scalar>() + static_cast<double>(std::numeric_limits<long double>::epsilon()));
  const double error =
      static_cast<double>((x.cast<long double>() - reference).norm() / reference.norm());
  EXPECT_LE(error, std::max(bound, 1e-15))
      << label << " n " << n << " m " << m << " cond " << condition;
  // Inertia: K has n + n₊(S) positive and n₋(S) negative eigenvalues (counted by Sylvester's
  // law of inertia on a dense LDLᵀ).
  const VectorLD pivots = Eigen::LDLT<DenseLD>(K).vectorD();
  int negative = 0;
  for (int i = 0; i < n + m; ++i) negative += pivots(i) < 0.0L;
  EXPECT_EQ(factor.inertia().negative, negative) << label;
  EXPECT_EQ(factor.inertia().positive + factor.inertia().negative, m) << label;
  EXPECT_EQ(factor.inertia().zero, 0) << label;
}

}  // namespace

TYPED_TEST(BorderedBandTest, MatchesDenseSolveOnRandomPositiveDefiniteSystems) {
  unsigned seed = 1;
  for (int n : {10, 57, 300}) {
    for (int p : {2, 8}) {
      for (int m : {1, 2, 4}) {
        const Case c =
            randomCase(n, p, m, BandKind::DiagonallyDominant, BorderKind::PositiveDefinite, ++seed);
        expectMatchesDense<TypeParam>(c, "positive definite");
      }
    }
  }
}

TYPED_TEST(BorderedBandTest, MatchesDenseSolveWithAnIndefiniteBorder) {
  unsigned seed = 100;
  for (int n : {10, 57, 300}) {
    for (int m : {1, 3, 4}) {
      const Case c =
          randomCase(n, 8, m, BandKind::DiagonallyDominant, BorderKind::Indefinite, ++seed);
      expectMatchesDense<TypeParam>(c, "indefinite");
      BorderedBandedFactor<TypeParam> factor;
      factor.factor(bandOf<TypeParam>(c), c.B, c.D);
      EXPECT_EQ(factor.inertia().negative, m);  // S = −M
    }
  }
}

// The biharmonic band's condition grows as n⁴ (~1e9 at n = 200): the error bound scales with it,
// and the extended precisions must then beat double by orders of magnitude.
TYPED_TEST(BorderedBandTest, MatchesDenseSolveOnIllConditionedBands) {
  unsigned seed = 200;
  for (int n : {40, 200}) {
    for (int m : {1, 4}) {
      for (BorderKind border : {BorderKind::PositiveDefinite, BorderKind::Indefinite}) {
        const Case c = randomCase(n, 4, m, BandKind::Biharmonic, border, ++seed);
        expectMatchesDense<TypeParam>(c, "ill-conditioned");
      }
    }
  }
}

TYPED_TEST(BorderedBandTest, ReportsABandThatIsNotPositiveDefinite) {
  Case c = randomCase(30, 3, 2, BandKind::DiagonallyDominant, BorderKind::PositiveDefinite, 7);
  c.A_dense(12, 12) = -1.0;
  BorderedBandedFactor<TypeParam> factor;
  EXPECT_FALSE(factor.factor(bandOf<TypeParam>(c), c.B, c.D));
  EXPECT_FALSE(factor.inertia().band_positive_definite);
  EXPECT_FALSE(factor.inertia().solvable());
}

TYPED_TEST(BorderedBandTest, ReportsASingularSchurComplement) {
  const Case c = randomCase(50, 8, 3, BandKind::DiagonallyDominant, BorderKind::Singular, 9);
  BorderedBandedFactor<TypeParam> factor;
  EXPECT_FALSE(factor.factor(bandOf<TypeParam>(c), c.B, c.D));
  EXPECT_TRUE(factor.inertia().band_positive_definite);
  EXPECT_EQ(factor.inertia().zero, 3);
}

// Without a border the bordered solve is the banded one (same factor, same substitutions).
TYPED_TEST(BorderedBandTest, WithoutABorderIsTheBandedSolve) {
  const Case c =
      randomCase(40, 8, 0, BandKind::DiagonallyDominant, BorderKind::PositiveDefinite, 11);
  Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(40, -1.0, 2.0), x = b;
  BorderedBandedFactor<TypeParam> factor;
  ASSERT_TRUE(factor.factor(bandOf<TypeParam>(c), c.B, c.D));
  factor.solve(&x);
  ASSERT_TRUE(bandOf<TypeParam>(c).solvePositiveDefinite(&b));
  EXPECT_EQ((x - b).cwiseAbs().maxCoeff(), 0.0);
}

// The Newton systems' half bandwidth (8) is factored and substituted by loops of fixed length away
// from the band's ends (banded_matrix.cpp): the same products in the same order as the general
// loops, so the same bits. The general loops run on the same band stored with one more diagonal,
// zero (each extra product is 0 and leaves its sum unchanged).
TEST(BandedCholesky, NewtonBandwidthGivesTheGeneralLoopsBits) {
  const int n = 60, p = 8;
  for (BandKind kind : {BandKind::DiagonallyDominant, BandKind::Biharmonic}) {
    std::mt19937 rng(kind == BandKind::Biharmonic ? 23 : 21);
    const Eigen::MatrixXd A = randomBand(n, p, kind, &rng);
    BandedSymmetricMatrix fixed(n, p), general(n, p + 1);
    for (int i = 0; i < n; ++i) {
      for (int j = std::max(0, i - p); j <= i; ++j) {
        fixed.add(i, j, A(i, j));
        general.add(i, j, A(i, j));
      }
    }
    const Eigen::VectorXd rhs = Eigen::VectorXd::LinSpaced(n, -1.0, 2.0);
    Eigen::VectorXd x_fixed = rhs, x_general = rhs;
    ASSERT_TRUE(fixed.solvePositiveDefinite(&x_fixed));
    ASSERT_TRUE(general.solvePositiveDefinite(&x_general));
    for (int i = 0; i < n; ++i) EXPECT_EQ(x_fixed(i), x_general(i)) << "row " << i;
    EXPECT_LT((A * x_fixed - rhs).norm(), 1e-12 * A.norm() * x_fixed.norm());  // it solves it
  }
}
