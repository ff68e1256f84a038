// fourth_order: one Richardson extrapolation step of second_order (docs/design/fourth_order.md).
// The combination of a second_order plan at N and one at 2N is written here once; the
// minimum-effort plan (plan_at_resolution.cpp, planFourthOrder) and the minimum-time plan
// (minimum_time.cpp: the pair of second_order minimum-time problems) both use it.
#pragma once

#include "attitude_planner/planning/problem.hpp"
#include "attitude_planner/planning/result.hpp"

namespace attitude_planner {

/// The fourth_order plan at problem.duration (problem.scheme fourth_order, problem.steps = N) from
/// two converged second_order plans of one extremal at that duration, `coarse` at N and `fine` at
/// 2N. second_order is time-symmetric, so its node values have an error expansion in even powers
/// of h; X = X_{2N} + (X_{2N} − X_N)/3 at the N + 1 common nodes cancels the h² term. On the
/// group, R_k = R^{2N}_{2k} exp(⅓ log((R^N_k)ᵀ R^{2N}_{2k})); R_0, R_N are the boundary data.
/// The result also carries the scheme's effort quadrature, the replay (cubic hold, RKMK4), the
/// node constraint figures measured on the combined plan, the worse of the two solves' residuals,
/// both solves' levels, history and iterations, and the fine solve's extremal. The caller writes
/// the message and the trail.
PlanResult richardsonCombination(const PlanningProblem& problem, const PlanResult& coarse,
                                 const PlanResult& fine);

/// richardsonCombination, unless the combination leaves a node bound (beyond
/// kNodeConstraintTolerance relative) that both plans meet: then the `coarse` plan itself, measured
/// as a fourth_order plan (`*replaced` true). Near a bound the combination has no h² expansion to
/// cancel: a bang–bang plan's switches move by O(h) from N to 2N, and where the 2N torque is at
/// its bound a and the N torque c is inside, the combination reaches a + (a − c)/3. Used where
/// one plan sits on its bounds by construction (minimum time and the plans from it); measured on
/// Bilimoria–Wie and Betts at N = 32 … 128 (docs/design/fourth_order.md, "Minimum time"), the N
/// plan at T* (a minimum-effort plan with slack) meets every bound and replays with a 4–40×
/// smaller terminal miss than the combination.
PlanResult richardsonCombinationWithinTheBounds(const PlanningProblem& problem,
                                                const PlanResult& coarse, const PlanResult& fine,
                                                bool* replaced = nullptr);

}  // namespace attitude_planner
