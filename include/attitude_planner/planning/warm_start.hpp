// Warm starts: a previous plan (or its remainder from a state on it) given as the initial guess of
// a solve (SolverOptions::warm_start; request field `initial_guess`, CLI --warm-start). A guess is
// only a start: it need not match the problem's boundary data, duration or N (it is resampled to
// the problem's grid), and the answer is the extremal next to it (the solvers skip their other
// starts: a warm-started re-plan stays in the guess's homotopy class). Malformed guesses are
// refused by validateInitialGuess, naming the field and the value.
#pragma once

#include <string>

#include "attitude_planner/dynamics/maneuver.hpp"
#include "attitude_planner/planning/problem.hpp"

namespace attitude_planner {

/// How far a guess attitude may be from a rotation (so3::orthogonalityError) before it is refused:
/// the rule the problem's own attitudes follow (validateProblem).
constexpr double kGuessOrthogonalityTolerance = 1e-9;

/// Throws InvalidInput naming `field` (e.g. "initial_guess", "--warm-start") and the offending
/// row and value unless `guess` is a usable start: at least 2 rows (N ≥ 1); every attitude
/// finite and a rotation within kGuessOrthogonalityTolerance; the other columns (time,
/// angular_velocity, torque), which may be empty or of another length (only the attitudes start
/// the solve; NLopt takes the torques too when they have a row per node), finite. A guess that
/// does not match the problem's boundary data is not refused: it is only a start.
void validateInitialGuess(const Maneuver& guess, const std::string& field);

/// The guess on the problem's grid (N + 1 rows, t_k = k T/N): a guess with the problem's N as it
/// is (its time column set to the problem's grid); another N resampled over its own span,
/// its k-th row taken at the fraction k/N of it (resampleAttitudes: the C¹ curve through the
/// guess's nodes along its own steps), the other columns left empty (the solvers use the
/// attitudes; NLopt its torques only at the same N).
Maneuver initialGuessOnGrid(const Maneuver& guess, const PlanningProblem& problem);

/// Re-planning from a state on a plan being flown: the problem from row k of `plan` (R_k, Ω_k:
/// the attitude and the velocity column there) to the same end, over T − t_k with N − k steps
/// (everything else as `problem`, the plan's N and T). For paper and variational, whose step k
/// velocity and R_{k+1} are what the plan already fixed, the plan's remainder (remainderOfPlan)
/// is an extremal of it (Bellman), with the remaining cost Σ_{j>k} ½|τ_j|². Throws
/// InvalidInput unless 0 ≤ k ≤ N − kMinSteps and the plan has the problem's N.
PlanningProblem remainderProblem(const PlanningProblem& problem, const Maneuver& plan, int k);

/// Rows k..N of `plan`, times shifted to start at 0, τ at the new first row 0 (as every plan's
/// first row of a scheme without end torques): the initial guess of remainderProblem.
Maneuver remainderOfPlan(const Maneuver& plan, int k);

}  // namespace attitude_planner
