// Minimum effort to a pointing end condition (R_N b = d, the twist ψ about b free): one problem
// in the unknowns (δ, ψ), solved by the twist Newton (newton/twist_newton.hpp) from starts over
// ψ and the ways round, the cheapest kept.
#pragma once

#include <cmath>

#include "attitude_planner/planning/problem.hpp"
#include "attitude_planner/planning/result.hpp"
#include "planning/problem/solve_context.hpp"

namespace attitude_planner {

/// Start twists per way round: ψ₀ + 2πi/kPointingStartTwists, ψ₀ the twist of least rotation from
/// R_0 (nearestTwist). With both ways round that is 2·kPointingStartTwists survey solves.
constexpr int kPointingStartTwists = 4;

/// A constrained request whose unconstrained twist optimum ψ* crosses a cone deeper than the
/// fixed-twist unconstrained optima at ψ* ± kPointingRidgeOffset [rad] do (a ridge of the
/// constrained cost over ψ: the plan passes the cone on one side or the other) starts the interior
/// point with ψ free from those two optima instead of from ψ*'s.
constexpr double kPointingRidgeOffset = M_PI / 4.0;

/// Plans `problem` (end_condition.pointing(), validated) in `context` with `options` for this
/// solve: the starts solved on a coarse survey grid (the coarsest of 16·4^k steps whose boundary
/// steps stay small, or the requested grid), the distinct converged answers within the class
/// survey's margin of the cheapest carried to the requested grid through factor-4 levels, the
/// cheapest converged plan kept. Every start and refinement is an attempt in the trail (its start
/// twist in start_detail.twist). Throws InvalidInput for a solver or warm start it cannot serve.
PlanResult planPointing(const PlanningProblem& problem, const SolverOptions& options,
                        SolveContext& context);

}  // namespace attitude_planner
