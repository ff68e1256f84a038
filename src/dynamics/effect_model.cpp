#include "attitude_planner/dynamics/effects.hpp"

namespace attitude_planner {

namespace {

/// An effect read on a clock moved on by a fixed offset (EffectModel::timeShifted).
class TimeShiftedEffect : public TorqueEffect {
 public:
  TimeShiftedEffect(std::shared_ptr<const TorqueEffect> effect, double offset)
      : effect_(std::move(effect)), offset_(offset) {}
  std::string name() const override { return effect_->name(); }
  Vector3 torque(const Matrix3& R, double t) const override {
    return effect_->torque(R, t + offset_);
  }
  Matrix3 jacobian(const Matrix3& R, double t) const override {
    return effect_->jacobian(R, t + offset_);
  }
  Matrix3 weightedSecondDerivative(const Matrix3& R, double t, const Vector3& w) const override {
    return effect_->weightedSecondDerivative(R, t + offset_, w);
  }
  EffectTimeDerivatives timeDerivatives(const Matrix3& R, double t) const override {
    return effect_->timeDerivatives(R, t + offset_);
  }
  /// A constant in the world frame stays one on a shifted clock.
  std::optional<Vector3> constantWorldTorque() const override {
    return effect_->constantWorldTorque();
  }

 private:
  std::shared_ptr<const TorqueEffect> effect_;
  double offset_;
};

}  // namespace

EffectModel EffectModel::timeShifted(double offset) const {
  EffectModel shifted;
  for (const auto& e : effects_) shifted.add(std::make_unique<TimeShiftedEffect>(e, offset));
  return shifted;
}

std::vector<std::string> EffectModel::names() const {
  std::vector<std::string> out;
  for (const auto& e : effects_) out.push_back(e->name());
  return out;
}

namespace {
/// Σ of every effect's constant (`constant` one of TorqueEffect's constant…Torque) when each
/// has one; none otherwise.
std::optional<Vector3> sumOfConstants(
    const std::vector<std::shared_ptr<const TorqueEffect>>& effects,
    std::optional<Vector3> (TorqueEffect::*constant)() const) {
  Vector3 sum = Vector3::Zero();
  for (const auto& e : effects) {
    const std::optional<Vector3> t = ((*e).*constant)();
    if (!t) return std::nullopt;
    sum += *t;
  }
  return sum;
}
}  // namespace

std::optional<Vector3> EffectModel::constantBodyTorque() const {
  return sumOfConstants(effects_, &TorqueEffect::constantBodyTorque);
}

std::optional<Vector3> EffectModel::constantWorldTorque() const {
  return sumOfConstants(effects_, &TorqueEffect::constantWorldTorque);
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

EffectTimeDerivatives EffectModel::timeDerivatives(const Matrix3& R, double t) const {
  EffectTimeDerivatives sum;
  for (const auto& e : effects_) {
    const EffectTimeDerivatives d = e->timeDerivatives(R, t);
    sum.torque_rate += d.torque_rate;
    sum.torque_acceleration += d.torque_acceleration;
    sum.jacobian_rate += d.jacobian_rate;
  }
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
