// Geometric attitude tracking on SO(3) (Lee, Leok, McClamroch, "Geometric tracking control of a
// quadrotor UAV on SE(3)", CDC 2010, the attitude part; and "Control of complex maneuvers for a
// quadrotor UAV using geometric methods on SE(3)", 2010, eqs. (10)–(12)):
//
//     e_R = ½ (R_dᵀ R − Rᵀ R_d)^∨,        e_Ω = Ω − Rᵀ R_d Ω_d,
//     τ   = −K_R e_R − K_Ω e_Ω + Ω × JΩ − J (Ω^ Rᵀ R_d Ω_d − Rᵀ R_d Ω̇_d).
//
// The last two terms are the feed-forward with its gyroscopic part: at zero error (R = R_d,
// Ω = Ω_d) τ = J Ω̇_d + Ω_d × J Ω_d, exactly the torque that makes the body follow the reference
// (Euler: J Ω̇ = JΩ × Ω + τ). The error dynamics are exponentially stable for attitude errors
// below 90° (Ψ = ½ tr(I − R_dᵀR) < 1) with positive definite gains. Gains here are J-scaled,
// K_R = ω_n² J, K_Ω = 2 ζ ω_n J, so that the linearized error J ë + K_Ω ė + K_R e = 0 is a
// second-order system of natural frequency ω_n and damping ζ about every axis.
//
// Pure mathematics, no state: the closed loop around a plan (reference interpolation, sampling,
// effects, actuation) is analysis/tracking.hpp.
#pragma once

#include "attitude_planner/lie/so3.hpp"

namespace attitude_planner {

/// The reference at one instant.
struct AttitudeReference {
  Matrix3 attitude = Matrix3::Identity();          ///< R_d, body → world
  Vector3 angular_velocity = Vector3::Zero();      ///< Ω_d [rad/s], reference body frame
  Vector3 angular_acceleration = Vector3::Zero();  ///< Ω̇_d [rad/s²], reference body frame
};

/// The tracking errors of a state against a reference.
struct TrackingErrors {
  Vector3 attitude = Vector3::Zero();  ///< e_R = ½ (R_dᵀR − RᵀR_d)^∨ (= sin θ · axis) [-]
  Vector3 rate = Vector3::Zero();      ///< e_Ω = Ω − RᵀR_d Ω_d [rad/s], body frame
  double angle = 0.0;                  ///< θ = ‖log(R_dᵀ R)‖ [rad], the attitude error angle
};

/// Gain matrices of the tracking law (symmetric positive definite).
struct TrackingGains {
  Matrix3 attitude = Matrix3::Identity();  ///< K_R [N·m]
  Matrix3 rate = Matrix3::Identity();      ///< K_Ω [N·m·s]
};

/// J-scaled gains K_R = ω_n² J, K_Ω = 2 ζ ω_n J: natural frequency `natural_frequency` ω_n
/// [rad/s] > 0 and damping ratio `damping` ζ > 0 about every axis of the linearized error. Throws
/// InvalidInput naming the argument and the value otherwise.
TrackingGains trackingGains(const Matrix3& inertia, double natural_frequency, double damping);

/// e_R, e_Ω and θ of the state (R, Ω) against `reference`.
TrackingErrors trackingErrors(const Matrix3& attitude, const Vector3& angular_velocity,
                              const AttitudeReference& reference);

/// The feed-forward torque J Ω̇_d + Ω_d × J Ω_d [N·m]: what the body needs to follow the
/// reference exactly (the law's output at zero error).
Vector3 feedForwardTorque(const Matrix3& inertia, const AttitudeReference& reference);

/// The tracking law τ(R, Ω; R_d, Ω_d, Ω̇_d) [N·m], body frame (see the file comment). This is the
/// total torque the body should receive; a caller that knows external torques τ_e subtracts them
/// from it to get the actuator command.
Vector3 trackingTorque(const Matrix3& inertia, const TrackingGains& gains, const Matrix3& attitude,
                       const Vector3& angular_velocity, const AttitudeReference& reference);

}  // namespace attitude_planner
