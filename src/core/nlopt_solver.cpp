// Placeholder until the NLopt cross-check lands: reports failure.
#include "attitude_planner/solvers.hpp"

namespace attitude_planner {

PlanResult solveWithNlopt(const PlanningProblem&, const SolverOptions&) {
  PlanResult result;
  result.converged = false;
  result.message = "nlopt solver not implemented yet";
  return result;
}

}  // namespace attitude_planner
