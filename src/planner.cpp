// planManeuver(): the one entry point. It sits above the analysis layer because a requested
// accuracy makes it choose N (planToAccuracy) before planning at that resolution.
#include "attitude_planner/planner.hpp"

#include "attitude_planner/analysis/accuracy.hpp"
#include "attitude_planner/planning/minimum_time.hpp"
#include "attitude_planner/planning/plan_at_resolution.hpp"

namespace attitude_planner {

PlanResult planManeuver(const PlanningProblem& problem, const SolverOptions& options) {
  if (problem.objective == Objective::MinimumTime) return planMinimumTime(problem, options);
  if (problem.accuracy.active()) {
    validateProblem(problem);
    validateOptions(options);
    return planToAccuracy(problem, options);
  }
  return planBoundedMinimumEffort(problem, options);
}

}  // namespace attitude_planner
