// The independent cross-check: NLopt on the direct method. Call planManeuver() rather than this.
#pragma once

#include "attitude_planner/planning/problem.hpp"
#include "attitude_planner/planning/result.hpp"

namespace attitude_planner {

/// Independent cross-check: NLopt on the direct method (τ_1..τ_{N−1} as variables, equality
/// constraints on the terminal state, exact gradients) (nlopt_solver.cpp).
PlanResult solveWithNlopt(const PlanningProblem& problem, const SolverOptions& options);

}  // namespace attitude_planner
