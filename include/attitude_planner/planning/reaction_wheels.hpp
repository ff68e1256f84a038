// Reaction wheels (scene `actuators: {reaction_wheels: …}`): the array's data, its validation and
// the wheel states a plan implies.
//
// Physics (no external torques): the total angular momentum in the world,
//     π₀ = R (J Ω + A h_w),      A = [a_1 … a_n] the unit spin axes (body), h_w the wheel momenta,
// is conserved, so the array's momentum in the body frame is a function of the body's state,
//     q = A h_w = Rᵀπ₀ − J Ω,
// and the wheels' torques u = ḣ_w follow from the body's motion: J Ω̇ + Ω × J Ω = τ with
// τ = −A u − Ω × A h_w (the body torque the array exerts), so A u = −(τ + Ω × q).
// Redundant arrays (n > 3) distribute by the minimum-norm law: h_w = A⁺q + (I − A⁺A) h_w(0), the
// null-space part constant (so u = A⁺ A u carries none), A⁺ = Aᵀ(AAᵀ)⁻¹.
//
// On a plan (discrete): q_k = R_kᵀπ₀ − Π_k with Π_k the body's node momentum (the mean of the
// two steps' momenta seen from node k, ReducedProblem::NodeMomentum; J Ω(0), J Ω(T) at the end
// nodes), π₀ = R_0 (J Ω(0) + A h_w(0)); and A u_k = −(τ_k + J⁻¹Π_k × q_k). Exactly: the spatial
// wheel momenta R_k q_k change by minus the body's trapezoidal impulse h (R_kτ_k +
// R_{k+1}τ_{k+1})/2 between nodes (the body and the array together conserve π₀ exactly); to O(h²):
// u_k against the central difference of the wheel momenta (docs/reaction_wheels.md).
#pragma once

#include <limits>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "attitude_planner/dynamics/discrete_scheme.hpp"
#include "attitude_planner/dynamics/maneuver.hpp"
#include "attitude_planner/lie/so3.hpp"

namespace attitude_planner {

/// A reaction-wheel array (empty spin_axes: none).
struct ReactionWheels {
  std::vector<Vector3> spin_axes;  ///< a_i, body frame, nonzero (normalized by wheelArray)
  /// U_i [N m]: |u_i| ≤ U_i; one entry (every wheel) or one per wheel.
  std::vector<double> max_torque;
  /// H_i [N m s]: |h_w,i| ≤ H_i; one entry (every wheel) or one per wheel.
  std::vector<double> max_momentum;
  /// h_w,i(0) [N m s], one per wheel (empty: all zero).
  std::vector<double> initial_momentum;
  /// The array's envelope as a sphere [N m s]: |A h_w| ≤ this (the norm of the array's momentum
  /// vector in the body frame; for orthonormal axes the same as |h_w|); +∞: none.
  double max_momentum_norm = std::numeric_limits<double>::infinity();
  /// J_s,i [kg m^2]: each wheel's moment of inertia about its spin axis; one entry (every wheel)
  /// or one per wheel; empty: not given (the wheel momenta are planned without it; only a
  /// wheel's spin rate needs it, wheelSpinRates).
  std::vector<double> spin_inertia;

  bool present() const { return !spin_axes.empty(); }
  int count() const { return static_cast<int>(spin_axes.size()); }
  double torqueLimit(int i) const { return max_torque.size() == 1 ? max_torque[0] : max_torque[i]; }
  double momentumLimit(int i) const {
    return max_momentum.size() == 1 ? max_momentum[0] : max_momentum[i];
  }
  bool hasSpinInertia() const { return !spin_inertia.empty(); }
  double spinInertia(int i) const {
    return spin_inertia.size() == 1 ? spin_inertia[0] : spin_inertia[i];
  }
  double initialMomentum(int i) const {
    return initial_momentum.empty() ? 0.0 : initial_momentum[i];
  }
};

/// The array's matrices: A (unit axes as columns), A⁺ and the constant null-space momentum.
struct WheelArray {
  Eigen::Matrix<double, 3, Eigen::Dynamic> axes;            ///< A
  Eigen::Matrix<double, Eigen::Dynamic, 3> pseudo_inverse;  ///< A⁺ = Aᵀ(AAᵀ)⁻¹
  Eigen::VectorXd null_momentum;  ///< (I − A⁺A) h_w(0): the part no body motion changes
  Vector3 initial_array_momentum = Vector3::Zero();  ///< A h_w(0), body frame
  /// h_w = A⁺q + null_momentum (the minimum-norm distribution).
  Eigen::VectorXd wheelMomenta(const Vector3& array_momentum) const {
    return pseudo_inverse * array_momentum + null_momentum;
  }
};
WheelArray wheelArray(const ReactionWheels& wheels);

/// Checks the array: ≥ 3 finite nonzero axes spanning R³ (the smallest singular value of the
/// normalized A above 1e-6), limits finite and > 0 with 1 or n entries, n initial momenta within
/// their limits and the norm envelope, spin inertias (when given) finite and > 0 with 1 or n
/// entries. Throws InvalidInput naming `field`.<key> and the value.
void validateReactionWheels(const ReactionWheels& wheels, const std::string& field);

/// Each wheel's spin rate relative to the body [rad/s] from its momentum h_w,i [N m s] and the
/// body rate Ω [rad/s]: a wheel spinning at w_i relative to the body turns at a_i·Ω + w_i about
/// its axis, so h_w,i = J_s,i (a_i·Ω + w_i) and w_i = h_w,i / J_s,i − a_i·Ω (a_i the unit axis).
/// (With that h_w the total momentum is R (J Ω + A h_w) when J excludes the wheels' axial
/// inertia Σ J_s,i a_i a_iᵀ, docs/reaction_wheels.md.) Needs ReactionWheels::spin_inertia.
Eigen::VectorXd wheelSpinRates(const ReactionWheels& wheels, const Eigen::VectorXd& momenta,
                               const Vector3& body_rate);
/// The inverse of wheelSpinRates: h_w,i = J_s,i (a_i·Ω + w_i) [N m s] from the spin rates w_i
/// relative to the body [rad/s] (what a wheel's tachometer reads) and the body rate Ω. Needs
/// ReactionWheels::spin_inertia.
Eigen::VectorXd wheelMomentaFromSpinRates(const ReactionWheels& wheels,
                                          const Eigen::VectorXd& rates, const Vector3& body_rate);

/// The wheel states of a plan: per node k = 0..N the wheel momenta h_w,k and torques u_k (the
/// definitions above; u at k = 0 and N of schemes without end torques is formed with τ = 0, what
/// their plans carry there).
struct WheelStates {
  std::vector<Eigen::VectorXd> momentum;  ///< h_w,k [N m s]
  std::vector<Eigen::VectorXd> torque;    ///< u_k [N m]
};

/// The body's node momentum Π_k of a plan of `scheme` (J Ω(0), J Ω(T) at k = 0, N; the node
/// velocity's J Ω_k for schemes with end torques; else the mean of the steps' momenta μ(F) of
/// the plan's attitudes seen from node k).
Vector3 planNodeMomentum(SchemeKind scheme, const Matrix3& inertia, const Maneuver& plan, int k);
/// π₀ = R_0 (J Ω(0) + A h_w(0)) of a plan.
Vector3 totalMomentum(const Matrix3& inertia, const WheelArray& array, const Maneuver& plan);
/// The array momentum q_k = R_kᵀπ_k − Π_k and torque A u_k = −(τ_k + J⁻¹Π_k × q_k) of node k,
/// π_k = π₀ + t_k τ_d with a constant world-frame disturbance τ_d (PlanningProblem::
/// worldDisturbance; t_k = k h): its impulse is t_k τ_d whatever the path.
Vector3 planArrayMomentum(SchemeKind scheme, const Matrix3& inertia, const WheelArray& array,
                          const Maneuver& plan, int k,
                          const Vector3& world_disturbance = Vector3::Zero());
Vector3 planArrayTorque(SchemeKind scheme, const Matrix3& inertia, const WheelArray& array,
                        const Maneuver& plan, int k,
                        const Vector3& world_disturbance = Vector3::Zero());
WheelStates wheelStates(SchemeKind scheme, const Matrix3& inertia, const ReactionWheels& wheels,
                        const Maneuver& plan, const Vector3& world_disturbance = Vector3::Zero());

}  // namespace attitude_planner
