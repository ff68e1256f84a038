// Newton's method on the first-order optimality conditions of the discrete problem (seed 000,
// Problem 3.2), O(N) time and memory per iteration.
//
// The problem is reduced_problem.hpp's unconstrained minimization over the interior attitudes;
// with right perturbations R_j exp(δ_j^) its gradient is Σ_k J_kᵀ τ_k and its exact Hessian is
// JᵀJ + sym(Σ_k Σ_i τ_{k,i} ∂J_{k,i}/∂δ), block-pentadiagonal: a banded Cholesky costs O(N).
//
// Globalization: the cost itself is the merit function. If the Hessian is not positive definite a
// multiple of the identity is added (Levenberg); an Armijo backtracking line search along the
// retraction R_j exp(α δ_j^) follows. Convergence: the Newton decrement relative to |τ|₂ is below
// the tolerance; the step it came with is then taken, leaving the torques exact to ~round-off.
#include <chrono>
#include <cmath>
#include <sstream>

#include <optional>

#include "attitude_planner/errors.hpp"
#include "attitude_planner/reduced_problem.hpp"
#include "attitude_planner/solvers.hpp"

namespace attitude_planner {

PlanResult solveWithNewton(const PlanningProblem& problem, const SolverOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  const auto elapsed = [&] {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  };
  PlanResult result;
  std::optional<ReducedProblem> reduced;
  try {
    reduced.emplace(problem);
  } catch (const StepTooLarge& e) {
    result.message = std::string("boundary velocity: ") + e.what();
    return result;
  }
  ReducedProblem& np = *reduced;
  if (options.warm_start) np.setInterior(options.warm_start->attitude);
  const int N = np.steps();
  const int n = 3 * (N - 3);
  BandedSymmetricMatrix hessian(n, 8);
  Eigen::VectorXd gradient(n), delta(n);
  double gradient_scale = 0.0;
  double relative_gradient = 0.0;
  double relative_decrement = 0.0;
  bool converged = false;
  std::string reason = "iteration limit reached";
  int iteration = 0;
  for (;; ++iteration) {
    const double cost = np.evaluate(&gradient, &hessian, &gradient_scale);
    relative_gradient = gradient.size() ? gradient.cwiseAbs().maxCoeff() / gradient_scale : 0.0;
    if (!std::isfinite(cost) || !std::isfinite(relative_gradient)) {
      reason = "non-finite cost or gradient (step too large for this h? increase steps)";
      break;
    }
    if (gradient.cwiseAbs().maxCoeff() == 0.0) {  // e.g. the zero maneuver
      converged = true;
      relative_decrement = 0.0;
      reason = "converged";
      break;
    }
    if (iteration >= options.max_iterations) break;
    if (options.time_budget_s > 0 && elapsed() > options.time_budget_s) {
      reason = "time budget exceeded";
      break;
    }
    // Newton direction; Levenberg shift until the Hessian is positive definite.
    double shift = 0.0;
    bool factored = false;
    for (int attempt = 0; attempt < 40; ++attempt) {
      BandedSymmetricMatrix trial = hessian;
      if (shift > 0) trial.addToDiagonal(shift);
      delta = -gradient;
      if (trial.solvePositiveDefinite(&delta)) {
        factored = true;
        break;
      }
      shift = shift == 0.0 ? 1e-10 * hessian.maxAbsDiagonal() : 10.0 * shift;
    }
    if (!factored) {
      reason = "Hessian could not be made positive definite";
      break;
    }
    // Newton decrement λ = √(gᵀH⁻¹g): λ ≈ the ℓ2 error of the torques, so λ/|τ|₂ with
    // |τ|₂ = √(2C) is the relative torque accuracy — scale-free, unlike the raw gradient, whose
    // conditioning grows like N⁴.
    const double slope = gradient.dot(delta);
    relative_decrement = std::sqrt(std::max(0.0, -slope)) / std::sqrt(std::max(2.0 * cost, 1e-300));
    const bool final_step = shift == 0.0 && relative_decrement <= options.tolerance;
    // Armijo backtracking on the cost along the retraction. Once the predicted decrease is below
    // the cost's round-off the test is meaningless and the full Newton step is taken.
    double alpha = 1.0;
    bool accepted = final_step || -slope <= 1e-13 * cost;
    std::vector<Matrix3> trial_R = np.retract(delta, alpha);
    for (int back = 0; !accepted && back < 50; ++back) {
      const double trial_cost = np.cost(trial_R);
      if (std::isfinite(trial_cost) && trial_cost <= cost + 1e-4 * alpha * slope) {
        accepted = true;
        break;
      }
      alpha *= 0.5;
      trial_R = np.retract(delta, alpha);
    }
    if (!accepted) {
      reason = "line search failed";
      break;
    }
    np.setInterior(trial_R);
    IterationInfo info{iteration + 1, cost, relative_decrement, alpha};
    result.history.push_back(info);
    if (final_step) {
      // This last step took the iterate from the tolerance to ~round-off (quadratic convergence).
      converged = true;
      reason = "converged";
      ++iteration;
      break;
    }
    if (options.on_iteration && !options.on_iteration(info)) {
      reason = "cancelled";
      ++iteration;
      break;
    }
  }
  // Report the first-order residual at the final iterate, not at the one before the last step.
  if (converged && iteration > 0) {
    np.evaluate(&gradient, nullptr, &gradient_scale);
    relative_gradient = gradient.size() ? gradient.cwiseAbs().maxCoeff() / gradient_scale : 0.0;
  }
  result.iterations = iteration;
  result.max_residual = relative_gradient;
  result.newton_decrement = relative_decrement;
  try {
    evaluatePlan(problem, np.torques(np.attitudes()), &result);
  } catch (const StepTooLarge& e) {
    result.converged = false;
    result.message = std::string("replay of the planned torques failed: ") + e.what();
    return result;
  }
  // The replay is the final judge: stationarity of the reduced problem means nothing if the
  // torques, integrated forward, do not land on the target (e.g. an implicit step that jumped to
  // another branch of μ(F) = p when h|Ω| is large).
  const double miss = std::max(result.terminal_attitude_error, result.terminal_velocity_error);
  const double allowed_miss = 1e-9 * std::max(1.0, N * 1e-4);
  if (converged && !(miss <= allowed_miss)) {
    converged = false;
    std::ostringstream why;
    why << "stationary point found, but replaying its torques misses the target by " << miss
        << " (step too large for this h? increase steps)";
    reason = why.str();
  }
  result.converged = converged;
  std::ostringstream msg;
  msg << reason << " after " << iteration << " iterations (relative gradient " << relative_gradient
      << ", relative Newton decrement " << relative_decrement << ")";
  result.message = msg.str();
  return result;
}

}  // namespace attitude_planner
