#include <cmath>

#include "attitude_planner/dynamics/effects.hpp"
#include "attitude_planner/errors.hpp"
#include "lie/dual.hpp"

namespace attitude_planner {

namespace {

/// τ(b) = 3n² (b × J b) and ∂τ/∂δ = 3n² (b^ J − (J b)^) b^ for b(δ) = exp(−δ^) b (db/dδ = b^).
template <typename S>
so3::Mat3<S> gravityGradientJacobian(const so3::Vec3<S>& b, const Matrix3& J, double n2) {
  const so3::Mat3<S> Js = J.cast<S>();
  const so3::Vec3<S> Jb = Js * b;
  return S(3.0 * n2) * ((so3::hat<S>(b) * Js - so3::hat<S>(Jb)) * so3::hat<S>(b));
}

}  // namespace

GravityGradient::GravityGradient(double mu, double orbit_radius, const Matrix3& inertia)
    : J_(inertia) {
  if (!(mu > 0) || !(orbit_radius > 0) || !std::isfinite(mu) || !std::isfinite(orbit_radius)) {
    throw InvalidInput("gravity_gradient: mu and orbit_radius must be finite and > 0, got mu = " +
                       std::to_string(mu) + ", orbit_radius = " + std::to_string(orbit_radius));
  }
  n_ = std::sqrt(mu / (orbit_radius * orbit_radius * orbit_radius));
}

Vector3 GravityGradient::radial(double t) const {
  return Vector3(std::cos(n_ * t), std::sin(n_ * t), 0.0);
}

Vector3 GravityGradient::torque(const Matrix3& R, double t) const {
  const Vector3 b = R.transpose() * radial(t);
  return 3.0 * n_ * n_ * b.cross(J_ * b);
}

Matrix3 GravityGradient::jacobian(const Matrix3& R, double t) const {
  return gravityGradientJacobian<double>(Vector3(R.transpose() * radial(t)), J_, n_ * n_);
}

Matrix3 GravityGradient::weightedSecondDerivative(const Matrix3& R, double t,
                                                  const Vector3& w) const {
  // Differentiate the analytic Jacobian along b(δ) = b + b^ δ (first order is all it needs).
  using D = Dual<3>;
  const Vector3 b = R.transpose() * radial(t);
  const Matrix3 db = so3::hat(b);
  so3::Vec3<D> bd;
  for (int i = 0; i < 3; ++i) {
    bd(i) = D(b(i));
    for (int e = 0; e < 3; ++e) bd(i).d(e) = db(i, e);
  }
  const so3::Mat3<D> Jd = gravityGradientJacobian<D>(bd, J_, n_ * n_);
  Matrix3 T = Matrix3::Zero();  // T(m, l) = Σ_i w_i ∂J(i, m)/∂δ_l
  for (int i = 0; i < 3; ++i) {
    for (int m = 0; m < 3; ++m) T.row(m) += w(i) * Jd(i, m).d.transpose();
  }
  return 0.5 * (T + T.transpose());
}

EffectTimeDerivatives GravityGradient::timeDerivatives(const Matrix3& R, double t) const {
  // b = Rᵀr̂(t) moves as b' = Rᵀr̂', b'' = −n² b. τ = c b × Jb (c = 3n²) is bilinear in b:
  // τ' = c (b' × Jb + b × Jb'), τ'' = c (b'' × Jb + 2 b' × Jb' + b × Jb''); the Jacobian
  // c (b^J − (Jb)^) b^ likewise: ∂/∂t = c ((b'^J − (Jb')^) b^ + (b^J − (Jb)^) b'^).
  const double c = 3.0 * n_ * n_;
  const Vector3 b = R.transpose() * radial(t);
  const Vector3 db = R.transpose() * Vector3(-n_ * std::sin(n_ * t), n_ * std::cos(n_ * t), 0.0);
  const Vector3 ddb = -n_ * n_ * b;
  const auto hat = [](const Vector3& v) { return so3::hat<double>(v); };
  EffectTimeDerivatives d;
  d.torque_rate = c * (db.cross(J_ * b) + b.cross(J_ * db));
  d.torque_acceleration = c * (ddb.cross(J_ * b) + 2.0 * db.cross(J_ * db) + b.cross(J_ * ddb));
  d.jacobian_rate =
      c * ((hat(db) * J_ - hat(J_ * db)) * hat(b) + (hat(b) * J_ - hat(J_ * b)) * hat(db));
  return d;
}

}  // namespace attitude_planner
