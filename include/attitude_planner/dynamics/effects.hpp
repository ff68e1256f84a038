// Physical effects a scene may call for: only the effects a scene lists are simulated.
//
// Plannable effects are known external torques τ_e(R_k, t_k) [N m, body frame] that enter the
// discrete dynamics as a forcing term alongside the control, at the node (DiscreteScheme):
//     μ(F_k) = F_{k−1}ᵀ μ(F_{k−1}) + h (τ_k + τ_e(R_k, t_k)).
// For the `variational` scheme this is the discrete Lagrange–d'Alembert forcing, not a potential
// in the discrete Lagrangian (documented choice: one forcing rule for both schemes).
// Tracker-only effects (actuator saturation, torque noise) act on the commanded torque.
#pragma once

#include <memory>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "attitude_planner/lie/so3.hpp"
#include "attitude_planner/name_table.hpp"

namespace attitude_planner {

/// The effects a scene or a request may list (plannable torques and tracker-side actuation).
enum class EffectKind { GravityGradient, DisturbanceTorque, ActuatorLimits, TorqueNoise };

/// The names of the effects (scene keys under `effects:`, Effect.msg `type`, JSON `effects`).
inline constexpr NamedValue<EffectKind> kEffectKindNames[] = {
    {EffectKind::GravityGradient, "gravity_gradient"},
    {EffectKind::DisturbanceTorque, "disturbance_torque"},
    {EffectKind::ActuatorLimits, "actuator_limits"},
    {EffectKind::TorqueNoise, "torque_noise"},
};

/// "gravity_gradient", "disturbance_torque", "actuator_limits" or "torque_noise".
inline std::string effectKindName(EffectKind kind) {
  return nameIn(kEffectKindNames, kind);
}
/// The effect named `text`; throws InvalidInput naming `field`, the value and the accepted names.
inline EffectKind parseEffectKind(const std::string& text, const std::string& field) {
  return parseIn(kEffectKindNames, text, field);
}

/// The frame a constant torque is given in.
enum class TorqueFrame { Body, World };

/// The names of the frames (disturbance_torque `frame`, scene and Effect.msg).
inline constexpr NamedValue<TorqueFrame> kTorqueFrameNames[] = {
    {TorqueFrame::Body, "body"},
    {TorqueFrame::World, "world"},
};

/// "body" or "world".
inline std::string torqueFrameName(TorqueFrame frame) {
  return nameIn(kTorqueFrameNames, frame);
}
/// The frame named `text`; throws InvalidInput naming `field`, the value and the accepted names.
inline TorqueFrame parseTorqueFrame(const std::string& text, const std::string& field) {
  return parseIn(kTorqueFrameNames, text, field);
}

/// How an effect's torque and Jacobian change with time at a fixed attitude: what the
/// transcription needs when the time step h is an unknown (t_k = k h moves with h).
struct EffectTimeDerivatives {
  Vector3 torque_rate = Vector3::Zero();          ///< ∂τ_e/∂t [N m/s]
  Vector3 torque_acceleration = Vector3::Zero();  ///< ∂²τ_e/∂t² [N m/s²]
  Matrix3 jacobian_rate = Matrix3::Zero();        ///< ∂(∂τ_e/∂δ)/∂t [N m/(rad s)]
};

/// A known external torque on the body.
class TorqueEffect {
 public:
  virtual ~TorqueEffect() = default;
  /// The scene key ("gravity_gradient", ...).
  virtual std::string name() const = 0;
  /// τ_e(R, t) [N m], body frame.
  virtual Vector3 torque(const Matrix3& R, double t) const = 0;
  /// ∂τ_e(R exp(δ^), t)/∂δ at δ = 0 [N m / rad].
  virtual Matrix3 jacobian(const Matrix3& R, double t) const = 0;
  /// sym(Σ_i w_i ∂(jacobian row i)(R exp(δ^))/∂δ) at δ = 0: the w-weighted second derivative
  /// the Newton solver's exact Hessian needs (the antisymmetric rest is the retraction's term).
  virtual Matrix3 weightedSecondDerivative(const Matrix3& R, double t, const Vector3& w) const = 0;
  /// The exact time derivatives of torque() and jacobian() at fixed R (minimum time: h unknown).
  virtual EffectTimeDerivatives timeDerivatives(const Matrix3& R, double t) const = 0;
  /// The torque when it is one constant vector in the body frame at every attitude and time (a
  /// verdict that must hold along every plan can use it); none otherwise.
  virtual std::optional<Vector3> constantBodyTorque() const { return std::nullopt; }
  /// The torque when it is one constant vector in the world frame at every attitude and time
  /// (its impulse over [0, t] is t times it, whatever the path: what the reaction wheels'
  /// total momentum needs); none otherwise.
  virtual std::optional<Vector3> constantWorldTorque() const { return std::nullopt; }
};

/// Gravity gradient of a circular orbit in the world x–y plane:
/// τ = 3 n² (b × J b), b = Rᵀ r̂(t), r̂(t) = (cos nt, sin nt, 0), n² = μ/r³.
class GravityGradient : public TorqueEffect {
 public:
  /// μ [m³/s²], r [m], J [kg m²].
  GravityGradient(double mu, double orbit_radius, const Matrix3& inertia);
  std::string name() const override { return effectKindName(EffectKind::GravityGradient); }
  Vector3 torque(const Matrix3& R, double t) const override;
  Matrix3 jacobian(const Matrix3& R, double t) const override;
  Matrix3 weightedSecondDerivative(const Matrix3& R, double t, const Vector3& w) const override;
  /// From r̂'(t) = n (−sin nt, cos nt, 0), r̂'' = −n² r̂.
  EffectTimeDerivatives timeDerivatives(const Matrix3& R, double t) const override;
  /// The orbit's mean motion n [rad/s].
  double meanMotion() const { return n_; }
  /// r̂(t), the unit vector from the Earth to the body, world frame.
  Vector3 radial(double t) const;

 private:
  double n_;   ///< mean motion √(μ/r³) [rad/s]
  Matrix3 J_;  ///< inertia [kg m²]
};

/// A known constant torque, given in the body or the world frame.
class DisturbanceTorque : public TorqueEffect {
 public:
  /// value [N m] expressed in `frame`.
  DisturbanceTorque(const Vector3& value, TorqueFrame frame);
  std::string name() const override { return effectKindName(EffectKind::DisturbanceTorque); }
  Vector3 torque(const Matrix3& R, double t) const override;
  Matrix3 jacobian(const Matrix3& R, double t) const override;
  Matrix3 weightedSecondDerivative(const Matrix3& R, double t, const Vector3& w) const override;
  /// Zero: constant in time in either frame (in the world frame it moves with R only).
  EffectTimeDerivatives timeDerivatives(const Matrix3& R, double t) const override;
  /// The value in the body frame (none in the world frame: it turns with the attitude).
  std::optional<Vector3> constantBodyTorque() const override;
  /// The value in the world frame (none in the body frame: it turns with the attitude).
  std::optional<Vector3> constantWorldTorque() const override;

 private:
  Vector3 value_;
  bool in_world_;
};

/// The plannable effects of a scene, composed once. Empty when the scene lists none.
class EffectModel {
 public:
  EffectModel() = default;
  void add(std::unique_ptr<TorqueEffect> effect) { effects_.push_back(std::move(effect)); }
  bool empty() const { return effects_.empty(); }
  std::vector<std::string> names() const;
  /// Σ τ_e(R, t) [N m].
  Vector3 torque(const Matrix3& R, double t) const;
  /// Σ of the effects' constant body torques when every effect has one (zero when empty); none
  /// otherwise.
  std::optional<Vector3> constantBodyTorque() const;
  /// Σ of the effects' constant world torques when every effect has one (zero when empty); none
  /// otherwise.
  std::optional<Vector3> constantWorldTorque() const;
  /// Σ ∂τ_e/∂δ.
  Matrix3 jacobian(const Matrix3& R, double t) const;
  /// Σ weighted second derivatives (see TorqueEffect).
  Matrix3 weightedSecondDerivative(const Matrix3& R, double t, const Vector3& w) const;
  /// Σ time derivatives (see TorqueEffect).
  EffectTimeDerivatives timeDerivatives(const Matrix3& R, double t) const;
  /// The same effects on a clock moved on by `offset` [s]: τ_e'(R, t) = τ_e(R, t + offset), names
  /// kept. The model of a plan that starts at `offset` of the original maneuver (re-planning the
  /// rest of it: the gravity gradient's orbit has moved on).
  EffectModel timeShifted(double offset) const;

 private:
  std::vector<std::shared_ptr<const TorqueEffect>> effects_;
};

/// What happens to a commanded torque on the way to the body (tracker-only effects): per-axis
/// saturation, then additive Gaussian noise. Deterministic for a given seed.
class Actuation {
 public:
  Actuation() = default;
  /// |τ_i| ≤ max_torque_i [N m].
  void setLimits(const Vector3& max_torque) {
    limits_ = max_torque;
    has_limits_ = true;
  }
  /// Per-axis standard deviation [N m] and PRNG seed.
  void setNoise(const Vector3& std_dev, std::uint64_t seed);
  bool empty() const { return !has_limits_ && !has_noise_; }
  /// The torque the body receives for commanded τ (advances the noise stream).
  Vector3 apply(const Vector3& commanded);

 private:
  bool has_limits_ = false, has_noise_ = false;
  Vector3 limits_ = Vector3::Zero(), noise_std_ = Vector3::Zero();
  std::mt19937_64 rng_;
};

}  // namespace attitude_planner
