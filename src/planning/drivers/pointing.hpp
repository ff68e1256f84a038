// Minimum effort to a pointing end condition (R_N b = d, the twist ψ about b free): one problem
// in the unknowns (δ, ψ), solved by the twist Newton (newton/twist_newton.hpp) from starts over
// ψ and the ways round, the cheapest kept.
#pragma once

#include <cmath>

#include "attitude_planner/planning/problem.hpp"
#include "attitude_planner/planning/result.hpp"
#include "planning/problem/solve_context.hpp"
#include "planning/problem/solve_request.hpp"

namespace attitude_planner {

/// Start twists per way round: ψ₀ + 2πi/kPointingStartTwists, ψ₀ the twist of least rotation from
/// R_0 (nearestTwist). With both ways round that is 2·kPointingStartTwists survey solves.
constexpr int kPointingStartTwists = 4;

/// A constrained request whose unconstrained twist optimum ψ* crosses a cone deeper than the
/// fixed-twist unconstrained optima at ψ* ± kPointingRidgeOffset [rad] do (a ridge of the
/// constrained cost over ψ: the plan passes the cone on one side or the other) starts the interior
/// point with ψ free from those two optima instead of from ψ*'s.
constexpr double kPointingRidgeOffset = M_PI / 4.0;

/// Only an unconstrained twist optimum whose path comes within (1 − this) of a cone's node half
/// angle a of its axis (least relative margin (angle − a)/a below −this) is checked for a ridge:
/// a path across the cone's rim has one way round, and the check's two fixed-twist solves were a
/// fast request's largest part (measured on the keep-out requests of seeds 41, 43 and 47: every
/// ridge at −0.87 or deeper, the shallowest −0.87; 36 of 50 with seeds 53 and 59 skip the check).
constexpr double kPointingRidgeDepth = 0.85;

/// Plans `problem` (end_condition.pointing(), validated) in `context` with `options` for this
/// solve: the starts solved on a coarse survey grid (the coarsest of 16·4^k steps whose boundary
/// steps stay small, or the requested grid), the distinct converged answers within the class
/// survey's margin of the cheapest carried to the requested grid through factor-4 levels, the
/// cheapest converged plan kept. Every start and refinement is an attempt in the trail (its start
/// twist in start_detail.twist). Throws InvalidInput for a solver or warm start it cannot serve.
PlanResult planPointing(const PlanningProblem& problem, const SolveRequest& options,
                        SolveContext& context);

}  // namespace attitude_planner
