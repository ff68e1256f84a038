// How consistent a maneuver is with its discrete problem (the step residual), independently of
// any solver: part of every plan's verdict.
#pragma once

#include "attitude_planner/dynamics/maneuver.hpp"
#include "attitude_planner/planning/problem.hpp"

namespace attitude_planner {

/// How well a maneuver satisfies the discrete problem, step by step, relative to its own scales:
/// rate W = max_k|Ω_k| + θ/T (θ the angle from R_0 to R_N*), momentum P = ‖J‖·W.
///   kinematics  |μ(R_kᵀR_{k+1}) − c_k| / P, c_k the momentum step k carries by its reported
///               velocity (paper exp(hΩ_k^)JΩ_k, variational JΩ_k, second_order JΩ_k + (h/2)a_k)
///   dynamics    |c_k − F_{k−1}ᵀc_{k−1} − h a_k| / P, a_k = τ_k + τ_e(R_k, t_k) (seed 000,
///               eq. 18), k = 1..N−1; second_order also |JΩ_N − F_{N−1}ᵀc_{N−1} − (h/2)a_N| / P
///   boundary    ∠(R_0, R_0*), ∠(R_N, R_N*) [rad], |Ω_0 − Ω_0*| / W and the end velocity
///               (row N−1, second_order row N) against Ω(T), / W
/// Invariant under T → sT and J → jJ (time by T, inertia by its scale).
struct StepResidual {
  double relative = 0.0;   ///< the worst of the figures above
  double tolerance = 0.0;  ///< what a consistent plan meets (stepResidualTolerance)
};
StepResidual measureStepResidual(const PlanningProblem& problem, const Maneuver& maneuver);

/// kStepResidualTolerance above the round-off floor of the attitudes (absolute eps per entry,
/// so a step of angle h·W carries its momentum to ~eps/(hW), and R_N is a product of N steps).
double stepResidualTolerance(int steps, double step_angle);

/// Relative step residual a converged plan must meet (above the round-off floor).
constexpr double kStepResidualTolerance = 1e-8;

}  // namespace attitude_planner
