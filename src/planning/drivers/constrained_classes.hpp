// The cheapest homotopy class under constraints: a constrained request that leaves its class free
// (classLeftFree) is first solved from the unconstrained optimum's class (the class survey's
// cheapest). Which side of a cone the interior point passes depends on that start, which violates
// the cone, so the first plan is checked against the class's plan on the survey grid: where that
// coarse plan's h·cost is lower, the class is solved again from it. Where the first solve ends
// without a plan (infeasible or unconverged: a verdict about one class and one start only), the
// classes the survey solved are solved under the constraints on the survey grid and carried to
// the requested grid: with cones only, in order of their cost there, each from its own coarse
// plan, until one holds the constraints between the nodes too; under torque or rate bounds, the
// best coarse plan's class alone, from its coarse plan under the bounds, then from its
// unconstrained optimum where it is another class (carryUnderBounds). Once a plan is in hand, every
// other class whose unconstrained optimum on the requested grid costs less than it is solved under
// the constraints too, the cheaper plan kept: the constraints only add to a class's cost from its
// own optimum. (That bound holds in the class's basin, not globally: a class is a lift of the
// rotation, and lifts two turns apart are one homotopy class on SO(3), whose loops are Z₂, so the
// interior point can slide from one to the other.) A class whose survey cost is beyond the survey's
// refine margin of the first class's, raised as much as the constraints raised the first's, is not
// solved. The first-plan check and the other classes' solves are for requests whose constraints are
// all cones; under torque or rate bounds a converged first class answers.
#pragma once

#include <vector>

#include "attitude_planner/planning/problem.hpp"
#include "attitude_planner/planning/result.hpp"
#include "planning/newton/newton_solver.hpp"

namespace attitude_planner {

/// Two plans whose largest violation between the nodes (PlanResult::max_violation_between_nodes)
/// differs by more than this are told apart by it before their cost.
constexpr double kBetweenNodesSlack = 1e-3;

/// The cheapest plan over the classes `survey` (the unconstrained solve's structured extremal)
/// solved, under the constraints, as the comment above describes; `first` is the constrained solve
/// from the unconstrained optimum's class on the requested grid, `unconstrained_cost` that
/// optimum's cost (NaN: unknown). The result's extremal lists each
/// class tried (stage constrained_class) after the survey's attempts; its attempts are the
/// context's from `first_recorded` (where `first`'s began), the best plan's attempt kept. `first`
/// is returned as it is when the survey solved no other class. A class with a plan in
/// `survey_plans` (solveWithNewton's) on the grid of its solve starts from it: its unconstrained
/// Newton solve is not run again (StartSpec::unconstrained_optimum).
PlanResult cheapestConstrainedClass(const PlanningProblem& problem, const SolveRequest& options,
                                    SolveContext& context, const ExtremalSummary& survey,
                                    const std::vector<ClassPlan>& survey_plans, PlanResult first,
                                    double unconstrained_cost, std::size_t first_recorded);

}  // namespace attitude_planner
