// The unconstrained solver: Newton on the reduced problem with grid continuation and its starts,
// run in the order of attempts of newton_solver.cpp's recipe. Call planManeuver() rather than
// this directly: it validates the problem and times the solve.
#pragma once

#include <vector>

#include "attitude_planner/planning/problem.hpp"
#include "attitude_planner/planning/result.hpp"
#include "planning/problem/solve_context.hpp"
#include "planning/problem/solve_request.hpp"

namespace attitude_planner {

/// A plan the class survey converged to in one class (solveWithNewton's `survey_plans`).
struct ClassPlan {
  HomotopyClass homotopy;
  Maneuver plan;  ///< on the grid it was solved on (plan.steps())
};

/// Newton's method on the first-order optimality conditions, O(N) per iteration, every attempt
/// of the recipe in `context` (its deadline, cancel flag, iteration numbering; each attempt is
/// recorded in its trail, the kept one marked), with the solve's own `request` (warm start,
/// tolerance, class policy: SolveContext::Call; a warm start that is the request's
/// start.unconstrained_optimum is named an earlier attempt's plan). Fills everything but
/// solve_time_s; `attempts` is this solve's part of the context's trail. `survey_plans` (optional)
/// receives the class survey's converged plans (a request that leaves its class free): each class
/// on the survey grid, and those refined on the requested grid there too; they start the
/// constrained class search (drivers/constrained_classes.hpp) instead of solving each class again.
/// A plan's check (planInconsistency) runs only where the walk's choice depends on it: the plan
/// kept is always checked, a plan that fails its check is never kept (unless none converged), and
/// the others' attempts say `plan_checked` false.
/// `replayed` (optional): the caller measures the returned plan's open-loop replay
/// (replayFigures of `problem`) unless this says the walk measured it already: with more than one
/// thread the request's own class's plan is checked beside its replay, and is kept in most
/// requests.
PlanResult solveWithNewton(const PlanningProblem& problem, const SolveRequest& request,
                           SolveContext& context, std::vector<ClassPlan>* survey_plans = nullptr,
                           bool* replayed = nullptr);

/// The steps ω_k, k = 0..N−1, of the Newton solver's first guess on the requested grid (the
/// rate-honouring Hermite curve to the nearest lift, or the other way round for LongWay), before
/// any continuation level: the start a peer solver gets in a like-for-like comparison
/// (benchmark_solvers --random-suite). Throws StepTooLarge like ReducedProblem.
std::vector<Vector3> newtonInitialSteps(const PlanningProblem& problem);

}  // namespace attitude_planner
