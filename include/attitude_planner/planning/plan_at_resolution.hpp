// The fixed-resolution planner: solves the problem at its own N with the chosen solver. The
// public entry point planManeuver() (attitude_planner/planner.hpp) calls it, directly or through
// planToAccuracy() (analysis/accuracy.hpp), which chooses N first.
#pragma once

#include "attitude_planner/planning/problem.hpp"
#include "attitude_planner/planning/result.hpp"
#include "attitude_planner/planning/verdict.hpp"

namespace attitude_planner {

/// Plans at problem.steps (problem.accuracy is ignored). Validates the problem and options
/// (InvalidInput), refuses boundary velocities without a step (StepTooLarge), times the solve.
PlanResult planAtResolution(const PlanningProblem& problem, const SolverOptions& options = {});

}  // namespace attitude_planner
