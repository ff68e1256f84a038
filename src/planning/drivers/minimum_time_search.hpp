// The search for T* (the fallback of minimum time, drivers/minimum_time.cpp): several starts,
// each a continuation downwards in T over minimum-effort solves warm-started from the last
// feasible plan, and a bisection of the best bracket; its T* is the least duration found
// feasible, an upper bound. Used where the free-time interior point does not apply or none of its
// solves converged.
#pragma once

#include "attitude_planner/planning/plan_at_resolution.hpp"
#include "planning/problem/solve_context.hpp"

namespace attitude_planner {

/// A minimum-time answer at `T` from a plan that proves T feasible (provesFeasible in
/// planning/problem/verdict.hpp; a minimum-effort solve that stopped short of optimality proves
/// it too, and whether it also minimizes the effort does not matter to the search — measured: on
/// Bilimoria–Wie's case the solves just below the T* found stopped at the iteration limit with
/// feasible iterates): T is the
/// least duration found feasible, which is what a minimum-time answer rests on, whether or not
/// the plan's minimum-effort solve stopped short of optimality (then said as
/// FeasibleAtMinimumTime, and the answer is converged). One rule for the search's T* and for a
/// probe's plan below a free-time T*.
void answerFeasibleAt(double T, PlanResult* plan);

/// The plan at the least feasible T the search finds (minimum_duration = T*, minimum_time.kkt_point
/// false), or why there is none (Infeasible: no duration up to 2^12 times the first guess; the
/// stop's termination when cancelled or out of time; not converged where it stopped at its work
/// allowance, AdvancedParameters::search_work_allowance, before a duration was found feasible). Its
/// solves run in `context` with its options().
PlanResult searchMinimumTime(const PlanningProblem& problem, SolveContext& context);
/// The same as a request of its own (tests, studies).
PlanResult searchMinimumTime(const PlanningProblem& problem, const SolverOptions& options);

}  // namespace attitude_planner
