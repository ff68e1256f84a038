// SO(3) toolkit: hat/vee, exp, log, Jacobians, quaternions, projection.
//
// Conventions (docs/DESIGN.md): R maps body vectors to the world; quaternions are Hamilton (w, x,
// y, z); perturbations are on the right, R exp(ε^), so Jacobians act on body-frame tangent vectors.
// Every function is a template on the scalar type so that the solvers can evaluate the same code
// with forward-mode dual numbers (exact derivatives); the double versions are the everyday API.
#pragma once

#include <Eigen/Core>
#include <Eigen/Geometry>
#include <cmath>

namespace attitude_planner {

using Vector3 = Eigen::Vector3d;
using Matrix3 = Eigen::Matrix3d;

namespace so3 {

template <typename S>
using Vec3 = Eigen::Matrix<S, 3, 1>;
template <typename S>
using Mat3 = Eigen::Matrix<S, 3, 3>;

/// Below this rotation angle [rad] exp/log/Jacobians switch to Taylor series; the truncation
/// error of the series used is far below machine epsilon there.
constexpr double kSmallAngle = 1e-4;

/// v ↦ v^, the skew matrix with v^ w = v × w.
template <typename S>
Mat3<S> hat(const Vec3<S>& v) {
  Mat3<S> m;
  m << S(0), -v.z(), v.y(), v.z(), S(0), -v.x(), -v.y(), v.x(), S(0);
  return m;
}

/// The inverse of hat, applied to the skew part of m: vee(m) = ((m − mᵀ)/2)^∨.
template <typename S>
Vec3<S> vee(const Mat3<S>& m) {
  return Vec3<S>(m(2, 1) - m(1, 2), m(0, 2) - m(2, 0), m(1, 0) - m(0, 1)) * S(0.5);
}

/// Rodrigues coefficients of exp(w^) = I + a w^ + b w^², a = sin θ/θ, b = (1 − cos θ)/θ², from
/// θ² = |w|²: Taylor series below kSmallAngle, half-angle forms (no cancellation) above.
template <typename S>
void rodriguesCoefficients(const S& theta2, S* a, S* b) {
  using std::sin;
  using std::sqrt;
  if (theta2 < S(kSmallAngle * kSmallAngle)) {
    *a = S(1) - theta2 / S(6) + theta2 * theta2 / S(120);
    *b = S(0.5) - theta2 / S(24) + theta2 * theta2 / S(720);
  } else {
    const S theta = sqrt(theta2);
    const S half_sin = sin(theta / S(2));
    *a = sin(theta) / theta;
    *b = S(2) * half_sin * half_sin / theta2;
  }
}

/// Exponential map (Rodrigues), exact at 0 through its Taylor series.
template <typename S>
Mat3<S> exp(const Vec3<S>& w) {
  S a, b;
  rodriguesCoefficients<S>(w.squaredNorm(), &a, &b);
  const Mat3<S> W = hat(w);
  return Mat3<S>::Identity() + a * W + b * (W * W);
}

/// exp(w^) − I = a w^ + b w^², formed without subtracting I: full relative precision for small w,
/// where exp(w^) itself is I plus only a few significant digits of w.
template <typename S>
Mat3<S> expMinusIdentity(const Vec3<S>& w) {
  S a, b;
  rodriguesCoefficients<S>(w.squaredNorm(), &a, &b);
  const Mat3<S> W = hat(w);
  return a * W + b * (W * W);
}

/// exp(w^) and exp(w^) − I from one evaluation of the Rodrigues coefficients, each formed by the
/// same expression as exp and expMinusIdentity (the same values: a plan does not depend on which
/// of them a caller used).
template <typename S>
void expWithMinusIdentity(const Vec3<S>& w, Mat3<S>* F, Mat3<S>* E) {
  S a, b;
  rodriguesCoefficients<S>(w.squaredNorm(), &a, &b);
  const Mat3<S> W = hat(w);
  *F = Mat3<S>::Identity() + a * W + b * (W * W);
  *E = a * W + b * (W * W);
}

/// Unit quaternion (w, x, y, z) of exp(v^): (cos θ/2, sin(θ/2)/θ · v), full relative precision in
/// the vector part for small v (series below kSmallAngle).
template <typename S>
Eigen::Matrix<S, 4, 1> quaternionOfRotationVector(const Vec3<S>& v) {
  using std::cos;
  using std::sin;
  using std::sqrt;
  const S theta2 = v.squaredNorm();
  S c, k;  // cos(θ/2), sin(θ/2)/θ
  if (theta2 < S(kSmallAngle * kSmallAngle)) {
    c = S(1) - theta2 / S(8) + theta2 * theta2 / S(384);
    k = S(0.5) - theta2 / S(48) + theta2 * theta2 / S(3840);
  } else {
    const S theta = sqrt(theta2);
    c = cos(theta / S(2));
    k = sin(theta / S(2)) / theta;
  }
  Eigen::Matrix<S, 4, 1> q;
  q << c, k * v.x(), k * v.y(), k * v.z();
  return q;
}

/// Hamilton product of quaternions (w, x, y, z).
template <typename S>
Eigen::Matrix<S, 4, 1> quaternionProduct(const Eigen::Matrix<S, 4, 1>& p,
                                         const Eigen::Matrix<S, 4, 1>& q) {
  const Vec3<S> pv = p.template tail<3>(), qv = q.template tail<3>();
  Eigen::Matrix<S, 4, 1> r;
  r(0) = p(0) * q(0) - pv.dot(qv);
  r.template tail<3>() = p(0) * qv + q(0) * pv + pv.cross(qv);
  return r;
}

/// Unit quaternion (w, x, y, z) of a rotation matrix by Shepperd's method: the largest of the four
/// squared components is taken from the diagonal, the others from sums/differences, so every
/// component keeps full relative accuracy, including at π where w → 0.
template <typename S>
Eigen::Matrix<S, 4, 1> quaternionCoefficients(const Mat3<S>& R) {
  using std::sqrt;
  Eigen::Matrix<S, 4, 1> q;  // (w, x, y, z)
  const S t = R(0, 0) + R(1, 1) + R(2, 2);
  if (t >= R(0, 0) && t >= R(1, 1) && t >= R(2, 2)) {
    const S r = sqrt(S(1) + t);
    const S s = S(0.5) / r;
    q << S(0.5) * r, (R(2, 1) - R(1, 2)) * s, (R(0, 2) - R(2, 0)) * s, (R(1, 0) - R(0, 1)) * s;
  } else if (R(0, 0) >= R(1, 1) && R(0, 0) >= R(2, 2)) {
    const S r = sqrt(S(1) + R(0, 0) - R(1, 1) - R(2, 2));
    const S s = S(0.5) / r;
    q << (R(2, 1) - R(1, 2)) * s, S(0.5) * r, (R(0, 1) + R(1, 0)) * s, (R(0, 2) + R(2, 0)) * s;
  } else if (R(1, 1) >= R(2, 2)) {
    const S r = sqrt(S(1) - R(0, 0) + R(1, 1) - R(2, 2));
    const S s = S(0.5) / r;
    q << (R(0, 2) - R(2, 0)) * s, (R(0, 1) + R(1, 0)) * s, S(0.5) * r, (R(1, 2) + R(2, 1)) * s;
  } else {
    const S r = sqrt(S(1) - R(0, 0) - R(1, 1) + R(2, 2));
    const S s = S(0.5) / r;
    q << (R(1, 0) - R(0, 1)) * s, (R(0, 2) + R(2, 0)) * s, (R(1, 2) + R(2, 1)) * s, S(0.5) * r;
  }
  if (q(0) < S(0)) q = -q;  // q and −q are the same rotation: take the one with w ≥ 0
  return q;
}

/// Rotation vector of a unit quaternion (w, x, y, z): angle 2·atan2(|v|, w) ∈ [0, π] for w ≥ 0.
/// atan2 keeps full accuracy at π (acos does not); a series is used for small |v|.
template <typename S>
Vec3<S> logOfQuaternion(const Eigen::Matrix<S, 4, 1>& q_in) {
  using std::atan2;
  using std::sqrt;
  Eigen::Matrix<S, 4, 1> q = q_in;
  if (q(0) < S(0)) q = -q;  // w = 0 exactly (angle π) is left as given
  const Vec3<S> v = q.template tail<3>();
  const S w = q(0);
  const S s2 = v.squaredNorm();
  if (s2 < S(kSmallAngle * kSmallAngle) * w * w) {
    // 2 atan(s/w)/s = (2/w)(1 − x/3 + x²/5 − x³/7), x = (s/w)²  (w ≈ 1 here)
    const S x = s2 / (w * w);
    return v * (S(2) / w * (S(1) - x / S(3) + x * x / S(5) - x * x * x / S(7)));
  }
  const S s = sqrt(s2);
  return v * (S(2) * atan2(s, w) / s);
}

/// Logarithm map SO(3) → R³ (principal branch, angle in [0, π]); exact near 0 and π.
/// At exactly π the two opposite vectors are the same rotation; the one returned has the first
/// nonzero component of the axis positive (deterministic).
template <typename S>
Vec3<S> log(const Mat3<S>& R) {
  Eigen::Matrix<S, 4, 1> q = quaternionCoefficients<S>(R);
  if (q(0) == S(0)) {  // exactly π: pick the axis whose first nonzero component is positive
    for (int i = 1; i < 4; ++i) {
      if (q(i) != S(0)) {
        if (q(i) < S(0)) q = -q;
        break;
      }
    }
  }
  return logOfQuaternion<S>(q);
}

/// Right Jacobian Jr(w): exp(w + δ) = exp(w) exp(Jr(w) δ) + O(δ²).
template <typename S>
Mat3<S> rightJacobian(const Vec3<S>& w) {
  using std::cos;
  using std::sin;
  using std::sqrt;
  const S theta2 = w.squaredNorm();
  S a, b;  // Jr = I − a w^ + b w^²
  if (theta2 < S(kSmallAngle * kSmallAngle)) {
    a = S(0.5) - theta2 / S(24) + theta2 * theta2 / S(720);
    b = S(1.0 / 6.0) - theta2 / S(120) + theta2 * theta2 / S(5040);
  } else {
    const S theta = sqrt(theta2);
    const S half_sin = sin(theta / S(2));
    a = S(2) * half_sin * half_sin / theta2;  // (1 − cos θ)/θ² without cancellation
    b = (theta - sin(theta)) / (theta2 * theta);
  }
  const Mat3<S> W = hat(w);
  return Mat3<S>::Identity() - a * W + b * (W * W);
}

/// Inverse right Jacobian: log(exp(w) exp(δ)) = w + Jr⁻¹(w) δ + O(δ²). Singular at |w| = 2π.
/// The coefficient c(θ²) of Jr⁻¹(w) = I + ½ w^ + c w^², θ² = |w|².
template <typename S>
S rightJacobianInverseCoefficient(const S& theta2) {
  using std::cos;
  using std::sin;
  using std::sqrt;
  if (theta2 < S(kSmallAngle * kSmallAngle)) {
    return S(1.0 / 12.0) + theta2 / S(720) + theta2 * theta2 / S(30240);
  }
  const S half = sqrt(theta2) / S(2);
  // (1 − θ sin θ / (2(1 − cos θ)))/θ² = (1 − (θ/2) cot(θ/2))/θ²: no 1 − cos θ to cancel
  return (S(1) - half * cos(half) / sin(half)) / theta2;
}

/// dc/d(θ²) of rightJacobianInverseCoefficient (for exact second derivatives of the log map):
/// series Σ_{n≥2} (n−1)|B_2n| θ^(2n−4)/(2n)! below θ = 0.1, where the closed form cancels.
double rightJacobianInverseCoefficientDerivative(double theta2);

template <typename S>
Mat3<S> rightJacobianInverse(const Vec3<S>& w) {
  const Mat3<S> W = hat(w);
  return Mat3<S>::Identity() + S(0.5) * W +
         rightJacobianInverseCoefficient<S>(w.squaredNorm()) * (W * W);
}

/// Left Jacobian: Jl(w) = Jr(−w) = exp(w) Jr(w).
template <typename S>
Mat3<S> leftJacobian(const Vec3<S>& w) {
  return rightJacobian<S>(Vec3<S>(-w));
}

/// Rotation matrix of a quaternion (w, x, y, z); the quaternion is normalized first.
template <typename S>
Mat3<S> matrixFromQuaternion(const Eigen::Matrix<S, 4, 1>& q_in) {
  const Eigen::Matrix<S, 4, 1> q = q_in / q_in.norm();
  const S w = q(0), x = q(1), y = q(2), z = q(3);
  Mat3<S> R;
  R << S(1) - S(2) * (y * y + z * z), S(2) * (x * y - w * z), S(2) * (x * z + w * y),
      S(2) * (x * y + w * z), S(1) - S(2) * (x * x + z * z), S(2) * (y * z - w * x),
      S(2) * (x * z - w * y), S(2) * (y * z + w * x), S(1) - S(2) * (x * x + y * y);
  return R;
}

// ---- double-precision conveniences -------------------------------------------------------------

inline Matrix3 hat(const Vector3& v) {
  return hat<double>(v);
}
inline Vector3 vee(const Matrix3& m) {
  return vee<double>(m);
}
inline Matrix3 exp(const Vector3& w) {
  return exp<double>(w);
}
inline Vector3 log(const Matrix3& R) {
  return log<double>(R);
}
inline Matrix3 rightJacobian(const Vector3& w) {
  return rightJacobian<double>(w);
}
inline Matrix3 rightJacobianInverse(const Vector3& w) {
  return rightJacobianInverse<double>(w);
}
inline Matrix3 leftJacobian(const Vector3& w) {
  return leftJacobian<double>(w);
}

/// Hamilton quaternion of R, with w ≥ 0.
Eigen::Quaterniond toQuaternion(const Matrix3& R);
/// Rotation matrix of a quaternion (normalized first).
Matrix3 fromQuaternion(const Eigen::Quaterniond& q);
/// Rotation by `angle` [rad] about `axis` (normalized first; any angle, including > π).
Matrix3 fromAxisAngle(const Vector3& axis, double angle);
/// Nearest rotation matrix in the Frobenius norm (SVD; det fixed to +1).
Matrix3 projectToSO3(const Matrix3& M);
/// ‖RᵀR − I‖ (max abs entry) + |det R − 1|: how far R is from the group.
double orthogonalityError(const Matrix3& R);
/// Geodesic distance ‖log(Aᵀ B)‖ [rad].
double angleBetween(const Matrix3& A, const Matrix3& B);

}  // namespace so3
}  // namespace attitude_planner
