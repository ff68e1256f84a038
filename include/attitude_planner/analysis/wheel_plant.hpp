// Body + reaction wheels as a plant driven by wheel-torque commands: what attitude_plant_node
// integrates for a scene with wheels, and what the tracker's external plant mode commands and
// predicts with (docs/ros_tracker.md, "External plant with wheels"). The equations are
// replayWithWheels' (dynamics/wheel_replay.hpp):
//
//     Ṙ = R Ω^,     J Ω̇ = −Ω × (J Ω + A h_w) − A u + τ_e(R, t),     ḣ_w = u,
//
// u held between commands (zero-order hold), RK4 in steps of at most max_step. τ_e is the sum
// of the known effects (gravity gradient, disturbance torques: EffectModel, body frame) acting on
// the body: they change the total angular momentum R (J Ω + A h_w) by their impulse, the wheels
// only move it between body and wheels. A wheel stops at
// its momentum limit: once |h_w,i| reaches H_i, a torque that would drive it further is not
// delivered (ḣ_w,i = 0: the wheel cannot absorb it, so its reaction on the body is missing,
// which is the commanded torque acting back on the body); one that brings it back is.
#pragma once

#include <Eigen/Core>
#include <memory>
#include <vector>

#include "attitude_planner/analysis/tracking.hpp"
#include "attitude_planner/planning/reaction_wheels.hpp"

namespace attitude_planner {

/// The wheel torques that make the body torque `body_torque` [N m] at body rate Ω and wheel
/// momenta h_w by the array's minimum-norm law (A u = −(τ + Ω × A h_w), u = A⁺(A u)), each then
/// cut to ±U_i, and to 0 in the direction that would drive a wheel already at ±H_i further;
/// `cut` (if not null) is set when a wheel's torque was changed.
Eigen::VectorXd wheelTorquesFor(const ReactionWheels& wheels, const WheelArray& array,
                                const Vector3& body_torque, const Vector3& rate,
                                const Eigen::VectorXd& momentum, bool* cut = nullptr);

/// The torque the array exerts on the body, τ = −A u − Ω × A h_w [N m].
Vector3 arrayReaction(const WheelArray& array, const Eigen::VectorXd& torque, const Vector3& rate,
                      const Eigen::VectorXd& momentum);

/// Body and wheels at one instant.
struct WheelBodyState {
  RigidBodyState body;
  Eigen::VectorXd momentum;  ///< h_w [N m s]
};

/// `state` at maneuver time t moved on by dt [s] (≥ 0) under the wheel torques u held and the
/// known effects (null: none; kWheelFlightSubsteps RK4 steps): the tracker moves a measurement
/// to its sample's time with it.
WheelBodyState predictWheelState(const Matrix3& inertia, const WheelArray& array,
                                 const WheelBodyState& state, const Eigen::VectorXd& torque,
                                 double dt, const EffectModel* effects = nullptr, double t = 0.0);

/// Body + wheels integrated from wheel-torque commands (zero-order hold).
class WheelPlant {
 public:
  /// At t = 0 in `start` (the wheels at their initial_momentum), under `effects` (null or empty:
  /// none; their clock is the plant's t). The array must be valid (validateReactionWheels);
  /// `max_step` > 0 [s] (throws InvalidInput naming it otherwise).
  WheelPlant(const Matrix3& inertia, const ReactionWheels& wheels, const RigidBodyState& start,
             double max_step, std::shared_ptr<const EffectModel> effects = nullptr);
  /// Holds the wheel torques u [N m] from now on, each cut to its torque limit ±U_i (the
  /// motor's); returns the torques delivered now (0 for a wheel at its momentum limit that u
  /// would drive further). Throws InvalidInput for a wrong count.
  const Eigen::VectorXd& command(const Eigen::VectorXd& torque);
  /// Integrates to maneuver time t; a t at or before time() changes nothing. A wheel that
  /// reaches its momentum limit on the way stops there at that instant (ḣ_w = u is linear in
  /// time under the hold, so the instant is exact) and the rest is integrated without its torque.
  void advanceTo(double t);
  double time() const { return time_; }                             ///< t [s]
  const Matrix3& attitude() const { return state_.body.attitude; }  ///< R(t), body → world
  const Vector3& angularVelocity() const { return state_.body.angular_velocity; }  ///< Ω [rad/s]
  const Eigen::VectorXd& momentum() const { return state_.momentum; }    ///< h_w(t) [N m s]
  const Eigen::VectorXd& deliveredTorque() const { return delivered_; }  ///< u [N m]
  const ReactionWheels& wheels() const { return wheels_; }
  /// Per wheel: the time [s] it first stopped at its momentum limit (NaN: never).
  const std::vector<double>& saturatedAt() const { return saturated_at_; }

 private:
  Matrix3 inertia_;
  ReactionWheels wheels_;
  std::shared_ptr<const EffectModel> effects_;  ///< null: none
  WheelArray array_;
  double max_step_;
  double time_ = 0.0;
  WheelBodyState state_;
  Eigen::VectorXd commanded_;  ///< u held, cut to ±U_i [N m]
  Eigen::VectorXd delivered_;  ///< u held, less the wheels stopped at their momentum limit
  std::vector<double> saturated_at_;

  /// delivered_ from commanded_ and the momenta now.
  void updateDelivered();
  /// Integrates dt [s] under delivered_.
  void integrate(double dt);
};

}  // namespace attitude_planner
