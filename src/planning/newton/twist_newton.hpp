// Newton on one grid for a pointing end condition: the unknowns are the free attitudes' δ and the
// twist ψ about the boresight (transcription/reduced_problem.hpp, evaluateWithTwist), the Newton
// matrix the band bordered by ψ's column (linalg/bordered_band.hpp), O(N) per iteration.
// Globalized by the least shift λ that makes the bordered matrix definite and an Armijo
// backtracking on the cost; stops on the relative Newton decrement as grid_solve.cpp does.
#pragma once

#include <functional>
#include <string>

#include "attitude_planner/planning/newton_parameters.hpp"
#include "attitude_planner/planning/result.hpp"
#include "planning/problem/solve_context.hpp"
#include "planning/transcription/reduced_problem.hpp"

namespace attitude_planner {

/// How one twist Newton solve ended.
struct TwistSolve {
  Termination termination = Termination::NotConverged;
  std::string reason = "iteration limit reached";
  int iterations = 0;
  double twist = 0.0;               ///< ψ [rad] at the end
  double cost = 0.0;                ///< C at the end
  double twist_gradient = 0.0;      ///< ∂C/∂ψ at the end [N²·m²/rad]
  double relative_gradient = 0.0;   ///< max|∇C| (δ and ψ) / (|∂τ/∂δ|·max|τ|) at the end
  double relative_decrement = 0.0;  ///< √(−gᵀΔ)/|τ|₂ of the last step
  /// The raises of λ from 0 its last indefinite iteration without a carried shift needed (0:
  /// none): a guess for the next start's (solveTwistNewton's `raise_guess`).
  int fresh_raises = 0;
};

/// Asked before each unshifted Newton step with where the quadratic model puts the full step (its
/// cost C + ½∇Cᵀ Δ and ψ + Δψ) and the step's relative decrement: a non-empty reason ends the solve
/// there, not converged, with that reason.
using TwistWatch =
    std::function<std::string(double model_cost, double model_twist, double relative_decrement)>;

/// Newton on (δ, ψ) from `np`'s iterate and `twist` (np built for R_N = pointingAttitude(twist));
/// `np` ends at the last accepted iterate. Iterations are reported through `context`; a cancel or
/// the deadline ends the solve with that termination, and so does `watch` (where given).
/// `raise_guess`: where the least definite shift from λ = 0 is searched first (an earlier
/// start's TwistSolve::fresh_raises); it changes the factorizations tried, not the iterates.
TwistSolve solveTwistNewton(ReducedProblem& np, double twist, SolveContext& context,
                            double tolerance, int max_iterations, const NewtonParameters& p,
                            std::vector<IterationInfo>* history, const TwistWatch* watch = nullptr,
                            int raise_guess = 1);

}  // namespace attitude_planner
