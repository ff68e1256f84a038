// The solvers behind planManeuver(). Call planManeuver() rather than these directly: it
// validates the problem, times the solve and fills the common figures.
#pragma once

#include "attitude_planner/planning/problem.hpp"
#include "attitude_planner/planning/result.hpp"

namespace attitude_planner {

/// Newton's method on the first-order optimality conditions, O(N) per iteration
/// (newton_solver.cpp). Fills everything but solve_time_s.
PlanResult solveWithNewton(const PlanningProblem& problem, const SolverOptions& options);

/// Independent cross-check: NLopt on the direct method (τ_1..τ_{N−1} as variables, equality
/// constraints on the terminal state, exact gradients) (nlopt_solver.cpp).
PlanResult solveWithNlopt(const PlanningProblem& problem, const SolverOptions& options);

/// Replays τ_1..τ_{N−1} (torque[k], k = 0..N, τ_0 = τ_N = 0) through the problem's scheme from
/// R_0, Ω_0 and fills result->maneuver, cost, dynamics_residual and the terminal errors.
/// Both solvers finish through here, so every reported figure is measured on the same replay.
/// Throws StepTooLarge if the replay's implicit step fails.
void evaluatePlan(const PlanningProblem& problem, const std::vector<Vector3>& torque,
                  PlanResult* result);

}  // namespace attitude_planner
