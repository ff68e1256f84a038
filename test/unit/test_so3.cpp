// SO(3) toolkit: exp/log at and near 0 and π, Jacobians against finite differences, quaternions.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>

#include "attitude_planner/lie/so3.hpp"
#include "lie/dual.hpp"
#include "lie/skew_products.hpp"

using namespace attitude_planner;

namespace {

Vector3 randomUnit(std::mt19937& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  return Vector3(n(rng), n(rng), n(rng)).normalized();
}

// R built from the quaternion (cos θ/2, sin θ/2 a): the reference attitude for angle θ.
Matrix3 referenceRotation(const Vector3& axis, double theta) {
  const Eigen::Quaterniond q(std::cos(theta / 2), std::sin(theta / 2) * axis.x(),
                             std::sin(theta / 2) * axis.y(), std::sin(theta / 2) * axis.z());
  return so3::fromQuaternion(q);
}

const double kAngles[] = {0.0,         1e-24,       1e-12,        1e-8, 1.0,
                          M_PI - 1e-3, M_PI - 1e-8, M_PI - 1e-12, M_PI};

}  // namespace

TEST(So3, HatIsCrossProductAndVeeInvertsIt) {
  const Vector3 u(0.3, -1.2, 2.5), v(-0.7, 0.4, 1.1);
  EXPECT_LE((so3::hat(u) * v - u.cross(v)).norm(), 1e-15);
  EXPECT_LE((so3::vee(so3::hat(u)) - u).norm(), 0.0);
  EXPECT_LE((so3::hat(u) + so3::hat(u).transpose()).norm(), 0.0);
  // [û, v̂] = (u × v)^
  const Matrix3 bracket = so3::hat(u) * so3::hat(v) - so3::hat(v) * so3::hat(u);
  EXPECT_LE((bracket - so3::hat(Vector3(u.cross(v)))).norm(), 1e-14);
}

TEST(So3, ExpMatchesQuaternionReferenceAtListedAngles) {
  std::mt19937 rng(7);
  for (double theta : kAngles) {
    for (int trial = 0; trial < 20; ++trial) {
      const Vector3 a = randomUnit(rng);
      const Matrix3 R = so3::exp(Vector3(theta * a));
      EXPECT_LE((R - referenceRotation(a, theta)).cwiseAbs().maxCoeff(), 2e-15)
          << "theta = " << theta;
      EXPECT_LE(so3::orthogonalityError(R), 4e-15);
    }
  }
}

TEST(So3, LogIsExactAtListedAnglesOnRandomAxes) {
  std::mt19937 rng(11);
  for (double theta : kAngles) {
    for (int trial = 0; trial < 50; ++trial) {
      const Vector3 a = randomUnit(rng);
      const Vector3 w = so3::log(referenceRotation(a, theta));
      const Vector3 expected = theta * a;
      double err = (w - expected).norm();
      if (theta == M_PI) err = std::min(err, (w + expected).norm());  // ±π a: same rotation
      // absolute accuracy ~1e-15 everywhere, relative ~1e-15 near 0
      EXPECT_LE(err, 1e-15 * std::max(theta, 1.0) + 1e-15 * theta) << "theta = " << theta;
      if (theta > 0 && theta < 1e-3) {
        EXPECT_LE(err / theta, 4e-16) << "theta = " << theta;
      }
      EXPECT_LE(w.norm(), M_PI + 1e-15);
    }
  }
}

TEST(So3, LogIsExactNearPiWhereAcosIsNot) {
  const Vector3 a = Vector3(1, 2, 3).normalized();
  const double theta = M_PI - 1e-6;
  const Matrix3 R = referenceRotation(a, theta);
  const double via_log = so3::log(R).norm();
  const double via_acos = std::acos(std::min(1.0, std::max(-1.0, (R.trace() - 1.0) / 2.0)));
  EXPECT_LE(std::abs(via_log - theta), 1e-15);
  // the naive route loses about half the digits here: this is why log goes through atan2
  EXPECT_GT(std::abs(via_acos - theta), 1e-12);
}

TEST(So3, LogOfExactlyPiSymmetricMatricesIsDeterministic) {
  Matrix3 R1;
  R1 << 0, -1, 0, -1, 0, 0, 0, 0, -1;
  const Vector3 w1 = so3::log(R1);
  EXPECT_LE((w1 - M_PI * Vector3(1, -1, 0).normalized()).norm(), 1e-15);
  const Vector3 w2 = so3::log(Matrix3(Vector3(1, -1, -1).asDiagonal()));
  EXPECT_LE((w2 - Vector3(M_PI, 0, 0)).norm(), 1e-15);
  const Vector3 w3 = so3::log(Matrix3(Vector3(-1, 1, -1).asDiagonal()));
  EXPECT_LE((w3 - Vector3(0, M_PI, 0)).norm(), 1e-15);
  const Vector3 w4 = so3::log(Matrix3(Vector3(-1, -1, 1).asDiagonal()));
  EXPECT_LE((w4 - Vector3(0, 0, M_PI)).norm(), 1e-15);
  // exp(log R) = R for each of them
  for (const Vector3& w : {w1, w2, w3, w4}) EXPECT_NEAR(w.norm(), M_PI, 1e-15);
  EXPECT_LE((so3::exp(w1) - R1).cwiseAbs().maxCoeff(), 1e-15);
}

TEST(So3, ExpOfLogIsIdentityOnRandomRotations) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> angle(0.0, M_PI);
  for (int trial = 0; trial < 1000; ++trial) {
    const Matrix3 R = so3::exp(Vector3(angle(rng) * randomUnit(rng)));
    EXPECT_LE((so3::exp(so3::log(R)) - R).cwiseAbs().maxCoeff(), 1e-14);
  }
}

TEST(So3, RightJacobianMatchesFiniteDifferences) {
  std::mt19937 rng(5);
  for (double theta : {1e-8, 1e-5, 1.0001e-4, 1e-3, 1e-2, 0.5, 2.0, 3.0}) {
    const Vector3 w = theta * randomUnit(rng);
    const Matrix3 Jr = so3::rightJacobian(w);
    const Matrix3 Jr_inverse = so3::rightJacobianInverse(w);
    const double eps = 1e-6;
    for (int i = 0; i < 3; ++i) {
      const Vector3 e = Vector3::Unit(i) * eps;
      // exp(w + δ) = exp(w) exp(Jr δ)
      const Vector3 fd_jr =
          (so3::log(Matrix3(so3::exp(w).transpose() * so3::exp(Vector3(w + e)))) -
           so3::log(Matrix3(so3::exp(w).transpose() * so3::exp(Vector3(w - e))))) /
          (2 * eps);
      EXPECT_LE((fd_jr - Jr.col(i)).norm(), 1e-8) << "theta = " << theta;
      // log(exp(w) exp(δ)) = w + Jr⁻¹ δ
      const Vector3 fd_inv = (so3::log(Matrix3(so3::exp(w) * so3::exp(e))) -
                              so3::log(Matrix3(so3::exp(w) * so3::exp(Vector3(-e))))) /
                             (2 * eps);
      EXPECT_LE((fd_inv - Jr_inverse.col(i)).norm(), 1e-8) << "theta = " << theta;
    }
    EXPECT_LE((Jr * Jr_inverse - Matrix3::Identity()).norm(), 1e-14) << "theta = " << theta;
    EXPECT_LE((so3::leftJacobian(w) - so3::exp(w) * Jr).norm(), 5e-14);
  }
  EXPECT_LE((so3::rightJacobian(Vector3::Zero()) - Matrix3::Identity()).norm(), 0.0);
}

TEST(So3, DualNumbersGiveTheInverseRightJacobianOfLog) {
  // Exact derivatives through the same templated code: d/dε log(R exp(ε)) = Jr⁻¹(log R).
  using D = Dual<3>;
  for (double theta : {0.0, 1e-9, 1e-3, 1.0, 3.0}) {
    const Vector3 w = theta * Vector3(1, -2, 0.5).normalized();
    so3::Vec3<D> eps(D(0.0, 0), D(0.0, 1), D(0.0, 2));
    const so3::Mat3<D> R = so3::exp<double>(w).cast<D>() * so3::exp<D>(eps);
    const so3::Vec3<D> l = so3::log<D>(R);
    Matrix3 derivative;
    for (int r = 0; r < 3; ++r) derivative.row(r) = l(r).d.transpose();
    EXPECT_LE((derivative - so3::rightJacobianInverse(w)).norm(), 1e-12) << "theta = " << theta;
  }
}

TEST(So3, QuaternionRoundTripAndSignAmbiguity) {
  std::mt19937 rng(9);
  for (int trial = 0; trial < 200; ++trial) {
    const Matrix3 R = so3::exp(Vector3(3.0 * randomUnit(rng)));
    const Eigen::Quaterniond q = so3::toQuaternion(R);
    EXPECT_GE(q.w(), 0.0);
    EXPECT_NEAR(q.norm(), 1.0, 1e-15);
    EXPECT_LE((so3::fromQuaternion(q) - R).cwiseAbs().maxCoeff(), 2e-15);
    const Eigen::Quaterniond minus(-q.w(), -q.x(), -q.y(), -q.z());
    EXPECT_LE((so3::fromQuaternion(minus) - R).cwiseAbs().maxCoeff(), 2e-15);
    // Agrees with Eigen's Hamilton convention
    EXPECT_LE((q.toRotationMatrix() - R).cwiseAbs().maxCoeff(), 2e-15);
  }
  // Near-unit quaternions are normalized
  const Matrix3 R = so3::fromQuaternion(Eigen::Quaterniond(2.0, 0.0, 0.0, 0.0));
  EXPECT_LE((R - Matrix3::Identity()).norm(), 0.0);
}

TEST(So3, ProjectionReturnsTheNearestRotation) {
  std::mt19937 rng(2);
  std::normal_distribution<double> n(0.0, 1e-3);
  const Matrix3 R = so3::exp(Vector3(0.4, -1.0, 2.0));
  Matrix3 noisy = R;
  for (int i = 0; i < 9; ++i) noisy(i) += n(rng);
  const Matrix3 P = so3::projectToSO3(noisy);
  EXPECT_LE(so3::orthogonalityError(P), 4e-15);
  EXPECT_LE((P - R).norm(), 5e-3);
  EXPECT_LE((so3::projectToSO3(R) - R).norm(), 1e-15);
  // A reflection is mapped to a proper rotation
  EXPECT_NEAR(so3::projectToSO3(Matrix3(Vector3(1, 1, -1).asDiagonal())).determinant(), 1.0, 1e-15);
}

TEST(So3, AxisAngleBeyondPiWrapsToTheShortRotation) {
  const Matrix3 R = so3::fromAxisAngle(Vector3(0, 0, 2), 2 * M_PI - 0.1);
  EXPECT_LE((so3::log(R) - Vector3(0, 0, -0.1)).norm(), 1e-15);
  EXPECT_NEAR(so3::angleBetween(Matrix3::Identity(), R), 0.1, 1e-15);
}

TEST(So3, ExpMinusIdentityKeepsRelativePrecisionForSmallRotations) {
  for (double theta : {1e-12, 1e-8, 1e-5, 1e-3, 0.5, 3.0}) {
    const Vector3 w = theta * Vector3(1, -2, 3).normalized();
    const Matrix3 E = so3::expMinusIdentity(w);
    // reference: the series w^ + w^²/2 + w^³/6 + ... summed far enough
    Matrix3 reference = Matrix3::Zero(), term = Matrix3::Identity();
    for (int n = 1; n < 40; ++n) {
      term = term * so3::hat(w) / n;
      reference += term;
    }
    EXPECT_LE((E - reference).norm(), 4e-16 * reference.norm()) << "theta = " << theta;
  }
}

TEST(So3, ExpWithMinusIdentityAgreesWithExpAndExpMinusIdentity) {
  // One Rodrigues evaluation for both (the torques and the stencils use it): the values of the
  // two separate maps to round-off (E to full relative precision), from 0 through π.
  std::mt19937 rng(19);
  for (double theta : kAngles) {
    for (int trial = 0; trial < 10; ++trial) {
      const Vector3 w = theta * randomUnit(rng);
      Matrix3 F, E;
      so3::expWithMinusIdentity<double>(w, &F, &E);
      EXPECT_LE((F - so3::exp(w)).cwiseAbs().maxCoeff(), 4e-16) << "theta = " << theta;
      const Matrix3 reference = so3::expMinusIdentity(w);
      EXPECT_LE((E - reference).cwiseAbs().maxCoeff(), 4e-16 * reference.cwiseAbs().maxCoeff())
          << "theta = " << theta;
    }
  }
}

TEST(So3, QuaternionCompositionOfSmallStepsKeepsRelativePrecision) {
  // log(exp(a) exp(b)) for tiny a, b: the quaternion route keeps ~1e-16 relative precision,
  // where the matrix route keeps only ~eps/|a| (here 1e-8).
  const Vector3 a(1e-8, -2e-8, 0.5e-8), b(3e-8, 1e-8, -1e-8);
  const Vector3 via_quaternions = so3::logOfQuaternion<double>(so3::quaternionProduct<double>(
      so3::quaternionOfRotationVector<double>(a), so3::quaternionOfRotationVector<double>(b)));
  const Vector3 bch = a + b + 0.5 * a.cross(b);  // exact to O(|a|³) = 1e-24
  EXPECT_LE((via_quaternions - bch).norm(), 1e-15 * bch.norm());
}

namespace {
template <typename A, typename B>
bool sameBits(const A& a, const B& b) {
  static_assert(sizeof(typename A::Scalar) == sizeof(double));
  return a.size() == b.size() && std::memcmp(a.data(), b.data(), sizeof(double) * a.size()) == 0;
}
}  // namespace

TEST(SkewProducts, GiveTheDenseProductsBits) {
  // The Newton Hessian's stencils use these in place of the dense products with so3::hat and
  // must keep the plans' bits: every entry the same double, on random operands of mixed scales.
  std::mt19937 rng(59);
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  const auto vector = [&] {
    return Vector3(u(rng), u(rng), u(rng)).cwiseProduct(Vector3(1.0, 1e-3, 1e3)).eval();
  };
  int checked = 0;
  for (int trial = 0; trial < 2000; ++trial) {
    const Vector3 v = vector(), x = vector();
    Matrix3 M;
    for (int i = 0; i < 9; ++i) M.data()[i] = u(rng) * std::pow(10.0, 3 * u(rng));
    const Matrix3 V = so3::hat<double>(v), X = so3::hat<double>(x);
    ASSERT_TRUE(sameBits(so3::hatTimes(v, x), Vector3(V * x))) << trial;
    ASSERT_TRUE(sameBits(so3::hatTimes(v, M), Matrix3(V * M))) << trial;
    ASSERT_TRUE(sameBits(so3::timesHat(M, v), Matrix3(M * V))) << trial;
    ASSERT_TRUE(sameBits(so3::hatTimesHat(v, x), Matrix3(V * X))) << trial;
    // Eigen forms s (V X) as (V s) X: its replacement scales v, not the product.
    const double s = u(rng);
    ASSERT_TRUE(sameBits(so3::hatTimesHat(Vector3(s * v), x), Matrix3(s * (V * X)))) << trial;
    ++checked;
  }
  EXPECT_EQ(checked, 2000);
}
