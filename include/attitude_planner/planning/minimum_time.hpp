// Minimum-time slews (objective minimum_time): the least duration T* at which the torque bounds
// and constraints in force admit a plan, and the plan at T* (bang–bang) or at (1 + m)·T*.
//
// Method: a search on T over minimum-effort problems with the same N and constraints, each
// solved by the interior-point solver (plan_at_resolution.hpp) and warm-started from the last
// feasible plan: from the first feasible T (the problem's duration or an eigenaxis guess, doubled
// until feasible) down in steps of 5 % while feasible, then bisection of the last step to a
// relative width of kMinimumTimeTolerance. A solve that does not converge counts as infeasible
// at that T. T* is therefore the least duration the solver found feasible: an upper bound on the
// true minimum, equal to it where the interior point's "infeasible" verdicts are right (checked
// against the closed form of a spherical body under a torque-norm bound), above it where they are
// not (Betts's asymmetric body under per-axis bounds: docs/minimum_time.md).
#pragma once

#include "attitude_planner/planning/plan_at_resolution.hpp"

namespace attitude_planner {

/// Relative width of the final bracket on T*.
constexpr double kMinimumTimeTolerance = 1e-9;

/// The minimum-time plan of `problem` (objective minimum_time). Throws InvalidInput naming the
/// field if no torque bound is in force (actuator_limits or max_torque_norm), for a negative
/// time_margin, or together with an accuracy target. The result's `minimum_duration` is T*,
/// `duration` the T of the returned plan ((1 + time_margin)·T*).
PlanResult planMinimumTime(const PlanningProblem& problem, const SolverOptions& options);

/// A duration at which an eigenaxis bang–bang slew would need the smallest authority of the
/// bounds in force (the search's first guess when the problem gives none) [s].
double eigenaxisDurationGuess(const PlanningProblem& problem);

}  // namespace attitude_planner
