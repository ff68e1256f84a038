// The constrained recipe: minimum effort under node constraints by the fixed-h interior point
// (interior_point/grid_solve.hpp), its attempts in order (constrained_recipe.cpp). Call
// planManeuver() rather than this directly.
#pragma once

#include "attitude_planner/planning/problem.hpp"
#include "attitude_planner/planning/result.hpp"
#include "planning/interior_point/grid_solve.hpp"
#include "planning/problem/solve_context.hpp"
#include "planning/problem/solve_request.hpp"

namespace attitude_planner {

/// Primal–dual interior point on the reduced problem with the node constraints (per-axis torque
/// bounds, PlanningProblem::constraints), O(N) per iteration (constrained_recipe.cpp). Starts
/// from request.warm_start if given (request.start says what that plan is). Ends Infeasible when
/// the constraints cannot be met. Polls `context` (cancel flag, deadline) inside its long loops,
/// reports its iterations and records its attempts there (the kept one marked; they are its
/// PlanResult::attempts too). Fills everything but solve_time_s and the constraint figures. Its
/// constants: request.advanced.interior_point.
PlanResult solveWithInteriorPoint(const PlanningProblem& problem, const SolveRequest& request,
                                  SolveContext& context);

/// The interior point on `problem`'s own grid alone (no grid continuation, no staged retry), for a
/// driver that runs its own levels (pointing): from `start_steps` (steps of this N, or of a coarser
/// grid's solution) with `start_duals` (free slacks; may be null), else from the geodesic, in the
/// request's formulation with its retry (not after `watch`, where given, stopped the first: see
/// GridRequest::watch). Reports its iterations through `context`; records no attempt.
GridOutcome solveInteriorPointOnGrid(const PlanningProblem& problem, const SolverOptions& options,
                                     SolveContext& context,
                                     const ReducedProblem::StepVectors* start_steps,
                                     const LevelDuals* start_duals,
                                     const FeasibleIterateWatch* watch = nullptr);

/// The interior point from request.warm_start (a plan given as the initial guess, with the
/// problem's N: initialGuessOnGrid) rather than from the unconstrained optimum.
PlanResult solveWithInteriorPointFromGuess(const PlanningProblem& problem,
                                           const SolveRequest& request, SolveContext& context);

}  // namespace attitude_planner
