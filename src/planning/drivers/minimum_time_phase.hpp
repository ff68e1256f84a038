// What the bounded minimum-effort driver (minimum_effort.cpp) asks of minimum time's
// (minimum_time.cpp): T* under the same bounds, and plans at T ≥ T* started from the plan at T*.
#pragma once

#include <string>

#include "attitude_planner/planning/problem.hpp"
#include "attitude_planner/planning/result.hpp"
#include "planning/problem/solve_context.hpp"

namespace attitude_planner {

/// fourth_order's minimum-time answer keeps its two second_order plans at T* (each meeting its
/// bounds there): a plan at T ≥ T* starts each sub-solve from its own (fourthOrderFromPair).
struct RichardsonPair {
  Maneuver coarse;  ///< the second_order plan at T*, N steps
  Maneuver fine;    ///< the second_order plan at T*, 2N steps
};

/// What T* is, for messages.
std::string tStarKind(const PlanResult& r);

/// The minimum-time answer of `problem` (its starts, refinement and probes), from several start
/// twists where the end condition is a pointing one (its R_N then posed at each:
/// pointingMinimumTime). fourth_order keeps its two plans at T* in `*pair`.
PlanResult minimumTimeOverTwists(const PlanningProblem& problem, SolveContext& context,
                                 RichardsonPair* pair);

/// `problem` as a minimum-effort problem at T from the plan `at_minimum_time` (attitudes at
/// T*): slower than the bang–bang plan, every node constraint is met with room (torques scale
/// like (T*/T)², rates like T*/T for rest-to-rest motions), so the interior point starts
/// strictly inside instead of from the unconstrained optimum, with a request's own recipe
/// (StartSpec::strictly_inside).
PlanResult planFromMinimumTimePlan(const PlanningProblem& problem, double T,
                                   const Maneuver& at_minimum_time, SolveContext& context);

/// A plan at T ≥ T* from the minimum-time answer (its plan, and for fourth_order its pair).
PlanResult planFromMinimumTime(const PlanningProblem& problem, double T,
                               const Maneuver& at_minimum_time, const RichardsonPair& pair,
                               SolveContext& context);

}  // namespace attitude_planner
