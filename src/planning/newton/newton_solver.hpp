// The unconstrained solver: Newton on the reduced problem with grid continuation and its starts.
// Call planManeuver() rather than this directly: it validates the problem and times the solve.
#pragma once

#include "attitude_planner/planning/problem.hpp"
#include "attitude_planner/planning/result.hpp"

namespace attitude_planner {

/// Newton's method on the first-order optimality conditions, O(N) per iteration
/// (newton_solver.cpp). Fills everything but solve_time_s.
PlanResult solveWithNewton(const PlanningProblem& problem, const SolverOptions& options);

/// The steps ω_k, k = 0..N−1, of the Newton solver's first guess on the requested grid (the
/// rate-honouring Hermite curve to the nearest lift, or the other way round for LongWay), before
/// any continuation level: the start a peer solver gets in a like-for-like comparison
/// (benchmark_solvers --random-suite). Throws StepTooLarge like ReducedProblem.
std::vector<Vector3> newtonInitialSteps(const PlanningProblem& problem);

}  // namespace attitude_planner
