// Simulation entry point: integrate the discrete rigid body under a given torque sequence.
// The tracker node, the CLI `simulate` tool and the benchmarks all call this.
#pragma once

#include <array>
#include <vector>

#include "attitude_planner/dynamics/discrete_scheme.hpp"
#include "attitude_planner/dynamics/effects.hpp"
#include "attitude_planner/dynamics/maneuver.hpp"

namespace attitude_planner {

/// Initial data and torques of a simulation.
struct SimulationInput {
  Matrix3 initial_attitude = Matrix3::Identity();  ///< R_0
  Vector3 initial_velocity = Vector3::Zero();      ///< Ω_0 [rad/s]
  /// τ_k [N·m], k = 0..N; τ_0 and τ_N must be zero (seed eq. 18) unless the scheme has end
  /// torques (second_order).
  std::vector<Vector3> torque;
  /// Known external torques τ_e(R_k, t_k) added at each node (nullptr or empty: none).
  const EffectModel* effects = nullptr;
  /// Saturation/noise applied to each commanded τ_k (nullptr or empty: none); advanced in place.
  Actuation* actuation = nullptr;
};

/// Figures of merit of a simulation.
struct SimulationReport {
  int max_step_iterations = 0;     ///< worst Newton count of the implicit step
  double max_step_residual = 0.0;  ///< worst |μ(F_k) − p_k| [N·m·s]
};

/// Integrates R_{k+1} = R_k F_k, μ(F_k) = F_{k−1}ᵀ μ(F_{k−1}) + h (τ_k + τ_e(R_k, t_k)),
/// k = 1..N−1; with end torques (second_order) also μ(F_0) = J Ω_0 + (h/2) τ_0, and the node
/// velocities are J⁻¹ Π_k (Π_N = F_{N−1}ᵀ μ(F_{N−1}) + (h/2) τ_N). The returned maneuver's torque
/// column holds the torques the body received (after actuation), not the effects. Without effects
/// and actuation the inner loop is the bare integrator (chosen once, at compile time):
/// bit-identical to a scene with `effects: []`. N = torque.size() − 1 ≥ 1. Attitudes are
/// re-orthonormalized each step (one Newton–Schulz iteration) so they stay on SO(3) to round-off
/// over millions of steps. Throws StepTooLarge (naming the step) if an implicit step fails,
/// InvalidInput on bad input.
Maneuver simulate(const DiscreteScheme& scheme, const SimulationInput& input,
                  SimulationReport* report = nullptr);

/// The cubic hold of fourth_order on step k, [t_k, t_{k+1}] (h = t_{k+1} − t_k): the Lagrange
/// cubic through the four node torques nearest to the step (nodes k−1..k+2; 0..3 on the first
/// step, N−3..N on the last), as coefficients c_0..c_3 of τ(t_k + s) = Σ_i c_i s^i. It
/// interpolates the node torques and is O(h⁴) from a smooth τ(t) sampled at the nodes. N ≥ 3.
std::array<Vector3, 4> cubicHoldCoefficients(const std::vector<Vector3>& torque, int k, double h);

/// Replays the node torques of a plan of scheme `kind` (time step h) with the hold and integrator
/// that keep the scheme's order — the one replay the tracker, simulate_torques and the planner's
/// own replay_miss use:
///   paper, variational, second_order  simulate(DiscreteScheme(kind, J, h), …): the scheme's own
///                                     discrete integrator, i.e. exactly the motion it plans;
///   fourth_order                      the continuous rigid body Ṙ = RΩ^, JΩ̇ = JΩ×Ω + τ(t) + τ_e,
///                                     τ(t) the cubic hold of the node torques
///                                     (cubicHoldCoefficients), integrated by RKMK4 (classical
///                                     Runge–Kutta on R = R_k exp(u^), u̇ = J_r(u)⁻¹Ω with the exact
///                                     inverse right Jacobian; one step per plan step): order 4 in
///                                     h, N ≥ 3. Actuation is applied to the node torques (in k
///                                     order) before they are interpolated; effects are evaluated
///                                     at every stage. The report's step figures stay 0 (explicit).
/// Rows k = 0..N are node values (t_k, R_k, Ω(t_k), received τ_k).
Maneuver replayPlan(SchemeKind kind, const Matrix3& inertia, double time_step,
                    const SimulationInput& input, SimulationReport* report = nullptr);

/// One Newton–Schulz step towards the nearest rotation: R (3I − RᵀR)/2.
Matrix3 reorthonormalize(const Matrix3& R);

}  // namespace attitude_planner
