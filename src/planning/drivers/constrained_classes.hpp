// The cheapest homotopy class under constraints: a constrained request that leaves its class free
// (classLeftFree) is first solved from the unconstrained optimum's class (the class survey's
// cheapest). Where that ends without a plan (infeasible or unconverged: a verdict about one class
// only), the classes the survey solved are solved under the constraints on the survey grid, and
// the cheapest there, if it is not the first, is solved on the requested grid too; the better
// plan is kept. (A class's unconstrained cost is no bound on what its constrained solve
// reaches: a class is a lift of the rotation, and lifts two turns apart are one homotopy class on
// SO(3), whose loops are Z₂, so the interior point can slide from one to the other.)
#pragma once

#include <vector>

#include "attitude_planner/planning/problem.hpp"
#include "attitude_planner/planning/result.hpp"
#include "planning/newton/newton_solver.hpp"

namespace attitude_planner {

/// Two plans whose largest violation between the nodes (PlanResult::max_violation_between_nodes)
/// differs by more than this are told apart by it before their cost.
constexpr double kBetweenNodesSlack = 1e-3;

/// `first` (the constrained solve from the unconstrained optimum's class, on the requested grid)
/// if it converged; else the better of it and the cheapest other class under the constraints: every
/// class `survey` (the unconstrained solve's structured extremal) solved is solved under the
/// constraints on its survey grid (the requested grid if that is no finer), and the cheapest there
/// carried to the requested grid by a solve in its class. The result's extremal lists each class
/// tried (stage constrained_class) after the survey's attempts; its attempts are the context's
/// from `first_recorded` (where `first`'s began), the best plan's attempt kept. `first` is returned
/// as it is when the survey solved no other class. A class with a plan in `survey_plans`
/// (solveWithNewton's) on the grid of its solve starts from it: its unconstrained Newton solve is
/// not run again (SolverOptions::unconstrained_optimum).
PlanResult cheapestConstrainedClass(const PlanningProblem& problem, const SolverOptions& options,
                                    SolveContext& context, const ExtremalSummary& survey,
                                    const std::vector<ClassPlan>& survey_plans, PlanResult first,
                                    std::size_t first_recorded);

}  // namespace attitude_planner
