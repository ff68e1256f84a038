#include "attitude_planner/dynamics/effects.hpp"

namespace attitude_planner {

std::vector<std::string> EffectModel::names() const {
  std::vector<std::string> out;
  for (const auto& e : effects_) out.push_back(e->name());
  return out;
}

Vector3 EffectModel::torque(const Matrix3& R, double t) const {
  Vector3 sum = Vector3::Zero();
  for (const auto& e : effects_) sum += e->torque(R, t);
  return sum;
}

Matrix3 EffectModel::jacobian(const Matrix3& R, double t) const {
  Matrix3 sum = Matrix3::Zero();
  for (const auto& e : effects_) sum += e->jacobian(R, t);
  return sum;
}

Matrix3 EffectModel::weightedSecondDerivative(const Matrix3& R, double t, const Vector3& w) const {
  Matrix3 sum = Matrix3::Zero();
  for (const auto& e : effects_) sum += e->weightedSecondDerivative(R, t, w);
  return sum;
}

void Actuation::setNoise(const Vector3& std_dev, std::uint64_t seed) {
  noise_std_ = std_dev;
  has_noise_ = true;
  rng_.seed(seed);
}

Vector3 Actuation::apply(const Vector3& commanded) {
  Vector3 tau = commanded;
  if (has_limits_) tau = tau.cwiseMax(-limits_).cwiseMin(limits_);
  if (has_noise_) {
    std::normal_distribution<double> unit(0.0, 1.0);
    for (int i = 0; i < 3; ++i) tau(i) += noise_std_(i) * unit(rng_);
  }
  return tau;
}

}  // namespace attitude_planner
