// What a solve returns (PlanResult) and how it ended (Termination).
#pragma once

#include <string>
#include <vector>

#include "attitude_planner/planning/problem.hpp"

namespace attitude_planner {

/// How a solve ended: the one status of a result. Messages explain it, they never carry it; the
/// node maps it to PlanErrorCode in one switch (ros/planner_node.cpp, errorCodeOf).
enum class Termination {
  Converged,     ///< first-order optimal and consistent to the tolerance
  NotConverged,  ///< iteration limit, stall, or a check failed (the message says which)
  Infeasible,    ///< the constraints admit no maneuver (the message names the binding one)
  StepTooLarge,  ///< an implicit step has no solution at this h (h·|Ω| too large): increase N
  TimedOut,      ///< the time budget ran out (the plan so far is returned)
  Cancelled,     ///< the on_iteration callback asked to stop (the plan so far is returned)
  InvalidInput,  ///< the problem or options were refused (a node answers this; the core throws)
};

/// "converged", "not_converged", "infeasible", "step_too_large", "timed_out", "cancelled",
/// "invalid_input" (JSON summary, logs).
std::string terminationName(Termination termination);

/// One grid level of a continuation solve (coarsest first; the last one is the requested N).
struct LevelSummary {
  int steps = 0;       ///< N of this level
  int iterations = 0;  ///< Newton iterations on this level
  Termination termination = Termination::NotConverged;
  double relative_gradient = 0.0;  ///< max|∇C| / (|∂τ/∂R|·max|τ|) at the level's last iterate
  double newton_decrement = 0.0;  ///< relative Newton decrement of its last iteration
  std::string reason;             ///< why the level ended, one sentence
};

/// What a solve returns: the plan, how the solve ended (`termination`, explained by `message`),
/// and the figures that judge it.
struct PlanResult {
  Termination termination = Termination::NotConverged;
  bool converged() const { return termination == Termination::Converged; }
  std::string message;  ///< human-readable explanation of `termination`, one level only
  /// The grid levels solved, coarsest first (continuation); empty for solvers without levels.
  std::vector<LevelSummary> levels;
  std::string solver;  ///< "newton" or "nlopt"
  SchemeKind scheme = SchemeKind::Paper;
  /// R_k, Ω_k, τ_k, k = 0..N: the plan itself (Newton, interior point: the solver's attitudes,
  /// their velocities and torques; NLopt: its torques replayed).
  Maneuver maneuver;
  double duration = 0.0;  ///< T [s] of the returned plan (minimum_time: chosen by the planner)
  /// T* [s]: the least duration found feasible (objective minimum_time; else 0).
  double minimum_duration = 0.0;
  /// Σ_k ½ w_k |τ_k|² [N²·m²]: the scheme's own objective (w_k = 1, k = 1..N−1, for paper and
  /// variational, as in the seed; second_order: k = 0..N with w_0 = w_N = ½; fourth_order:
  /// Gregory's end-corrected weights, schemeTorqueWeight).
  double cost = 0.0;
  /// h · cost [N²·m²·s]: the scheme's quadrature of ½∫₀ᵀ|τ|²dt, comparable across schemes and
  /// with the continuous optimum.
  double effort = 0.0;
  int iterations = 0;  ///< Newton iterations, coarser continuation levels included
  /// First-order optimality residual at the end: max-norm of ∇C relative to |∂τ/∂R|·max|τ|
  /// (the interior point: of the KKT stationarity residual ∇C − Σ zᵢ∇cᵢ with its multipliers).
  double max_residual = 0.0;
  /// Newton: √(gᵀH⁻¹g)/|τ|₂ of the last iteration, ≈ the relative ℓ2 torque error before the
  /// final step (the convergence test); NLopt: 0.
  double newton_decrement = 0.0;
  double dynamics_residual = 0.0;  ///< worst implicit-step residual on replay [N·m·s]
  /// Worst residual of the discrete equations of motion and boundary data on the returned
  /// maneuver, step by step, relative to the problem's scales (measureStepResidual); part of
  /// the convergence verdict.
  double step_residual = 0.0;
  double terminal_attitude_error = 0.0;  ///< ‖log(R_N*ᵀ R_N)‖ [rad] of the replayed maneuver
  /// |Ω_N − Ω(T)| [rad/s] of the replay (Ω_N = Ω_{N−1} for paper and variational)
  double terminal_velocity_error = 0.0;
  /// max(terminal_attitude_error, T·terminal_velocity_error) [rad]: how far the planned torques,
  /// replayed open-loop from R_0, Ω_0 through the same integrator, end from the target. A
  /// sensitivity of the maneuver (round-off grows like e^{λT} on unstable motions), reported,
  /// never a reason to refuse an optimum.
  double replay_miss = 0.0;
  double solve_time_s = 0.0;           ///< wall time [s]
  std::vector<IterationInfo> history;  ///< one entry per iteration
  /// Which extremal was found, e.g. "short way: 3.14159 rad about [1, 0, 0]" (Newton), with the
  /// cost of the other way when both were solved.
  std::string extremal;
  /// The effects in the planning model (scene keys), in order; "actuator_limits" last when the
  /// control torques are bounded.
  std::vector<std::string> effects;
  /// The accuracy of the plan when PlanningProblem::accuracy was given (requested = true).
  AccuracyEstimate accuracy;
  /// The node constraints in force (scene keys, in order; "actuator_limits" first when bounded).
  std::vector<std::string> constraints;
  /// Worst violation over all nodes and constraints, each in its own unit (N m, rad/s, rad), ≥ 0,
  /// measured on the returned maneuver (checkConstraints).
  double max_constraint_violation = 0.0;
  /// The same over the continuous motion between the nodes too (R_k exp(s ω_k^), torques held):
  /// what a cone's `margin` is for (checkConstraints), ≥ max_constraint_violation.
  double max_violation_between_nodes = 0.0;
  /// Node constraints at their bound (within kActiveConstraintTolerance relative) on the result.
  int active_constraints = 0;
  /// Interior-point plans under per-axis torque bounds: the discrete PMP switching function
  /// σ_k = τ_k + (z⁺_k − z⁻_k)/(a w_k) per axis [N m], k = 0..N (z± the multipliers of the upper
  /// and lower bound, a the bound, w_k the cost weight): the minimizer of the Lagrangian in τ_k
  /// without the bound, so τ_k = sat(σ_k) at a KKT point, and a bang–bang plan switches where σ_k
  /// changes sign. Empty otherwise.
  std::vector<Vector3> switching_function;
};

}  // namespace attitude_planner
