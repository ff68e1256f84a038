// The continuous-time optimum of the fully actuated problem (seed 000, Problem 2.2), the reference
// every discrete plan is measured against (accuracy.hpp).
//
//   minimize ½∫₀ᵀ |τ|² dt   s.t.   Ṙ = R Ω^,   J Ω̇ = (JΩ) × Ω + τ,   R(0), Ω(0), R(T), Ω(T) given.
//
// Pontryagin form (derived in docs/results/accuracy.md, "The continuous reference"), with the costate of
// R left-trivialized (π ∈ R³, body frame) and the costate of Ω written λ = J ν:
//
//   H = ½|τ|² + π·Ω + ν·((JΩ) × Ω + τ)     ⇒  τ = −ν   (∂H/∂τ = 0)
//   π̇ = π × Ω                               (R π is constant: H does not depend on R)
//   J ν̇ = −π − J(Ω × ν) + (JΩ) × ν          (λ̇ = −∂H/∂Ω)
//
// The extremal flow (R, Ω, π, ν) is integrated by GBS extrapolation of order 16 on the unit
// quaternion of R (extrapolation_integrator.hpp); the unknown π(0), ν(0) are found by multiple
// shooting: Newton on the node defects with exact sensitivities (dual numbers through the same
// integrator). The Hamiltonian −½|ν|² + π·Ω + ν·((JΩ)×Ω) is conserved along the flow (a check).
#pragma once

#include <array>

#include <vector>

#include "attitude_planner/planning/plan_at_resolution.hpp"

namespace attitude_planner {

/// One point of the continuous optimum.
struct ContinuousState {
  double t = 0.0;                              ///< time [s]
  Matrix3 attitude = Matrix3::Identity();      ///< R(t)
  Vector3 angular_velocity = Vector3::Zero();  ///< Ω(t) [rad/s], body
  Vector3 costate_attitude = Vector3::Zero();  ///< π(t), left-trivialized costate of R [N·m]
  Vector3 costate_velocity = Vector3::Zero();  ///< ν(t) = J⁻¹λ [N·m]; the torque is τ = −ν
  double cost = 0.0;                           ///< ½∫₀ᵗ |τ|² ds [N²·m²·s]

  Vector3 torque() const { return -costate_velocity; }
};

/// Settings of the reference solve.
struct ReferenceOptions {
  int segments = 8;                 ///< multiple-shooting intervals M
  int macro_steps_per_segment = 8;  ///< GBS steps per interval (order 16 each)
  double tolerance =
      2e-13;  ///< max-norm of the shooting defects to stop at (round-off floor ~1e-13)
  int max_iterations = 30;  ///< Newton iterations
  /// Initial guess: a discrete plan of the same problem (null: planManeuver at N = 256, paper).
  const Maneuver* guess = nullptr;
};

/// The continuous optimum: node states of the shooting grid and a sampler.
class ContinuousReference {
 public:
  bool converged = false;
  std::string message;
  int iterations = 0;
  double max_defect = 0.0;  ///< max-norm of the shooting defects at the end
  /// max |difference| of the terminal state and cost between the solve's macro step and half of
  /// it (the integration error of the flow, an upper estimate)
  double integration_error = 0.0;
  double cost = 0.0;               ///< ½∫₀ᵀ |τ|² dt [N²·m²·s]
  double hamiltonian_drift = 0.0;  ///< max |H(t_m) − H(0)| over the nodes (conserved: a check)

  /// State at time t ∈ [0, T] (integrated from the node before t).
  ContinuousState stateAt(double t) const;
  /// States at sorted times in [0, T] (one sweep: each integrated from the previous one).
  std::vector<ContinuousState> sample(const std::vector<double>& times) const;
  /// Node states at t_m = m T/M, m = 0..M (the last is the end of the final interval).
  const std::vector<ContinuousState>& nodes() const { return nodes_; }
  const Matrix3& inertia() const { return J_; }
  double duration() const { return T_; }

 private:
  friend ContinuousReference solveContinuousReference(const PlanningProblem&,
                                                      const ReferenceOptions&);
  Matrix3 J_ = Matrix3::Identity();
  double T_ = 0.0;
  double max_macro_step_ = 0.0;
  std::vector<ContinuousState> nodes_;
};

/// Solves the continuous problem of `problem` (inertia, duration, boundary data; steps and scheme
/// only choose the default guess). Throws InvalidInput for a bad problem or one with effects or
/// torque bounds (the reference is the bare rigid body). Never throws for non-convergence.
ContinuousReference solveContinuousReference(const PlanningProblem& problem,
                                             const ReferenceOptions& options = {});

/// Integrates the extremal flow from `start` over `duration` [s] in `macro_steps` GBS steps.
ContinuousState propagateExtremal(const Matrix3& inertia, const ContinuousState& start,
                                  double duration, int macro_steps);

/// Integrates the forced rigid body Ṙ = RΩ^, JΩ̇ = (JΩ)×Ω + τ with τ constant over `duration`
/// [s], in `macro_steps` GBS steps (order 16). For zero-order-hold replays.
void propagateRigidBody(const Matrix3& inertia, const Vector3& torque, double duration,
                        int macro_steps, Matrix3* attitude, Vector3* angular_velocity);

/// The same with τ linear in time from `torque_start` to `torque_end` (first-order hold).
void propagateRigidBody(const Matrix3& inertia, const Vector3& torque_start,
                        const Vector3& torque_end, double duration, int macro_steps,
                        Matrix3* attitude, Vector3* angular_velocity);

/// The same with τ(s) = Σ_i c_i s^i a cubic in the time s since the start (fourth_order's cubic
/// hold, cubicHoldCoefficients in simulation.hpp).
void propagateRigidBody(const Matrix3& inertia, const std::array<Vector3, 4>& torque_polynomial,
                        double duration, int macro_steps, Matrix3* attitude,
                        Vector3* angular_velocity);

}  // namespace attitude_planner
