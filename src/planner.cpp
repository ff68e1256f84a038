// planManeuver(): the one entry point. It sits above the analysis layer because a requested
// accuracy makes it choose N (planToAccuracy) before planning at that resolution. It builds the
// request's SolveContext (clock and deadline, cancel flag, iteration numbering, trail), which every
// driver and solver of the request shares (planning/drivers/requests.hpp).
#include "attitude_planner/planner.hpp"

#include "attitude_planner/analysis/accuracy.hpp"
#include "attitude_planner/planning/minimum_time.hpp"
#include "attitude_planner/planning/plan_at_resolution.hpp"
#include "attitude_planner/planning/pointing.hpp"
#include "planning/drivers/requests.hpp"
#include "planning/transcription/reduced_problem.hpp"

namespace attitude_planner {

namespace {

PlanResult planRequest(const PlanningProblem& problem, const SolverOptions& options) {
  if (problem.accuracy.active() && problem.objective != Objective::MinimumTime) {
    validateProblem(problem);
    validateOptions(options);
    return planToAccuracy(problem, options);  // one request per resolution it tries
  }
  SolveContext context(options);
  PlanResult result = problem.objective == Objective::MinimumTime
                          ? planMinimumTime(problem, context)
                          : planBoundedMinimumEffort(problem, context);
  // The request's iterations are the ones its context numbered (every solve of the package's own
  // solvers reports there), not the drivers' sums, which dropped the solves a later phase
  // replaced (measured: minimum time 30 counted of 1,542 run). NLopt counts its own.
  if (options.solver == SolverKind::Structured) result.iterations = context.iterations();
  return result;
}

}  // namespace

PlanResult planManeuver(const PlanningProblem& problem, const SolverOptions& options) {
  PlanResult result = planRequest(problem, options);
  // What the transcription's cost sums (NLopt's dense transcription minimizes the same τ_k).
  result.minimized_effort = ReducedProblem::kMinimizedEffort;
  if (problem.end_condition.pointing()) {
    result.pointing.infeasible_basis = pointingInfeasibleBasis(result);
  }
  return result;
}

}  // namespace attitude_planner
