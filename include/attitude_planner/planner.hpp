// The one entry point for planning a fully actuated maneuver: the CLI `plan_maneuver`, the planner
// node, the tracker and the studies all call planManeuver(). It includes the problem, options and
// result types, so this is the only header a caller needs.
#pragma once

#include "attitude_planner/planning/problem.hpp"
#include "attitude_planner/planning/result.hpp"

namespace attitude_planner {

/// Plans the maneuver. Throws InvalidInput for a bad problem or options, StepTooLarge if a
/// boundary velocity has no step at h = T/N (the message names it and says "increase steps");
/// never throws for a solve that does not converge (PlanResult::converged = false says so, with
/// the reason). With an active problem.accuracy it chooses N itself (planToAccuracy,
/// accuracy.hpp).
PlanResult planManeuver(const PlanningProblem& problem, const SolverOptions& options = {});

}  // namespace attitude_planner
