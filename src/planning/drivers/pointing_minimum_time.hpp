// Minimum time to a pointing end condition (R_N b = d, the twist ψ about b free): the request's
// minimum-time recipe (drivers/minimum_time.cpp) run from several start twists, ψ a global
// unknown of every free-time solve (interior_point/kkt_system.hpp: KktSink), the least T* kept.
#pragma once

#include <functional>

#include "attitude_planner/planning/problem.hpp"
#include "attitude_planner/planning/result.hpp"
#include "planning/problem/solve_context.hpp"

namespace attitude_planner {

/// The minimum-time recipe for one posed problem (its R_N at a start twist, the end condition
/// still a pointing one: the twist stays free in its solves).
using MinimumTimeRecipe = std::function<PlanResult(const PlanningProblem& posed)>;

/// Plans `problem` (end_condition.pointing(), objective minimum time) from kPointingStartTwists
/// start twists, ψ₀ + 2πi/kPointingStartTwists (ψ₀ the twist of least rotation from R_0:
/// nearestTwist), on a survey grid of N/4 steps (at least 16; none where that is not below N): at
/// each start twist, where the eigenaxis slew is a start (rest to rest, it and R_N clear of the
/// cones), the fixed-twist free-time solve from that slew, one free-time solve with ψ free from its
/// plan (the fixed-twist plan kept where that ends above it) and one from the slew itself, else
/// `recipe` there; the survey's least T* carried to N through factor-2 levels (one free-time solve
/// with ψ free per level from the coarser plan prolonged), else `recipe` on N at its twist; where
/// that does not converge either (or without a survey), `recipe` at every start twist on N; then
/// the least T* on N against another branch of the fixed-twist T*(ψ) beside its twist (fixed-twist
/// free-time solves from the eigenaxis slew at ψ* ± 0.01 rad, and where one ends below it one
/// ψ-free solve from its plan begun near that KKT point; up to 4 rounds). A
/// start twist whose R_N a cone excludes is not posed. The ways round are the recipe's own starts.
/// The kept answer is the converged one on N with the least T* (else the last start's on N), with
/// every start's trail (each attempt's start_detail.twist its start twist) and the pointing summary
/// (final_twist, the end condition's residual, ∂L/∂ψ at the KKT point). Stops at a cancel or the
/// deadline.
PlanResult pointingMinimumTime(const PlanningProblem& problem, SolveContext& context,
                               const MinimumTimeRecipe& recipe);

}  // namespace attitude_planner
