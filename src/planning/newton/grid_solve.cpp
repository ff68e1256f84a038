// Newton's method on the first-order optimality conditions of the discrete problem (seed 000,
// Problem 3.2), O(N) time and memory per iteration.
//
// The problem is reduced_problem.hpp's unconstrained minimization over the interior attitudes;
// with right perturbations R_j exp(δ_j^) its gradient is Σ_k J_kᵀ τ_k and its exact Hessian is
// JᵀJ + sym(Σ_k Σ_i τ_{k,i} ∂J_{k,i}/∂δ), block-pentadiagonal: a banded Cholesky costs O(N).
// The step solves (H + λI)δ = −g along the retraction R_j exp(δ_j^); the step control
// (step_control.hpp) chooses λ. Convergence: the Newton decrement relative to |τ|₂ is below the
// tolerance; the step it came with is then taken, leaving the torques exact to ~round-off.
#include "planning/newton/grid_solve.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory>
#include <optional>
#include <sstream>

#include <Eigen/Eigenvalues>

#include "attitude_planner/errors.hpp"
#include "planning/newton/least_raise.hpp"
#include "planning/problem/message_notes.hpp"
#include "planning/problem/verdict.hpp"
#include "planning/strategies/starts.hpp"

namespace attitude_planner {

namespace {

/// The scale the augmented system's relative shift multiplies: (2|J|/h²)², the largest
/// curvature of |τ|² in one attitude.
double augmentedShiftScale(const ReducedProblem& np) {
  const double h = np.scheme().timeStep();
  return std::pow(2.0 * np.scheme().inertia().norm() / (h * h), 2);
}

/// The augmented system's block positions: the torques k = first − 1 .. last + 1, each followed
/// by δ_k if R_k is free.
struct AugmentedLayout {
  /// Half bandwidth in scalar rows: a stencil's S couples δ_{k−1} with δ_{k+1}, four blocks
  /// apart in the order y, δ alternating; with 3 × 3 blocks that is 3·4 + 2 = 14 rows.
  static constexpr int kHalfBandwidth = 14;
  int first, last;
  int y(int k) const { return k < first ? 0 : 2 * (k - first) + 1; }
  int d(int j) const { return 2 * (j - first) + 2; }
  int size() const { return 3 * (y(last + 1) + 1); }
};

/// α ≈ σ_min(J) keeps cond(K) ≈ cond(J) (Björck; α ≈ σ_max would give cond(J)², no better than
/// the normal equations). The smoothest attitude mode δ(t) = sin(πt/T) v has
/// |δτ| ≈ J_min (π/T)² |δ|, which estimates σ_min.
double augmentedAlpha(const ReducedProblem& np) {
  const double T = np.scheme().timeStep() * np.steps();
  const double smallest_moment =
      Eigen::SelfAdjointEigenSolver<Matrix3>(np.scheme().inertia()).eigenvalues()(0);
  return smallest_moment * (M_PI / T) * (M_PI / T);
}

/// One stencil's entries of the augmented matrix (see solveAugmented).
void addStencil(const ReducedProblem& np, const AugmentedLayout& at, double alpha,
                const ReducedProblem::Stencil& st, BandedLinearSystem* K, Eigen::VectorXd* rhs) {
  const int ry = 3 * at.y(st.k);
  for (int i = 0; i < 3; ++i) {
    K->add(ry + i, ry + i, -alpha);
    (*rhs)(ry + i) = -st.tau(i);
  }
  for (int s = 0; s < 3; ++s) {
    const int j = st.k - 1 + s;
    if (np.variableIndex(j) < 0) continue;
    const int rd = 3 * at.d(j);
    for (int i = 0; i < 3; ++i) {
      for (int c = 0; c < 3; ++c) {
        K->add(ry + i, rd + c, st.jacobian(i, 3 * s + c));
        K->add(rd + c, ry + i, st.jacobian(i, 3 * s + c));
      }
    }
    for (int t = 0; t < 3; ++t) {
      const int jt = st.k - 1 + t;
      if (np.variableIndex(jt) < 0) continue;
      const int rt = 3 * at.d(jt);
      for (int i = 0; i < 3; ++i) {
        for (int c = 0; c < 3; ++c) K->add(rd + i, rt + c, st.second(3 * s + i, 3 * t + c) / alpha);
      }
    }
  }
}

/// Solves the Newton system (JᵀJ + S + shift I) δ = −Jᵀτ through its augmented form
///   [ −α I   J        ] [ z ]   [ −τ ]
///   [  Jᵀ   (S+shift)/α ] [ δ ] = [  0 ],   y = J δ + τ = α z,
/// ordered by node, y_k before δ_k (y_1, y_2, δ_2, y_3, δ_3, …, y_{N−1}; with end torques
/// y_0, y_1, δ_1, …, δ_{N−1}, y_N) so it is banded, and solved by LU with partial pivoting.
/// `delta` holds −g on entry and δ on return. `workspace` is allocated once per solve: at
/// N = 10⁶ it is 2 GB, and fresh pages cost more system time than the factorization.
bool solveAugmented(const ReducedProblem& np, double relative_shift, int bandwidth,
                    const Interruption& interruption, Eigen::VectorXd* delta,
                    std::unique_ptr<BandedLinearSystem>* workspace) {
  // Allocated and zeroed with polls (~200 MB at N = 1e5): a stop is not held up by it.
  const AugmentedLayout at{np.firstFreeNode(), np.lastFreeNode()};
  const int n = at.size();
  if (*workspace) {
    (*workspace)->setZero(&interruption);
  } else {
    workspace->reset(new BandedLinearSystem(n, bandwidth, &interruption));
  }
  BandedLinearSystem& K = **workspace;
  Eigen::VectorXd rhs = Eigen::VectorXd::Zero(n);
  const double alpha = augmentedAlpha(np);
  const double shift = relative_shift * augmentedShiftScale(np);
  np.forEachStencil(true, [&](const ReducedProblem::Stencil& st) {
    if (st.k % kColumnsBetweenPolls == 0) interruption.poll();
    addStencil(np, at, alpha, st, &K, &rhs);
  });
  if (shift > 0) {
    for (int j = at.first; j <= at.last; ++j) {
      for (int i = 0; i < 3; ++i) K.add(3 * at.d(j) + i, 3 * at.d(j) + i, shift / alpha);
    }
  }
  if (!K.solve(&rhs, &interruption)) return false;
  for (int j = at.first; j <= at.last; ++j)
    delta->segment<3>(np.variableIndex(j)) = rhs.segment<3>(3 * at.d(j));
  return delta->allFinite();
}

/// The stopping test's reading of one trial step.
struct StepAssessment {
  double relative_decrement = 0.0;  ///< √(−gᵀδ)/|τ|₂: ≈ the relative ℓ2 torque error
  double predicted_decrement = std::numeric_limits<double>::infinity();  ///< after this step
  bool predicted_within_tolerance = false;
  bool final_step = false;     ///< the last step: take it and stop
  bool take_unjudged = false;  ///< take it without the step control's judgement
};

/// When to stop: the Newton decrement relative to |τ|₂ — scale-free, unlike the raw gradient,
/// whose conditioning grows like N⁴ — below the tolerance, predicted below it after a step from
/// the quadratic convergence observed, or stalled at the round-off floor (~eps·N²).
class StoppingTest {
 public:
  StoppingTest(const NewtonParameters& p, double tolerance, int steps)
      : p_(p),
        tolerance_(tolerance),
        floor_(p.roundOffFloor(steps)),
        acceptance_(p.roundOffAcceptance(steps)) {}

  StepAssessment assess(double slope, double cost, double shift) const {
    StepAssessment a;
    a.relative_decrement =
        std::sqrt(std::max(0.0, -slope)) / std::sqrt(std::max(2.0 * cost, p_.cost_floor));
    // The last full step took the decrement from d₋ to d, so this one will leave about C d²,
    // C = d/d₋²: well inside the tolerance, this step is the last.
    const double d_prev = previous_full_step_decrement_, d = a.relative_decrement;
    if (d_prev > 0.0 && d < d_prev) a.predicted_decrement = d / (d_prev * d_prev) * d * d;
    a.predicted_within_tolerance =
        a.predicted_decrement <= p_.final_step_prediction_margin * tolerance_;
    a.final_step =
        shift == 0.0 && (d <= std::max(tolerance_, floor_) || a.predicted_within_tolerance);
    // Below the cost's round-off the step control's ratio is meaningless: take the step.
    a.take_unjudged = a.final_step || -slope <= p_.negligible_decrease * cost || d <= acceptance_;
    return a;
  }

  /// After an accepted step: true once full steps no longer shrink a small decrement (round-off).
  bool stalledAfter(double decrement, bool full_newton_step) {
    if (decrement <= acceptance_ && decrement > p_.stall_decrement_ratio * best_decrement_) {
      ++stalled_iterations_;
    } else {
      stalled_iterations_ = 0;
    }
    best_decrement_ = std::min(best_decrement_, decrement);
    previous_full_step_decrement_ = full_newton_step ? decrement : 0.0;
    return stalled_iterations_ >= p_.stall_iterations;
  }

  double tolerance() const { return tolerance_; }

 private:
  const NewtonParameters& p_;
  double tolerance_, floor_, acceptance_;
  double previous_full_step_decrement_ = 0.0;  ///< 0 unless the last step was full Newton
  double best_decrement_ = std::numeric_limits<double>::infinity();
  int stalled_iterations_ = 0;
};

/// Why a converged final step stopped (its accuracy, when the tolerance was not reached itself).
std::string finalStepReason(const StepAssessment& a, double tolerance, double round_off_report) {
  if (a.relative_decrement <= tolerance) return "converged";
  std::ostringstream why;
  if (a.predicted_within_tolerance) {
    why << "converged (relative torque accuracy ";
    if (a.predicted_decrement < round_off_report) {
      why << "at round-off";
    } else {
      why << "about " << a.predicted_decrement;
    }
    why << " after the last step, predicted from the quadratic convergence of the steps"
        << " before it; " << a.relative_decrement << " before it)";
  } else {
    why << "converged to the round-off floor (relative torque accuracy about "
        << a.relative_decrement << " before the last step, tolerance " << tolerance
        << " is below the floor ~eps N^2 at this N)";
  }
  return why.str();
}

/// The loop of one grid solve and its state.
class GridSolver {
 public:
  GridSolver(ReducedProblem& np, SolveContext& context, const GridSettings& settings,
             const NewtonParameters& p)
      : np_(np),
        context_(context),
        settings_(settings),
        p_(p),
        augmented_(np.steps() > p.normal_equations_max_steps),
        hessian_(np.unknowns(), ReducedProblem::kHalfBandwidth),
        gradient_(np.unknowns()),
        delta_(np.unknowns()),
        stopping_(p, settings.tolerance, np.steps()),
        control_(makeStepControl(settings.globalization, p)) {}

  /// Iterates until a stop; returns the iterations taken.
  int run(std::vector<IterationInfo>* history) {
    try {
      while (iterate(history)) ++iteration_;
    } catch (const SolveInterrupted& stop) {
      termination_ = stop.termination;
      reason_ = stop.termination == Termination::Cancelled ? "cancelled" : "time budget exceeded";
    }
    return iteration_;
  }

  Termination termination() const { return termination_; }
  const std::string& reason() const { return reason_; }
  double relativeGradient() const { return relative_gradient_; }
  double relativeDecrement() const { return assessment_.relative_decrement; }
  /// The first-order residual at the final iterate (not at the one before the last step).
  void evaluateAtFinalIterate() {
    double scale = 0.0;
    np_.evaluate(&gradient_, nullptr, &scale, &trial_forms_);
    relative_gradient_ = gradient_.size() ? gradient_.cwiseAbs().maxCoeff() / scale : 0.0;
  }

 private:
  /// One iteration; false when the solve ends (termination_ and reason_ say why).
  bool iterate(std::vector<IterationInfo>* history) {
    if (!evaluate()) return false;
    if (iteration_ >= settings_.max_iterations) return false;
    if (const auto stop = context_.stopReason()) throw SolveInterrupted{*stop};
    if (!takeStep()) return false;
    const bool full_newton = control_->shift() == 0.0 && step_length_ == 1.0;
    const bool stalled = stopping_.stalledAfter(assessment_.relative_decrement, full_newton);
    IterationInfo info{iteration_ + 1, cost_, assessment_.relative_decrement, step_length_};
    info.steps = np_.steps();  // the grid level and its h·cost, for the action's feedback
    info.effort = cost_ * np_.scheme().timeStep();
    history->push_back(info);
    const bool go_on = context_.reportIteration(info);
    if (stalled || assessment_.final_step) {
      converge(stalled);
      return false;
    }
    if (!go_on) {
      finishStep(Termination::Cancelled, "cancelled");
      return false;
    }
    return true;
  }

  /// The cost, gradient and (normal equations) Hessian at the iterate; false if the solve ends.
  bool evaluate() {
    double scale = 0.0;
    cost_ = np_.evaluate(&gradient_, augmented_ ? nullptr : &hessian_, &scale, &trial_forms_);
    relative_gradient_ = gradient_.size() ? gradient_.cwiseAbs().maxCoeff() / scale : 0.0;
    if (!std::isfinite(cost_) || !std::isfinite(relative_gradient_)) {
      termination_ = Termination::StepTooLarge;
      reason_ = "non-finite cost or gradient (step too large for this h? increase steps)";
      return false;
    }
    if (gradient_.cwiseAbs().maxCoeff() == 0.0) {  // e.g. the zero maneuver
      termination_ = Termination::Converged;
      assessment_.relative_decrement = 0.0;
      reason_ = "converged";
      return false;
    }
    return true;
  }

  /// The Newton step for the step control's shift into delta_; false if H + λI is not definite.
  bool newtonStep(double shift, double shift_scale) {
    delta_ = -gradient_;
    if (augmented_) {
      return solveAugmented(np_, shift, AugmentedLayout::kHalfBandwidth, context_, &delta_,
                            &workspace_) &&
             gradient_.dot(delta_) < 0;
    }
    if (shift == 0.0) return solveWith(hessian_);  // no copy
    BandedSymmetricMatrix shifted = hessian_;
    shifted.addToDiagonal(shift * shift_scale);
    return solveWith(shifted);
  }

  /// delta_ ← A⁻¹ delta_ by the solver's one Cholesky factor (its storage reused from iteration
  /// to iteration, not allocated per solve); false if A is not positive definite.
  bool solveWith(const BandedSymmetricMatrix& A) {
    if (!cholesky_.factor(A, &context_)) return false;
    cholesky_.solve(&delta_);
    return true;
  }

  /// The least of the step control's raised shifts (raisedShift) at which H + λI is definite,
  /// within `most_raises` raises of the current one, by leastSucceedingRaise: the λ a one-by-one
  /// scan stops at (definiteness is monotone in λ), with about 2 log₂ of the raises in
  /// factorizations (a Hermite start's first iterate on the class survey grid needs 18 to 22
  /// raises from 0; from 0 the search starts at the raises the last search from 0 needed). The
  /// control's shift is raised to it and delta_ holds its step; returns the raises, −1 if none.
  int raisesToDefinite(double shift_scale, int most_raises) {
    const double from = control_->shift();
    const bool fresh = from == 0.0;
    int held = -1;  // the raise whose step delta_ holds
    const int raises = leastSucceedingRaise(
        most_raises,
        [&](int r) {
          const bool definite = newtonStep(raisedShift(from, r, p_), shift_scale);
          held = definite ? r : -1;
          return definite;
        },
        fresh ? fresh_raises_ : 1);
    if (raises < 0) return -1;
    if (held != raises) newtonStep(raisedShift(from, raises, p_), shift_scale);
    if (fresh && raises > 0) fresh_raises_ = raises;
    control_->raiseForIndefinite(raises);
    return raises;
  }

  /// Trial steps until one is accepted (the iterate moves); false if none is.
  bool takeStep() {
    control_->beginIteration();
    const double shift_scale = augmented_ ? augmentedShiftScale(np_) : hessian_.maxAbsDiagonal();
    step_length_ = 1.0;
    bool factored = false;
    ReducedProblem::StepVectors trial;
    for (int attempt = 0; attempt < p_.max_step_attempts; ++attempt) {
      const int raises = raisesToDefinite(shift_scale, p_.max_step_attempts - 1 - attempt);
      factored = raises >= 0;
      if (!factored) break;
      attempt += raises;  // each raise counts as the trial it replaces
      const double slope = gradient_.dot(delta_);
      assessment_ = stopping_.assess(slope, cost_, control_->shift());
      trial = np_.retract(delta_, 1.0);  // steps are taken in full; λ does the damping
      bool accepted = assessment_.take_unjudged;
      if (accepted) {
        control_->acceptUnjudged();
      } else {
        accepted = control_->judge(
            {np_, cost_, slope, delta_, shift_scale, &trial, &step_length_, &trial_forms_});
      }
      if (accepted) {
        np_.setCurrent(trial);
        return true;
      }
    }
    reason_ = factored ? "no step decreased the cost (trust region collapsed)"
                       : "Hessian could not be made positive definite";
    return false;
  }

  void converge(bool stalled) {
    if (stalled) {
      std::ostringstream why;
      why << "converged to the round-off floor (relative torque accuracy about "
          << assessment_.relative_decrement << ", tolerance " << settings_.tolerance << ")";
      finishStep(Termination::Converged, why.str());
    } else {
      finishStep(Termination::Converged,
                 finalStepReason(assessment_, settings_.tolerance, p_.round_off_report));
    }
  }

  /// Ends the solve after the step of this iteration (which counts).
  void finishStep(Termination termination, std::string reason) {
    termination_ = termination;
    reason_ = std::move(reason);
    ++iteration_;
  }

  ReducedProblem& np_;
  SolveContext& context_;
  const GridSettings& settings_;
  const NewtonParameters& p_;
  const bool augmented_;
  BandedSymmetricMatrix hessian_;
  BandedCholesky cholesky_;
  std::unique_ptr<BandedLinearSystem> workspace_;
  Eigen::VectorXd gradient_, delta_;
  /// The judged trials' step forms: the accepted trial is the next iterate, whose evaluation
  /// reads them instead of forming them again.
  ReducedProblem::StepForms trial_forms_;
  StoppingTest stopping_;
  std::unique_ptr<StepControl> control_;
  StepAssessment assessment_;
  double cost_ = 0.0;
  double relative_gradient_ = 0.0;
  double step_length_ = 1.0;
  int iteration_ = 0;
  int fresh_raises_ = 1;  ///< the raises the last definite-shift search from λ = 0 needed
  Termination termination_ = Termination::NotConverged;
  std::string reason_ = "iteration limit reached";
};

/// The level's summary and the result's message from how the solve ended.
PlanResult finished(PlanResult result, int steps, int iterations, Termination termination,
                    const std::string& reason, double relative_gradient, double decrement) {
  result.termination = termination;
  recordVerdict(&result, verdicts::NewtonEnded{reason, iterations, relative_gradient, decrement});
  result.levels.push_back(
      {steps, iterations, termination, relative_gradient, decrement, renderMessage(result)});
  return result;
}

/// The reduced problem at its start, or nothing if a boundary velocity has no step.
std::optional<ReducedProblem> startedProblem(const PlanningProblem& problem, const GridStart& start,
                                             PlanResult* result) {
  std::optional<ReducedProblem> reduced;
  try {
    reduced.emplace(problem);
  } catch (const StepTooLarge& e) {
    *result = finished(*result, problem.steps, 0, Termination::StepTooLarge,
                       std::string("boundary velocity: ") + e.what(), 0.0, 0.0);
    recordVerdict(result, verdicts::NoBoundaryStep{e.what()});
    result->levels.back().reason = renderMessage(*result);
    return std::nullopt;
  }
  result->extremal_summary = extremalOf(startOnHermiteCurve(problem, &*reduced));
  if (start.warm_start) reduced->setInteriorFromAttitudes(start.warm_start->attitude);
  if (start.coarse) reduced->initializeFromCoarser(*start.coarse, start.coarser);
  return reduced;
}

/// A level reached after the solve was stopped (budget, cancel): its iterate is only carried
/// on, without the solver's Newton systems (at N = 1e5 each level's allocation and evaluation
/// was most of a cancelled solve's 1-3 s hand-over). On the requested grid the plan is built in
/// place and judged as any plan, its first-order residual measured from one gradient.
PlanResult carriedWhenStopped(const PlanningProblem& problem, ReducedProblem& np, Termination stop,
                              ReducedProblem::StepVectors* final_steps) {
  PlanResult result;
  const std::string reason = stop == Termination::Cancelled ? "cancelled" : "time budget exceeded";
  if (final_steps) {
    *final_steps = np.current();
    result.max_residual = std::numeric_limits<double>::quiet_NaN();
  } else {
    Eigen::VectorXd gradient(np.unknowns());
    double scale = 0.0;
    np.evaluate(&gradient, nullptr, &scale);
    result.max_residual = gradient.size() ? gradient.cwiseAbs().maxCoeff() / scale : 0.0;
    result.maneuver = np.maneuver(np.current());
    evaluatePlan(problem, result.maneuver.torque, &result, &result.maneuver);
  }
  const double residual = result.max_residual;
  return finished(std::move(result), np.steps(), 0, stop, reason, residual, 0.0);
}

}  // namespace

PlanResult solveOnGrid(const PlanningProblem& problem, SolveContext& context,
                       const GridSettings& settings, const GridStart& start,
                       ReducedProblem::StepVectors* final_steps,
                       const NewtonParameters& parameters) {
  PlanResult result;
  std::optional<ReducedProblem> reduced = startedProblem(problem, start, &result);
  if (!reduced) return result;
  ReducedProblem& np = *reduced;
  if (const auto stop = context.stopReason())
    return carriedWhenStopped(problem, np, *stop, final_steps);
  GridSolver solver(np, context, settings, parameters);
  const int iterations = solver.run(&result.history);
  Termination termination = solver.termination();
  std::string reason = solver.reason();
  result.iterations = iterations;
  result.newton_decrement = solver.relativeDecrement();
  if (final_steps) {
    // A coarse level: its only product is the iterate the next grid starts from.
    *final_steps = np.current();
    result.max_residual = solver.relativeGradient();
  } else {
    if (termination == Termination::Converged && iterations > 0) solver.evaluateAtFinalIterate();
    // Built in place: the plan's N + 1 rows are not copied (at N = 1e5 the copies were most of
    // a stopped solve's hand-over).
    result.maneuver = np.maneuver(np.current());
    result.max_residual = solver.relativeGradient();
    StepResidual residual;
    evaluatePlan(problem, result.maneuver.torque, &result, &result.maneuver, &residual);
    // Judged by what the plan is: the open-loop replay's miss is a sensitivity, not a verdict.
    if (termination == Termination::Converged && settings.deferred_check) {
      *settings.deferred_check = residual;
    } else if (termination == Termination::Converged) {
      const std::string inconsistent = planInconsistency(problem, result, false, &residual);
      if (!inconsistent.empty()) {
        termination = Termination::NotConverged;
        reason = inconsistent;
      }
    }
  }
  return finished(std::move(result), np.steps(), iterations, termination, reason,
                  solver.relativeGradient(), solver.relativeDecrement());
}

bool checkDeferredPlan(const PlanningProblem& problem, const StepResidual& residual,
                       PlanResult* plan, const StepwiseReplay* stepwise) {
  const std::string inconsistent = planInconsistency(problem, *plan, false, &residual, stepwise);
  if (inconsistent.empty()) return true;
  // solveOnGrid's result begins with its Newton end (finished: the verdict, then the level's
  // summary in those words); the continuation's notes come after it.
  auto& ended = std::get<verdicts::NewtonEnded>(std::get<Verdict>(plan->clauses.front()));
  ended.how = inconsistent;
  plan->verdict = ended;
  plan->termination = Termination::NotConverged;
  LevelSummary& level = plan->levels.back();
  level.termination = Termination::NotConverged;
  level.reason = renderClauses({plan->clauses.front()});
  return false;
}

}  // namespace attitude_planner
