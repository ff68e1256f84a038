// Placeholder until the Newton solver lands (in progress in this session): reports failure.
#include "attitude_planner/solvers.hpp"

namespace attitude_planner {

PlanResult solveWithNewton(const PlanningProblem&, const SolverOptions&) {
  PlanResult result;
  result.converged = false;
  result.message = "newton solver not implemented yet";
  return result;
}

}  // namespace attitude_planner
