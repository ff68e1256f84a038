#include "attitude_planner/dynamics/effects.hpp"

namespace attitude_planner {

DisturbanceTorque::DisturbanceTorque(const Vector3& value, TorqueFrame frame)
    : value_(value), in_world_(frame == TorqueFrame::World) {}

Vector3 DisturbanceTorque::torque(const Matrix3& R, double) const {
  return in_world_ ? Vector3(R.transpose() * value_) : value_;
}

std::optional<Vector3> DisturbanceTorque::constantWorldTorque() const {
  if (!in_world_) return std::nullopt;
  return value_;
}

std::optional<Vector3> DisturbanceTorque::constantBodyTorque() const {
  if (in_world_) return std::nullopt;
  return value_;
}

Matrix3 DisturbanceTorque::jacobian(const Matrix3& R, double) const {
  // world frame: τ = exp(−δ^) Rᵀ w ≈ Rᵀw + (Rᵀw)^ δ
  return in_world_ ? so3::hat(Vector3(R.transpose() * value_)) : Matrix3::Zero().eval();
}

Matrix3 DisturbanceTorque::weightedSecondDerivative(const Matrix3& R, double,
                                                    const Vector3& w) const {
  if (!in_world_) return Matrix3::Zero();
  // J(δ) = v(δ)^ with v(δ) = v + v^ δ, so ∂J/∂δ_l = (v × e_l)^ and
  // T(m, l) = Σ_i w_i ∂J(i, m)/∂δ_l = ((v × e_l)^ᵀ w)_m = (w × (v × e_l))_m = (w^ v^)(m, l).
  const Vector3 v = R.transpose() * value_;
  const Matrix3 T = so3::hat(w) * so3::hat(v);
  return 0.5 * (T + T.transpose());
}

EffectTimeDerivatives DisturbanceTorque::timeDerivatives(const Matrix3&, double) const {
  return {};
}

}  // namespace attitude_planner
