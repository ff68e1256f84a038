// The unconstrained solver: Newton on the reduced problem with grid continuation and its starts,
// run in the order of attempts of newton_solver.cpp's recipe. Call planManeuver() rather than
// this directly: it validates the problem and times the solve.
#pragma once

#include "attitude_planner/planning/problem.hpp"
#include "attitude_planner/planning/result.hpp"
#include "planning/problem/solve_context.hpp"

namespace attitude_planner {

/// Newton's method on the first-order optimality conditions, O(N) per iteration, every attempt
/// of the recipe in `context` (its deadline, cancel flag, iteration numbering; each attempt is
/// recorded in its trail, the kept one marked). Fills everything but solve_time_s; `attempts` is
/// the context's trail.
PlanResult solveWithNewton(const PlanningProblem& problem, SolveContext& context);

/// The same in a context of its own.
PlanResult solveWithNewton(const PlanningProblem& problem, const SolverOptions& options);

/// The steps ω_k, k = 0..N−1, of the Newton solver's first guess on the requested grid (the
/// rate-honouring Hermite curve to the nearest lift, or the other way round for LongWay), before
/// any continuation level: the start a peer solver gets in a like-for-like comparison
/// (benchmark_solvers --random-suite). Throws StepTooLarge like ReducedProblem.
std::vector<Vector3> newtonInitialSteps(const PlanningProblem& problem);

}  // namespace attitude_planner
