// Body + reaction wheels replayed from the wheel torques alone: the continuous equations of the
// coupled system, integrated by classical RK4, independent of the planner's discrete algebra
// (node momenta, π₀, A⁺): the check that a plan's wheel torques fly the plan within the limits.
//
//     Ṙ = R Ω^,     J Ω̇ = −Ω × (J Ω + A h_w) − A u + τ_e(R, t),     ḣ_w = u
//
// (τ_e the external torque in the body frame: Rᵀτ_d for a constant world-frame disturbance τ_d,
// zero without, or any field of the attitude and time; A the unit spin axes as columns). u(t)
// is the node values held linearly between the nodes (a box limit met at the nodes holds
// between them).
#pragma once

#include <functional>
#include <vector>

#include <Eigen/Core>

#include "attitude_planner/lie/so3.hpp"

namespace attitude_planner {

/// The replay at the nodes t_k = k h, k = 0..N.
struct WheelReplay {
  std::vector<Matrix3> attitude;          ///< R(t_k)
  std::vector<Vector3> angular_velocity;  ///< Ω(t_k) [rad/s], body
  std::vector<Eigen::VectorXd> momentum;  ///< h_w(t_k) [N m s]
  /// max over the substeps of |h_w,i(t)| per wheel (the momentum between nodes too).
  Eigen::VectorXd peak_momentum;
};

/// An external torque on the body [N m, body frame] at attitude R (body → world) and time t [s]
/// from the replay's start (gravity gradient, disturbances: EffectModel::torque).
using ExternalTorque = std::function<Vector3(const Matrix3& R, double t)>;

/// Replays N = torque.size() − 1 steps of `time_step` from R_0, Ω_0 and h_w(0) with wheel torques
/// u_k (one vector of n per node) and the world-frame disturbance τ_d [N m], `substeps` RK4
/// steps per step.
WheelReplay replayWithWheels(const Matrix3& inertia,
                             const Eigen::Matrix<double, 3, Eigen::Dynamic>& axes,
                             const Matrix3& initial_attitude, const Vector3& initial_velocity,
                             const Eigen::VectorXd& initial_momentum, double time_step,
                             const std::vector<Eigen::VectorXd>& torque,
                             const Vector3& world_disturbance = Vector3::Zero(), int substeps = 16);

/// The same under the external torque τ_e(R, t), evaluated at every RK4 stage (null: none).
WheelReplay replayWithWheelsUnder(const Matrix3& inertia,
                                  const Eigen::Matrix<double, 3, Eigen::Dynamic>& axes,
                                  const Matrix3& initial_attitude, const Vector3& initial_velocity,
                                  const Eigen::VectorXd& initial_momentum, double time_step,
                                  const std::vector<Eigen::VectorXd>& torque,
                                  const ExternalTorque& external, int substeps);

}  // namespace attitude_planner
