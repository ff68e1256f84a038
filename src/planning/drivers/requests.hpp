// The drivers' entry points inside one request. Each takes the request's SolveContext (built
// once: by planManeuver, or by a public entry point called on its own), so every solve of the
// request shares its clock and deadline, its cancel flag, one iteration numbering and one trail;
// a driver hands its solvers their own options (warm start, class policy) beside it.
#pragma once

#include "attitude_planner/planning/problem.hpp"
#include "attitude_planner/planning/result.hpp"
#include "planning/problem/solve_context.hpp"
#include "planning/problem/solve_request.hpp"

namespace attitude_planner {

/// planAtResolution (plan_at_resolution.hpp) with `request` for this solve (the user's options
/// and where it starts), in `context`.
PlanResult planAtResolution(const PlanningProblem& problem, const SolveRequest& request,
                            SolveContext& context);

/// Node constraints from no guess of their own: the unconstrained optimum first (fast path): if
/// it meets every node constraint it is the constrained optimum too; otherwise it starts the
/// interior point, in its class, and a request that left its class free has the other classes
/// solved under the constraints too (constrained_classes.hpp), each from its class survey's plan
/// (minimum_effort.cpp).
PlanResult planUnderConstraints(const PlanningProblem& problem, const SolveRequest& request,
                                SolveContext& context);

/// planMinimumTime (minimum_time.hpp) with the request's options, context.options().
PlanResult planMinimumTime(const PlanningProblem& problem, SolveContext& context);

/// planBoundedMinimumEffort (minimum_time.hpp, defined in minimum_effort.cpp) with the request's
/// options, context.options().
PlanResult planBoundedMinimumEffort(const PlanningProblem& problem, SolveContext& context);

}  // namespace attitude_planner
