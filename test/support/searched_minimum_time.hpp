// The former search on T over minimum-effort solves (planning/drivers/minimum_time_search.hpp)
// on a request, called directly: the reference the free-time answer is checked against (an
// upper bound on the discrete T*). planManeuver answers minimum time by the free-time interior
// point wherever it applies, effects included.
#pragma once

#include "attitude_planner/planning/problem.hpp"
#include "planning/drivers/minimum_time_search.hpp"

namespace attitude_planner::test_support {

/// The search's answer to `problem` (objective minimum_time) with default options.
inline PlanResult searchedMinimumTime(const PlanningProblem& problem) {
  validateProblem(problem);
  return searchMinimumTime(problem, SolverOptions());
}

}  // namespace attitude_planner::test_support
