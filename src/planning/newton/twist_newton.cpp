#include "planning/newton/twist_newton.hpp"

#include <cmath>

#include "planning/linalg/bordered_band.hpp"
#include "planning/newton/least_raise.hpp"
#include "planning/newton/step_control.hpp"

namespace attitude_planner {

namespace {

/// Halvings of the step always tried before the round-off stop of acceptStep.
constexpr int kHalvingsBeforeRoundOffStop = 8;

/// The loop's state at one iterate: C, ∇C over (δ, ψ), and the bordered Hessian.
struct TwistModel {
  explicit TwistModel(const ReducedProblem& np)
      : band(np.unknowns(), ReducedProblem::kHalfBandwidth) {}
  double cost = 0.0, corner = 0.0, gradient_scale = 0.0;
  Eigen::VectorXd gradient, border;
  BandedSymmetricMatrix band;
};

/// The Newton step of (H + λ s I) Δ = −g into `step` (s: the larger of H's diagonal scales);
/// false unless the shifted bordered matrix is positive definite (band definite, Schur
/// complement positive) and Δ descends.
bool shiftedStep(const TwistModel& m, double shift, Eigen::VectorXd* step) {
  const double scale = std::max(m.band.maxAbsDiagonal(), std::abs(m.corner));
  BandedSymmetricMatrix A = m.band;
  if (shift > 0.0) A.addToDiagonal(shift * scale);
  Eigen::MatrixXd D(1, 1);
  D(0, 0) = m.corner + shift * scale;
  BorderedBanded factor;
  if (!factor.factor(A, Eigen::MatrixXd(m.border), D) || factor.inertia().negative > 0) {
    return false;
  }
  *step = -m.gradient;
  factor.solve(step);
  return step->allFinite() && m.gradient.dot(*step) < 0.0;
}

/// The least definite shift among `from` raised 0, 1, …, `most_raises` times, its step in `step`.
struct DefiniteShift {
  bool found = false;
  double shift = 0.0;
  int raises = 0;  ///< how many raises of `from` it took (the attempts a one-by-one scan spends)
};

/// The shift a one-by-one scan (shiftedStep at `from`, raised until it succeeds) stops at, found
/// by leastSucceedingRaise from `guess`: in exact arithmetic both end at the same raise, so the
/// same iterates follow (measured: 132 seeded requests' iterations, costs and twists bit for bit
/// the same), with fewer factorizations where a start's Hessian is indefinite.
DefiniteShift leastDefiniteShift(const TwistModel& m, double from, int most_raises, int guess,
                                 const NewtonParameters& p, Eigen::VectorXd* step) {
  Eigen::VectorXd trial;
  int last_success = -1;  // the raise whose step `step` holds
  const int raises = leastSucceedingRaise(
      most_raises,
      [&](int r) {
        if (!shiftedStep(m, raisedShift(from, r, p), &trial)) return false;
        *step = trial;
        last_success = r;
        return true;
      },
      guess);
  if (raises < 0) return {};
  if (last_success != raises) shiftedStep(m, raisedShift(from, raises, p), step);
  return {true, raisedShift(from, raises, p), raises};
}

/// A trial along Δ accepted by Armijo's test at the largest α = 1, ½, ¼, … (p.max_halvings);
/// the step taken unjudged when `unjudged` (a final step, or a decrease below round-off).
/// Returns the α taken, 0 if none.
double acceptStep(ReducedProblem& np, const TwistModel& m, const Eigen::VectorXd& step,
                  bool unjudged, const NewtonParameters& p, double* twist) {
  const int n = np.unknowns();
  const double slope = m.gradient.dot(step);
  double alpha = 1.0;
  for (int halving = 0; halving <= p.max_halvings; ++halving, alpha *= p.backtrack_factor) {
    const ReducedProblem::StepVectors trial = np.retractWithTwist(step.head(n), step(n), alpha);
    const double trial_cost = np.cost(trial);
    if (unjudged ||
        (std::isfinite(trial_cost) && trial_cost <= m.cost + p.armijo * alpha * slope)) {
      np.setCurrentWithTwist(trial, alpha * step(n));
      *twist += alpha * step(n);
      return alpha;
    }
    // A step whose predicted decrease is below the cost's round-off cannot pass Armijo's test:
    // stop halving (the caller raises the shift) after a few tries.
    if (halving >= kHalvingsBeforeRoundOffStop &&
        alpha * std::abs(slope) < p.negligible_decrease * m.cost) {
      break;
    }
  }
  return 0.0;
}

/// Evaluates the model at np's iterate; false (with `out` saying why) if the solve ends there.
bool evaluateModel(const ReducedProblem& np, TwistModel* m, TwistSolve* out) {
  m->cost =
      np.evaluateWithTwist(&m->gradient, &m->band, &m->border, &m->corner, &m->gradient_scale);
  out->cost = m->cost;
  out->twist_gradient = m->gradient(np.unknowns());
  out->relative_gradient = m->gradient.cwiseAbs().maxCoeff() / m->gradient_scale;
  if (!std::isfinite(m->cost) || !std::isfinite(out->relative_gradient)) {
    out->termination = Termination::StepTooLarge;
    out->reason = "non-finite cost or gradient (step too large for this h? increase steps)";
    return false;
  }
  if (m->gradient.cwiseAbs().maxCoeff() == 0.0) {
    out->termination = Termination::Converged;
    out->reason = "converged";
    return false;
  }
  return true;
}

}  // namespace

TwistSolve solveTwistNewton(ReducedProblem& np, double twist, SolveContext& context,
                            double tolerance, int max_iterations, const NewtonParameters& p,
                            std::vector<IterationInfo>* history, const TwistWatch* watch,
                            int raise_guess) {
  TwistSolve out;
  TwistModel m(np);
  Eigen::VectorXd step;
  const double floor = p.roundOffFloor(np.steps()), acceptance = p.roundOffAcceptance(np.steps());
  double shift = 0.0, best_decrement = INFINITY;
  double previous_full_step = 0.0;  ///< the last iteration's decrement if it was a full Newton step
  int stalled = 0;
  std::string watched;  ///< why `watch` ended the solve (empty: it did not)
  while (evaluateModel(np, &m, &out) && out.iterations < max_iterations) {
    if (const auto stop = context.stopReason()) {
      out.termination = *stop;
      out.reason = *stop == Termination::Cancelled ? "cancelled" : "time budget exceeded";
      break;
    }
    double alpha = 0.0;
    bool final_step = false;
    for (int attempt = 0; attempt < p.max_step_attempts && alpha == 0.0; ++attempt) {
      // From λ = 0 the least definite shift is searched from the last one found from 0 (the
      // Hessian's scale changes little between iterations and starts); from a carried λ, at it.
      const bool fresh = shift == 0.0;
      const DefiniteShift definite = leastDefiniteShift(m, shift, p.max_step_attempts - 1 - attempt,
                                                        fresh ? raise_guess : 1, p, &step);
      if (!definite.found) break;
      if (fresh && definite.raises > 0) raise_guess = out.fresh_raises = definite.raises;
      shift = definite.shift;
      attempt += definite.raises;  // as many attempts as the raises one at a time would take
      const double slope = m.gradient.dot(step);
      out.relative_decrement = std::sqrt(-slope) / std::sqrt(std::max(2.0 * m.cost, p.cost_floor));
      // As grid_solve.cpp's StoppingTest: the last full step took d₋ to d, so this one leaves
      // about d³/d₋² (quadratic convergence): well inside the tolerance, this step is the last.
      const double d = out.relative_decrement;
      if (watch && shift == 0.0) {
        watched = (*watch)(m.cost + 0.5 * slope, twist + step(np.unknowns()), d);
      }
      if (!watched.empty()) break;
      const bool predicted = previous_full_step > 0.0 && d < previous_full_step &&
                             d * d * d / (previous_full_step * previous_full_step) <=
                                 p.final_step_prediction_margin * tolerance;
      final_step = shift == 0.0 && (d <= std::max(tolerance, floor) || predicted);
      const bool unjudged = final_step || -slope <= p.negligible_decrease * m.cost ||
                            out.relative_decrement <= acceptance;
      alpha = acceptStep(np, m, step, unjudged, p, &twist);
      if (alpha == 0.0) shift = shift == 0.0 ? p.first_rejection_shift : 10.0 * shift;
    }
    if (!watched.empty() || alpha == 0.0) {
      out.reason = watched.empty() ? "no step decreased the cost" : watched;
      break;
    }
    ++out.iterations;
    previous_full_step = shift == 0.0 && alpha == 1.0 ? out.relative_decrement : 0.0;
    shift = shift * p.shift_min_factor < p.negligible_shift ? 0.0 : shift * p.shift_min_factor;
    IterationInfo info{context.iterations() + 1, m.cost, out.relative_decrement, alpha};
    info.steps = np.steps();
    info.effort = m.cost * np.scheme().timeStep();
    if (history) history->push_back(info);
    const bool go_on = context.reportIteration(info);
    stalled = out.relative_decrement <= acceptance &&
                      out.relative_decrement > p.stall_decrement_ratio * best_decrement
                  ? stalled + 1
                  : 0;
    best_decrement = std::min(best_decrement, out.relative_decrement);
    if (final_step || stalled >= p.stall_iterations) {
      out.termination = Termination::Converged;
      out.reason = final_step ? "converged" : "converged to the round-off floor";
      evaluateModel(np, &m, &out);  // the figures at the final iterate
      out.termination = Termination::Converged;
      break;
    }
    if (!go_on) {
      out.termination = Termination::Cancelled;
      out.reason = "cancelled";
      break;
    }
  }
  out.twist = twist;
  return out;
}

}  // namespace attitude_planner
