#include "support/hermite_simpson.hpp"

#include <cmath>

#include "attitude_planner/lie/so3.hpp"

namespace attitude_planner {
namespace peers {

namespace {

using Vector4 = Eigen::Matrix<double, 4, 1>;

/// p ⊗ q = right(q) p (Hamilton, (w, x, y, z)).
Eigen::Matrix4d rightProduct(const Vector4& q) {
  Eigen::Matrix4d R;
  R << q(0), -q(1), -q(2), -q(3), q(1), q(0), q(3), -q(2), q(2), -q(3), q(0), q(1), q(3), q(2),
      -q(1), q(0);
  return R;
}
/// q ⊗ p = left(q) p.
Eigen::Matrix4d leftProduct(const Vector4& q) {
  Eigen::Matrix4d L;
  L << q(0), -q(1), -q(2), -q(3), q(1), q(0), -q(3), q(2), q(2), q(3), q(0), -q(1), q(3), -q(2),
      q(1), q(0);
  return L;
}
Vector4 pure(const Vector3& v) {
  return Vector4(0.0, v(0), v(1), v(2));
}

constexpr double kInfinity = 1e19;

}  // namespace

HermiteSimpsonTranscription::HermiteSimpsonTranscription(const PlanningProblem& problem)
    : N_(problem.steps),
      h_(problem.duration / problem.steps),
      J_(problem.inertia),
      J_inverse_(problem.inertia.inverse()),
      omega0_(problem.initial_velocity),
      omegaT_(problem.final_velocity) {
  q0_ = so3::quaternionCoefficients<double>(problem.initial_attitude);
  qT_ = so3::quaternionCoefficients<double>(problem.final_attitude);
  if (q0_.dot(qT_) < 0.0) qT_ = -qT_;  // the sign nearest the start (the geodesic's end)
  // Jacobian pattern, in jacobianValues' order.
  for (int k = 0; k < N_; ++k) {
    const int L = 2 * k, M = 2 * k + 1, R = 2 * k + 2;
    appendBlock(14 * k, L, true);
    appendBlock(14 * k, M, false);
    appendBlock(14 * k, R, true);
    appendBlock(14 * k + 7, L, true);
    appendBlock(14 * k + 7, M, true);
    appendBlock(14 * k + 7, R, true);
  }
  for (int r = 0; r < 3; ++r)
    for (int a = 0; a < 4; ++a) {
      jac_rows_.push_back(14 * N_ + r);
      jac_cols_.push_back(qIndex(2 * N_) + a);
    }
  // Hessian pattern (lower triangle: Ω indices exceed q indices, τ exceed Ω), per point.
  for (int p = 0; p < points(); ++p) {
    for (int j = 0; j < 3; ++j)
      for (int a = 0; a < 4; ++a) {
        hess_rows_.push_back(omegaIndex(p) + j);
        hess_cols_.push_back(qIndex(p) + a);
      }
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j <= i; ++j) {
        hess_rows_.push_back(omegaIndex(p) + i);
        hess_cols_.push_back(omegaIndex(p) + j);
      }
    for (int i = 0; i < 3; ++i) {
      hess_rows_.push_back(torqueIndex(p) + i);
      hess_cols_.push_back(torqueIndex(p) + i);
    }
  }
}

void HermiteSimpsonTranscription::appendBlock(int r0, int p, bool full) {
  for (int r = 0; r < 7; ++r) {
    if (!full) {
      jac_rows_.push_back(r0 + r);
      jac_cols_.push_back(10 * p + r);
      continue;
    }
    const int first = r < 4 ? 0 : 4, last = r < 4 ? 6 : 9;
    for (int c = first; c <= last; ++c) {
      jac_rows_.push_back(r0 + r);
      jac_cols_.push_back(10 * p + c);
    }
  }
}

double HermiteSimpsonTranscription::weight(int p) const {
  if (p % 2 == 1) return 4.0 * h_ / 6.0;
  return (p == 0 || p == 2 * N_) ? h_ / 6.0 : 2.0 * h_ / 6.0;
}

void HermiteSimpsonTranscription::bounds(double* lower, double* upper) const {
  for (int i = 0; i < variables(); ++i) lower[i] = -kInfinity, upper[i] = kInfinity;
  for (int a = 0; a < 4; ++a) lower[qIndex(0) + a] = upper[qIndex(0) + a] = q0_(a);
  for (int i = 0; i < 3; ++i) {
    lower[omegaIndex(0) + i] = upper[omegaIndex(0) + i] = omega0_(i);
    lower[omegaIndex(2 * N_) + i] = upper[omegaIndex(2 * N_) + i] = omegaT_(i);
  }
}

void HermiteSimpsonTranscription::startingPoint(double* x) const {
  const Matrix3 R0 = so3::matrixFromQuaternion<double>(q0_);
  const Matrix3 RT = so3::matrixFromQuaternion<double>(qT_);
  const Vector3 phi = so3::log(Matrix3(R0.transpose() * RT));
  const double T = h_ * N_;
  for (int p = 0; p < points(); ++p) {
    const double s = time(p) / T;
    Eigen::Map<Vector4>(x + qIndex(p)) = so3::quaternionProduct<double>(
        q0_, so3::quaternionOfRotationVector<double>(Vector3(s * phi)));
    Vector3 omega = phi / T;
    if (p == 0) omega = omega0_;
    if (p == 2 * N_) omega = omegaT_;
    Eigen::Map<Vector3>(x + omegaIndex(p)) = omega;
    Eigen::Map<Vector3>(x + torqueIndex(p)) = -(J_ * omega).cross(omega);
  }
}

double HermiteSimpsonTranscription::objective(const double* x) const {
  double f = 0.0;
  for (int p = 0; p < points(); ++p)
    f += 0.5 * weight(p) * Eigen::Map<const Vector3>(x + torqueIndex(p)).squaredNorm();
  return f;
}

void HermiteSimpsonTranscription::objectiveGradient(const double* x, double* gradient) const {
  for (int i = 0; i < variables(); ++i) gradient[i] = 0.0;
  for (int p = 0; p < points(); ++p)
    for (int i = 0; i < 3; ++i) gradient[torqueIndex(p) + i] = weight(p) * x[torqueIndex(p) + i];
}

HermiteSimpsonTranscription::Vector7 HermiteSimpsonTranscription::dynamics(const double* x,
                                                                           int p) const {
  const Vector4 q(Eigen::Map<const Vector4>(x + qIndex(p)));
  const Vector3 w(Eigen::Map<const Vector3>(x + omegaIndex(p)));
  const Vector3 tau(Eigen::Map<const Vector3>(x + torqueIndex(p)));
  Vector7 f;
  f.head<4>() = 0.5 * leftProduct(q) * pure(w);
  f.tail<3>() = J_inverse_ * ((J_ * w).cross(w) + tau);
  return f;
}

Eigen::Matrix<double, 7, 10> HermiteSimpsonTranscription::dynamicsJacobian(const double* x,
                                                                           int p) const {
  const Vector4 q(Eigen::Map<const Vector4>(x + qIndex(p)));
  const Vector3 w(Eigen::Map<const Vector3>(x + omegaIndex(p)));
  Eigen::Matrix<double, 7, 10> D = Eigen::Matrix<double, 7, 10>::Zero();
  D.block<4, 4>(0, 0) = 0.5 * rightProduct(pure(w));
  D.block<4, 3>(0, 4) = 0.5 * leftProduct(q).rightCols<3>();
  D.block<3, 3>(4, 4) = J_inverse_ * (so3::hat(Vector3(J_ * w)) - so3::hat(w) * J_);
  D.block<3, 3>(4, 7) = J_inverse_;
  return D;
}

void HermiteSimpsonTranscription::constraintValues(const double* x, double* values) const {
  using Map7 = Eigen::Map<const Vector7>;
  for (int k = 0; k < N_; ++k) {
    const int L = 2 * k, M = 2 * k + 1, R = 2 * k + 2;
    const Vector7 fL = dynamics(x, L), fM = dynamics(x, M), fR = dynamics(x, R);
    const Map7 xL(x + 10 * L), xM(x + 10 * M), xR(x + 10 * R);
    Eigen::Map<Vector7>(values + 14 * k) = xM - 0.5 * (xL + xR) - h_ / 8.0 * (fL - fR);
    Eigen::Map<Vector7>(values + 14 * k + 7) = xR - xL - h_ / 6.0 * (fL + 4.0 * fM + fR);
  }
  const Vector4 conj(qT_(0), -qT_(1), -qT_(2), -qT_(3));
  const Vector4 qN(Eigen::Map<const Vector4>(x + qIndex(2 * N_)));
  Eigen::Map<Vector3>(values + 14 * N_) = (leftProduct(conj) * qN).tail<3>();
}

void HermiteSimpsonTranscription::jacobianValues(const double* x, double* values) const {
  std::size_t z = 0;
  const auto block = [&](const Eigen::Matrix<double, 7, 10>& D, double a, double b, bool full) {
    for (int r = 0; r < 7; ++r) {
      if (!full) {
        values[z++] = a;
        continue;
      }
      const int first = r < 4 ? 0 : 4, last = r < 4 ? 6 : 9;
      for (int c = first; c <= last; ++c) values[z++] = (r == c ? a : 0.0) + b * D(r, c);
    }
  };
  std::vector<Eigen::Matrix<double, 7, 10>> D(points());
  for (int p = 0; p < points(); ++p) D[p] = dynamicsJacobian(x, p);
  for (int k = 0; k < N_; ++k) {
    const int L = 2 * k, M = 2 * k + 1, R = 2 * k + 2;
    block(D[L], -0.5, -h_ / 8.0, true);
    block(D[M], 1.0, 0.0, false);
    block(D[R], -0.5, h_ / 8.0, true);
    block(D[L], -1.0, -h_ / 6.0, true);
    block(D[M], 0.0, -4.0 * h_ / 6.0, true);
    block(D[R], 1.0, -h_ / 6.0, true);
  }
  const Vector4 conj(qT_(0), -qT_(1), -qT_(2), -qT_(3));
  const Eigen::Matrix4d Lc = leftProduct(conj);
  for (int r = 0; r < 3; ++r)
    for (int a = 0; a < 4; ++a) values[z++] = Lc(r + 1, a);
}

void HermiteSimpsonTranscription::hessianValues(const double* x, double sigma, const double* lambda,
                                                double* values) const {
  using Map7 = Eigen::Map<const Vector7>;
  std::size_t z = 0;
  for (int p = 0; p < points(); ++p) {
    // ν_p: the multipliers of the rows that touch point p, times the coefficient of f_p there.
    Vector7 nu = Vector7::Zero();
    if (p % 2 == 1) {
      nu = -4.0 * h_ / 6.0 * Map7(lambda + 14 * (p / 2) + 7);
    } else {
      const int k = p / 2;
      if (k < N_) nu += -h_ / 8.0 * Map7(lambda + 14 * k) - h_ / 6.0 * Map7(lambda + 14 * k + 7);
      if (k > 0)
        nu += h_ / 8.0 * Map7(lambda + 14 * (k - 1)) - h_ / 6.0 * Map7(lambda + 14 * (k - 1) + 7);
    }
    const Vector4 nu_q = nu.head<4>();
    // ∂²(ν_qᵀ ½ q ⊗ (0, Ω))/∂Ω_j ∂q = ½ right((0, e_j))ᵀ ν_q.
    for (int j = 0; j < 3; ++j) {
      const Vector4 column = 0.5 * rightProduct(pure(Vector3::Unit(j))).transpose() * nu_q;
      for (int a = 0; a < 4; ++a) values[z++] = column(a);
    }
    // ∂²(wᵀ (JΩ) × Ω)/∂Ω² = ŵ J − J ŵ, w = J⁻¹ ν_Ω.
    const Vector3 w = J_inverse_ * nu.tail<3>();
    const Matrix3 H = so3::hat(w) * J_ - J_ * so3::hat(w);
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j <= i; ++j) values[z++] = H(i, j);
    for (int i = 0; i < 3; ++i) values[z++] = sigma * weight(p);
  }
  (void)x;  // the Hessian of f is constant in x (f is polynomial of degree 2)
}

std::vector<Vector3> HermiteSimpsonTranscription::torques(const double* x) const {
  std::vector<Vector3> tau(points());
  for (int p = 0; p < points(); ++p) tau[p] = Eigen::Map<const Vector3>(x + torqueIndex(p));
  return tau;
}

}  // namespace peers
}  // namespace attitude_planner
