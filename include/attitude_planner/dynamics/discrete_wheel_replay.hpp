// Body + reaction wheels replayed from the wheel torques alone on the discrete scheme of the plan
// (paper, variational, second_order): the discrete mechanics of the closed system, derived here
// from the scheme's forced discrete Legendre transforms and independent of the planner's wheel
// quantities. Replaying a plan's own wheel torques reproduces its nodes to round-off, so every
// wheel limit the plan meets at its nodes is met by the replay to round-off; a wrong torque
// departs. (The continuous check, RK4 between the nodes, is wheel_replay.hpp: O(h²).)
//
// The step k → k+1, with ω = J⁻¹Π, q = A h_w (A the unit spin axes as columns), τ_d a constant
// world-frame disturbance and π_k = π₀ + t_k τ_d the total angular momentum R(Π + q):
//
//   τ_k     = −A u_k − ω_k × q_k                 the torque the array exerts on the body at node k
//   μ(F_k)  = Π_k + (h/2)(τ_k + R_kᵀτ_d)         the body's half impulse; F_k solves it (scheme's
//   μ) R_{k+1} = R_k F_k Π_{k+1} = F_kᵀμ(F_k) + (h/2)(τ_{k+1} + R_{k+1}ᵀτ_d),   q_{k+1} =
//   R_{k+1}ᵀπ_{k+1} − Π_{k+1} τ_{k+1} = −A u_{k+1} − ω_{k+1} × q_{k+1}     (implicit in τ_{k+1}: a
//   3 × 3 Newton solve)
//
// The wheels' side is the trapezoidal rule of d(R q)/dt = R (A u + Ω × q) (the array's spatial
// momentum advanced by the wheel torques and the gyroscopic term in the scheme's quadrature):
// R_{k+1}q_{k+1} − R_k q_k = (h/2)[R_k(A u_k + ω_k × q_k) + R_{k+1}(A u_{k+1} + ω_{k+1} ×
// q_{k+1})], which with the body's two half impulses is the conservation written above. The wheel
// momenta are h_w,k+1 = A⁺q_{k+1} + P_N (h_w,k + (h/2)(u_k + u_{k+1})), P_N = I − A⁺A the null
// space (no body motion reaches it; a torque with a null-space part moves it).
//
// paper and variational fix their first and last steps by the boundary velocities (τ_0 = τ_N = 0
// in the body's equations): F_0 = the step of Ω(0), and Π_N = J × the velocity the scheme reports
// for the last step; u_0, u_N then reach the wheels only through their null-space part.
// fourth_order (a Richardson extrapolation, not a discretization) is refused by name.
#pragma once

#include <vector>

#include <Eigen/Core>

#include "attitude_planner/dynamics/discrete_scheme.hpp"
#include "attitude_planner/lie/so3.hpp"

namespace attitude_planner {

/// The discrete replay at the nodes k = 0..N.
struct DiscreteWheelReplay {
  std::vector<Matrix3> attitude;          ///< R_k
  std::vector<Vector3> node_velocity;     ///< J⁻¹Π_k [rad/s] (the node momentum's velocity)
  std::vector<Vector3> body_torque;       ///< τ_k [N m], the torque the array exerts on the body
  std::vector<Eigen::VectorXd> momentum;  ///< h_w,k [N m s]
  double max_step_residual = 0.0;         ///< max |μ(F_k) − target| of the step solves [N m s]
};

/// Replays N = torque.size() − 1 steps of `time_step` of `scheme` from R_0, Ω(0), h_w(0) with the
/// wheel torques u_k (n per node) and the world-frame disturbance τ_d [N m]. Throws InvalidInput
/// (fourth_order, fewer than 2 nodes, a torque row of the wrong size) or StepTooLarge (a step
/// solve or a node solve that does not converge).
DiscreteWheelReplay replayWithWheelsOnTheScheme(
    SchemeKind scheme, const Matrix3& inertia, const Eigen::Matrix<double, 3, Eigen::Dynamic>& axes,
    const Matrix3& initial_attitude, const Vector3& initial_velocity,
    const Eigen::VectorXd& initial_momentum, double time_step,
    const std::vector<Eigen::VectorXd>& torque, const Vector3& world_disturbance = Vector3::Zero());

}  // namespace attitude_planner
