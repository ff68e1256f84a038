// Minimum-time slews (objective minimum_time): the least duration T* at which the torque bounds
// and constraints in force admit a plan, and the plan at T* (bang–bang) or at (1 + m)·T*.
//
// Method: searches on T over minimum-effort problems with the same N and constraints, each solve
// by the interior-point solver (plan_at_resolution.hpp) warm-started from the last feasible plan
// of its search: from a first T down in steps of 5 % while feasible; the search with the least
// feasible T then bisects its last step to a relative width of kMinimumTimeTolerance. A solve that
// does not converge counts as infeasible at that T. Minimum-time problems have several local
// optima, so there are several starts: the minimum-effort continuation from the problem's
// duration (or an eigenaxis guess, doubled until feasible) and, rest to rest, the eigenaxis
// bang–bang slew and excursions off it (two sizes, ±two perpendicular axes, first solved just
// above and just below the eigenaxis T). Above N = 64 the starts are searched on the grid with
// half the steps and its T* plan starts the search here. The message names the start that won
// and every start's T. T* is the least duration found feasible: an upper bound on the true
// minimum (docs/results/minimum_time.md: Betts's published T* reached to 0.05 %, Bilimoria–Wie's to 2 %).
#pragma once

#include "attitude_planner/planning/plan_at_resolution.hpp"

namespace attitude_planner {

/// Relative width of the final bracket on T*.
constexpr double kMinimumTimeTolerance = 1e-9;

/// The minimum-time plan of `problem` (objective minimum_time). Throws InvalidInput naming the
/// field if no torque bound is in force (actuator_limits or max_torque_norm), for a negative
/// time_margin, or together with an accuracy target. The result's `minimum_duration` is T*,
/// `duration` the T of the returned plan ((1 + time_margin)·T*, planned from the T* plan). A
/// problem.duration > 0 is an upper bound: T* above it ends Infeasible, naming T*.
PlanResult planMinimumTime(const PlanningProblem& problem, const SolverOptions& options);

/// A minimum-effort plan at problem.duration whose "infeasible" is backed: when the solve ends
/// Infeasible under a torque bound, the minimum-time problem under the same bounds either shows
/// the duration feasible (T* ≤ T: the plan is solved again from the T* plan, which meets every
/// bound with room) or names the least duration found feasible ("needs T >= T* s"); the
/// result's minimum_duration is that T* (0 when it was not needed or not found).
PlanResult planBoundedMinimumEffort(const PlanningProblem& problem, const SolverOptions& options);

/// A duration at which an eigenaxis bang–bang slew would need the smallest authority of the
/// bounds in force (the search's first guess when the problem gives none) [s].
double eigenaxisDurationGuess(const PlanningProblem& problem);

}  // namespace attitude_planner
