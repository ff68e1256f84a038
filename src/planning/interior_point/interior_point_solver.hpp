// The constrained solver: a primal–dual interior point on the reduced problem with the node
// constraints. Call planManeuver() rather than this directly.
#pragma once

#include "attitude_planner/planning/problem.hpp"
#include "attitude_planner/planning/result.hpp"

namespace attitude_planner {

/// Primal–dual interior point on the reduced problem with the node constraints (per-axis torque
/// bounds, PlanningProblem::constraints), O(N) per iteration (interior_point_solver.cpp). Starts
/// from options.warm_start if given. Sets PlanResult::infeasible when the constraints cannot be
/// met. Fills everything but solve_time_s and the constraint figures.
PlanResult solveWithInteriorPoint(const PlanningProblem& problem, const SolverOptions& options);

}  // namespace attitude_planner
