// Minimum-time slews (objective minimum_time): the least duration T* at which the torque bounds
// and constraints in force admit a plan, and the plan at T* (bang–bang) or at (1 + m)·T*.
//
// Method (src/planning/drivers/minimum_time*.cpp): minimum time as ONE interior-point problem per
// start, the time step h (T = N h) an unknown next to the node unknowns, objective T, the
// request's stage constraints (torque bounds, cones and rate limits) as
// constraints (src/planning/interior_point/free_time_solver.hpp). Starts, rest to rest:
// the eigenaxis bang–bang slew at its closed-form T and excursions off it about the body axes'
// parts perpendicular to the eigenaxis and their diagonals (body-fixed: the same in every world
// frame); otherwise the geodesic. Above N = 64 the starts run on N = 64 and the best is refined
// by 2 at a time up to N (each level from the coarser answer's rates interpolated in time). Each
// start's solve is stopped where it can no longer end below the least T so far, or where it
// joins an earlier start's central path. The least T is kept; its free-time plan is the answer
// (the switching functions from its bound multipliers). With cones each start is first made to
// clear them (a minimum-effort plan under the cones tightened by 0.01 rad). T* is a KKT point of
// the discrete minimum-time problem, its residuals in PlanResult::minimum_time; with effects too
// (their time t_k = k h moves with h). With spinning ends the answer is also probed below T* by
// minimum-effort solves, and a plan found there lowers it. fourth_order's T* is the larger of the
// two second_order minimum times at N and 2N (both plans must exist at T), a KKT point of the
// pair. Where no free-time solve converges, a search answers (a continuation down in T over
// minimum-effort solves and a bisection to kMinimumTimeTolerance): its T* is the least duration
// found feasible, an upper bound (minimum_time.kkt_point false); its plan then starts one more
// free-time solve, whose KKT point at or below the search's T is the answer if it converges.
// docs/results/minimum_time.md has the figures.
#pragma once

#include "attitude_planner/planning/plan_at_resolution.hpp"

namespace attitude_planner {

/// Relative width of the search's final bracket on T* (the fallback).
constexpr double kMinimumTimeTolerance = 1e-9;

/// The minimum-time plan of `problem` (objective minimum_time). Throws InvalidInput naming the
/// field if no torque bound is in force (actuator_limits or max_torque_norm), for a negative
/// time_margin, or together with an accuracy target. The result's `minimum_duration` is T*,
/// `duration` the T of the returned plan ((1 + time_margin)·T*, planned from the T* plan). A
/// problem.duration > 0 is an upper bound: T* above it ends Infeasible, naming T*.
PlanResult planMinimumTime(const PlanningProblem& problem, const SolverOptions& options);

/// A minimum-effort plan at problem.duration whose "infeasible" is backed (defined in
/// src/planning/drivers/minimum_effort.cpp): when the solve ends Infeasible, stops, or leaves a
/// bound under a torque bound, the minimum-time problem under the same bounds either shows the
/// duration feasible (T* ≤ T: the plan is solved again from the T* plan, which meets every bound
/// with room, through a ladder of durations where that start is stuck) or the answer is
/// "infeasible from here": T* is the least duration at which a plan was found, a local figure,
/// not a requirement, beside the proven lower bound on T where one is known
/// (duration_verdict). The result's minimum_duration is that T* (0 when it was not needed or
/// not found).
PlanResult planBoundedMinimumEffort(const PlanningProblem& problem, const SolverOptions& options);

/// A duration at which an eigenaxis bang–bang slew would need the smallest authority of the
/// bounds in force, boundary rates shed and gained at that authority (the first guess when the
/// problem gives none) [s]: never below the proven lower bound (durationLowerBound), and with
/// spinning ends at most representableDuration unless that is below the proven bound.
double eigenaxisDurationGuess(const PlanningProblem& problem);

/// The longest T at which the grid's boundary steps turn at most 1 rad at the boundary rates
/// (infinity at rest): a start longer than this may have no boundary step at all [s].
double representableDuration(const PlanningProblem& problem);

}  // namespace attitude_planner
