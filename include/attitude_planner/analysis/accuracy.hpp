// What accuracy a discrete plan has, and plans to a requested accuracy (docs/results/accuracy.md).
//
// Three measures of a plan of N steps (h = T/N) against the continuous optimum
// (continuous_reference.hpp):
//   (a) cost error  |h Σ_k ½ w_k|τ_k|² − ½∫₀ᵀ|τ|²dt| (the effort's error): paper and
//       variational sum the N − 1 interior torques (w_k = 1, a Riemann sum), second_order all
//       N + 1 with the trapezoidal weights, fourth_order with Gregory's end-corrected ones;
//   (b) trajectory error max_k ‖log(R(t_k)ᵀ R_k)‖ and torque error max_k |τ_k − τ(t_k)| (the end
//       nodes too for second_order and fourth_order): all schemes apply the torque as an impulse hτ_k at the node
//       t_k (discrete_scheme.hpp: the momentum jumps by hτ_k between step k−1 and step k), so τ_k
//       samples τ(t_k);
//   (c) physical miss: the plan's torques drive the continuous rigid body (integrated to ~1e-13)
//       under the scheme's own hold; terminal ‖log(R_Tᵀ R(T))‖ and |Ω(T) − Ω_T|. paper and
//       variational: the impulse hτ_k at t_k is held over [t_k − h/2, t_k + h/2] (node-centred);
//       holding it over the step [t_k, t_{k+1}) (what a naive controller does) adds a half-step
//       delay. second_order: τ linear between the node values (first-order hold); fourth_order:
//       the cubic hold of the node torques (cubicHoldCoefficients, simulation.hpp).
#pragma once

#include "attitude_planner/analysis/continuous_reference.hpp"
#include "attitude_planner/planning/plan_at_resolution.hpp"

namespace attitude_planner {

/// Over which interval a zero-order hold applies τ_k.
enum class TorqueHold {
  NodeCentred,  ///< [t_k − h/2, t_k + h/2] ∩ [0, T]: the impulse hτ_k spread around its node
  StepStart,    ///< [t_k, t_{k+1}), k = 0..N−1: τ_k held over the step that starts at t_k
  /// τ linear between the nodes (first-order hold): the interpolant of the node torques of a
  /// scheme with end torques (second_order), which keeps its order 2.
  PiecewiseLinear,
  /// τ the local cubic interpolant of the node torques (cubicHoldCoefficients): fourth_order,
  /// order 4.
  PiecewiseCubic,
};

/// The hold that keeps a scheme's order: node-centred for paper and variational (the impulse
/// hτ_k at t_k), piecewise linear for second_order (τ_k are samples of τ(t_k), ends included),
/// piecewise cubic for fourth_order (samples accurate to O(h⁴)).
TorqueHold naturalHold(SchemeKind scheme);

/// Terminal state of the continuous body driven by a plan's torques (zero-order hold).
struct ZeroOrderHoldReplay {
  Matrix3 attitude = Matrix3::Identity();      ///< R(T)
  Vector3 angular_velocity = Vector3::Zero();  ///< Ω(T) [rad/s]
  double attitude_miss = 0.0;                  ///< ‖log(R_Tᵀ R(T))‖ [rad]
  double velocity_miss = 0.0;                  ///< |Ω(T) − Ω_T| [rad/s]
};

/// Drives the continuous rigid body of `problem` from (R_0, Ω_0) with the plan's torques τ_k,
/// k = 0..N, as a zero-order hold (GBS order 16, every hold interval split into steps of at most
/// T/64 and 0.25 rad of rotation at the plan's fastest Ω_k: accurate to ~1e-13 on the seed's
/// examples, test_accuracy.cpp).
ZeroOrderHoldReplay replayZeroOrderHold(const PlanningProblem& problem, const Maneuver& plan,
                                        TorqueHold hold);
/// The same with the hold that keeps the order of problem.scheme (naturalHold).
inline ZeroOrderHoldReplay replayZeroOrderHold(const PlanningProblem& problem,
                                               const Maneuver& plan) {
  return replayZeroOrderHold(problem, plan, naturalHold(problem.scheme));
}

/// The three measures of a plan.
struct AccuracyMeasures {
  int steps = 0;                  ///< N
  double cost_integral = 0.0;     ///< effort h Σ ½ w_k |τ_k|² [N²·m²·s]
  double cost_error = 0.0;        ///< |h Σ ½ w_k |τ_k|² − ½∫|τ|²dt| [N²·m²·s]
  double trajectory_error = 0.0;  ///< max_k ‖log(R(t_k)ᵀ R_k)‖ [rad], k = 0..N
  double torque_error = 0.0;  ///< max_k |τ_k − τ(t_k)| [N·m], k = 1..N−1 (0..N with end torques)
  ZeroOrderHoldReplay miss;             ///< (c) with the scheme's own hold (naturalHold)
  ZeroOrderHoldReplay miss_step_start;  ///< (c) with the step-start hold (comparison)
};

/// Measures a plan of `problem` against its continuous reference.
AccuracyMeasures measureAccuracy(const PlanningProblem& problem, const Maneuver& plan,
                                 const ContinuousReference& reference);

/// The convergence order p of a measure (error ≈ C N^−p) as measured by scripts/accuracy on the
/// seed's examples (docs/results/accuracy.md): cost error 1 (paper, variational), terminal attitude miss
/// 1 (paper) and 2 (variational); second_order 2 and fourth_order 4 in both. The planner predicts
/// N from it.
double measuredOrder(SchemeKind scheme, AccuracyMeasure measure);

/// Plans to problem.accuracy: solves N = 64 of each candidate scheme (and N = 32 for the cost's
/// Richardson estimate), predicts N from the error there and the order, solves at N and checks
/// the estimate (repeating with a larger N if it misses, at most 4 times). The result is the plan
/// at the final N with PlanResult::accuracy filled; converged = false if the target was not
/// reached.
PlanResult planToAccuracy(const PlanningProblem& problem, const SolverOptions& options);

}  // namespace attitude_planner
