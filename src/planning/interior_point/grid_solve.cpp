// The interior point on one grid on the PrimalDualLoop (primal_dual_loop.hpp) with the decrement
// test (the loop calls it), its hooks named pieces: the step (assembly, inertia correction, the
// barrier rule's predictor), the step's acceptance, a rejection (the Levenberg–Marquardt retry),
// the end of a barrier problem at μ_final (converged, penalty raise or infeasible) and the
// barrier rule's update.
#include "planning/interior_point/grid_solve.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <sstream>

#include "attitude_planner/errors.hpp"
#include "attitude_planner/planning/pointing.hpp"
#include "planning/interior_point/barrier_problem_solve.hpp"
#include "planning/interior_point/inertia_correction.hpp"
#include "planning/interior_point/kkt_system.hpp"
#include "planning/interior_point/line_search.hpp"
#include "planning/interior_point/primal_dual_loop.hpp"
#include "planning/interior_point/stopping_tests.hpp"
#include "planning/linalg/banded_matrix.hpp"
#include "planning/linalg/double_double.hpp"
#include "planning/problem/message_notes.hpp"
#include "planning/problem/verdict.hpp"
#include "planning/transcription/stage_constraints.hpp"

namespace attitude_planner {

namespace {

std::string describeManeuverSpan(const PlanningProblem& problem) {
  std::ostringstream s;
  s << "cannot turn this body by "
    << so3::angleBetween(problem.initial_attitude, problem.final_attitude)
    << " rad in T = " << problem.duration << " s";
  return s.str();
}

/// The fixed-h profile of the barrier problem: objective C, every row in the formulation's form
/// (free slacks or ℓ1-elastic), the rows' g gᵀ/D as rank-one terms in the band's precision, the
/// trial point the node unknowns' retraction, the merit's penalty ν or ρ, the decrement test.
template <typename Scalar>
class GridSolve final : public BarrierProblemSolve<FixedTimeStep, Scalar> {
  using Base = BarrierProblemSolve<FixedTimeStep, Scalar>;
  using Base::np_, Base::p_, Base::block_, Base::kkt_blocks_, Base::rhs_, Base::d_, Base::scales_,
      Base::mu_, Base::rho_, Base::iteration_, Base::termination_, Base::reason_, Base::end,
      Base::dualStep;

 public:
  GridSolve(const PlanningProblem& problem, const SolverOptions& options,
            const InteriorPointParameters& parameters, SolveContext& context,
            const GridRequest& request, ReducedProblem* np, ConstrainedSystem* system)
      : Base(*np, parameters, system->block(), &context,
             {"iteration limit reached", "time budget exceeded"}),
        problem_(problem),
        options_(options),
        context_(context),
        request_(request),
        system_(*system),
        free_slacks_(system->freeSlacks()),
        test_(parameters, options.tolerance, np->steps(), request.barrier == BarrierRule::Mehrotra,
              free_slacks_) {
    system_.setInterruption(&context);
  }

  GridOutcome run() {
    initialize();
    this->solve(
        {test_, makeBarrierUpdate(request_.barrier, p_), std::make_unique<RowRelativeShift>(p_)},
        {fixedStepLineSearch(p_), true, true}, context_, options_.max_iterations);
    system_.setInterruption(nullptr);
    return finish();
  }

 private:
  /// Scales, barriers, penalty and the first multipliers (from the coarse level's if given).
  void initialize() {
    // f_scale: the cost of the start (the unconstrained optimum), floored by the cost of a
    // torque J·θ/T² at every node so a free coast still has a scale.
    double start_cost = 0.0;
    system_.merit(np_.current(), 1.0, 1.0, &start_cost);
    const int N = np_.steps();
    const double angle = std::max(
        so3::angleBetween(problem_.initial_attitude, problem_.final_attitude), p_.angle_floor);
    const double floor_torque =
        problem_.inertia.norm() * angle / (problem_.duration * problem_.duration);
    scales_.f_scale =
        std::max(start_cost, p_.cost_scale_floor * 0.5 * N * floor_torque * floor_torque);
    scales_.constraints = std::max(system_.constraintCount(), 1);
    scales_.steps = N;
    const double f = scales_.f_scale;
    const int m = scales_.constraints;
    rho_ = p_.fixed_step.initial_penalty * scales_.f_scale;
    // From a coarse solution the active set is nearly right: a barrier that starts small keeps
    // the iterate near it.
    mu_start_ = (request_.coarse_steps ? p_.warm_barrier : p_.fixed_step.initial_barrier) * f / m;
    mu_ = mu_start_;
    // The final barrier grows with N above final_barrier_round_off_steps: a torque constraint's
    // value 1 ∓ τ_a/a carries round-off ~ε|Π|/(h a), which grows like N, and final slacks below
    // it would make the multipliers noise.
    scales_.mu_final =
        std::min(mu_, p_.final_barrier_fraction * options_.tolerance * f / m *
                          std::max(1.0, static_cast<double>(N) / p_.final_barrier_round_off_steps));
    system_.evaluateValues(np_.current(), nullptr);
    block_.initialize(mu_, rho_, p_.initial_multiplier_cap * f / m);
    if (request_.barrier == BarrierRule::Mehrotra && request_.coarse_duals &&
        !request_.coarse_duals->empty() && request_.coarse_steps) {
      // The barrier of the warm start: its own complementarity (the predictor lowers it).
      mu_ =
          std::max(scales_.mu_final, std::min(mu_, system_.warmStartDuals(*request_.coarse_duals)));
    }
  }

  // PrimalDualProblem: what the decrement test reads, the direction, the step, a rejection, the
  // ends.
  void describe(BarrierState* s) const override {
    s->max_violation = block_.maxViolation();
    s->f_scale = scales_.f_scale;
  }
  BarrierRows* barrierRows() override { return &system_; }
  double previousDecrement() const override { return test_.previousDecrement(); }
  /// The condensed system (primal: with the multipliers μ/s); a non-finite cost ends the solve.
  Pass assemble(bool primal) override {
    cost_ = system_.assemble(mu_, rho_, primal, &kkt_blocks_, &rhs_, &merit_gradient_);
    if (!std::isfinite(cost_)) {
      return end(Termination::StepTooLarge,
                 "non-finite cost (step too large for this h? increase steps)");
    }
    return Pass::Step;
  }
  /// The slope of φ_μ along the step (free slacks: with the slack terms); without the primal
  /// multipliers a step that is no descent direction is taken again with them (it is one with
  /// them, H being positive definite).
  Pass direction(bool primal, double shift, LineSearchRequest* request, Eigen::VectorXd** d,
                 DirectionMeasures* measures) override {
    double slope = merit_gradient_.dot(d_);
    double decrement_slope = 0.0;
    if (free_slacks_) addSlackTerms(&slope, &decrement_slope);
    if (slope >= 0.0 && !primal) return Pass::Retry;
    if (watched(shift, free_slacks_ ? decrement_slope : slope)) return Pass::Stop;
    *measures = {free_slacks_ ? decrement_slope : slope, shift};
    request->slope = slope;
    request->alpha0 = free_slacks_ ? alpha_slack_ : 1.0;
    *d = &d_;
    return Pass::Step;
  }
  /// Whether the request's watch stops the solve at this iterate (a FeasibleIterate: free
  /// slacks, every constraint met, no shift, a small step; `slope` the merit's along the step,
  /// a lower one than φ's own with free slacks), ending it with the watch's reason.
  bool watched(double shift, double slope) {
    if (!request_.watch || !free_slacks_ || shift != 0.0 || slope >= 0.0) return false;
    if (block_.maxViolation() > 0.0) return false;
    const FeasibleIterate at{
        cost_, cost_ - block_.rows.dualityGap() + 0.5 * slope,
        std::sqrt(-slope / std::max(2.0 * cost_, std::numeric_limits<double>::min())), iteration_};
    if (!(at.relative_decrement <= kLocalBoundDecrement)) return false;
    const std::string stop = (*request_.watch)(at);
    if (stop.empty()) return false;
    stopped_by_watch_ = true;
    end(Termination::NotConverged, stop);
    return true;
  }
  Pass noDirection() override {
    return end(Termination::NotConverged, "Newton system could not be made positive definite");
  }

  /// Takes the step, reports it; the barrier problem's last step ends it.
  Pass accept(const LineSearchResult& result, const StopVerdict& verdict) override {
    const double alpha = result.alpha;
    takeStep(trial_, alpha);
    if (!report(cost_, verdict.relative_decrement, alpha)) {
      ++iteration_;
      return end(Termination::Cancelled, "cancelled");
    }
    if (const std::string stop = iterateStop(); !stop.empty()) {
      ++iteration_;
      stopped_by_watch_ = true;
      return end(Termination::NotConverged, stop);
    }
    return verdict.final_step ? endBarrierProblem() : Pass::Continue;
  }

  /// The context's IterateWatch on the accepted iterate (empty: go on, or no watch).
  std::string iterateStop() {
    if (!context_.watchesIterates()) return {};
    return context_.iterateStop(np_.attitudes(np_.current()));
  }

  /// Free slacks: the slack and dual steps, the ℓ1 merit's ν (at least the multipliers after the
  /// step, and large enough that the step decreases the merit by a fraction of its predicted
  /// infeasibility reduction), and the slopes with the slacks' and the penalty's part.
  void addSlackTerms(double* slope, double* decrement_slope) {
    const ConstrainedSystem::SlackStep slack = system_.slackStep(d_, mu_);
    alpha_slack_ = slack.alpha;
    alpha_dual_ = dualStep();
    nu_ = std::max(nu_, p_.merit_multiplier_margin * block_.largestMultiplier(0.0));
    const double without_penalty = *slope + slack.barrier_slope;
    const double fraction = p_.merit_infeasibility_fraction;
    if (slack.residual > 0.0 && without_penalty > -fraction * nu_ * slack.residual) {
      nu_ = std::max(nu_, 2.0 * without_penalty / ((1.0 - fraction) * slack.residual));
    }
    *slope = without_penalty - nu_ * slack.residual;
    // (Its magnitude: a step that mostly repairs round-off residuals may raise f and the barrier
    // a little; that is not convergence.)
    *decrement_slope = -std::abs(without_penalty) - nu_ * slack.significant_residual;
  }

  // The line search (ArmijoBacktracking in the fixed-h profile) is Armijo on φ_μ along the
  // retraction from the fraction-to-the-boundary step (the free slacks' α, else 1); a predicted
  // decrease below φ's round-off is taken. trial_ is the accepted point.
  // BarrierProblem: φ_μ with the penalty of the form (free slacks: ν, elastic: ρ) at the
  // iterate's slacks moved with the step.
  double merit() override { return system_.assembledMerit(cost_, mu_, penalty()); }
  double trialMerit(const Eigen::VectorXd& d, double alpha, bool* moved) override {
    trial_ = FixedStepTranscription::retract(np_, d, alpha);
    if (moved) *moved = true;
    // The domain, as the barrier's c > 0: a step past the scheme's fold aliases a slow motion.
    if (!np_.onPrincipalBranch(trial_)) return std::numeric_limits<double>::infinity();
    return system_.merit(trial_, mu_, penalty(), nullptr, alpha);
  }
  void moveTo(const Eigen::VectorXd& d, double alpha) override {
    trial_ = FixedStepTranscription::retract(np_, d, alpha);
  }
  void restore() override {}  // the trials never moved the accepted iterate
  double penalty() const { return free_slacks_ ? nu_ : rho_; }

  /// A direction the line search rejects (not at the round-off floor: the decrement test ends
  /// the solve there), regularized more by the inertia correction (Levenberg–Marquardt): a retry
  /// is an iteration (counted), reported too, at the same iterate (step 0).
  Pass retry(const StopVerdict& verdict) override {
    if (report(cost_, verdict.relative_decrement, 0.0)) return Pass::Continue;
    ++iteration_;
    return end(Termination::Cancelled, "cancelled");
  }
  /// No retry left.
  Pass rejected(const LineSearchResult&, const StopVerdict& verdict) override {
    relative_decrement_ = verdict.relative_decrement;
    return end(Termination::NotConverged, "line search failed");
  }
  Pass ended(const LoopEnd& e) override {
    if (e.decrement) relative_decrement_ = *e.decrement;
    return end(e.termination, e.reason);
  }

  /// Takes the step: slacks, multipliers (the values the step was computed with, moved by the
  /// dual step), the iterate.
  void takeStep(const ReducedProblem::StepVectors& trial, double alpha) {
    if (free_slacks_) {
      system_.applySlackStep(alpha);
    } else {
      alpha_dual_ = dualStep();
    }
    block_.applyDualStep(std::min(alpha_dual_, 1.0));
    FixedStepTranscription::accept(np_, trial, d_, alpha);
  }

  /// Records the iteration and reports it; false if the caller asked to stop.
  bool report(double cost, double decrement, double alpha) {
    relative_decrement_ = decrement;
    IterationInfo info{iteration_ + 1, cost, decrement, alpha};
    info.steps = np_.steps();  // the grid level and its h·cost, for the action's feedback
    info.effort = cost * np_.scheme().timeStep();
    history_.push_back(info);
    return context_.reportIteration(info);
  }

  /// The last step of a barrier problem at μ_final: converged if feasible; a small violation may
  /// be a penalty below a multiplier (elastic: raise ρ once and re-solve from here); else
  /// infeasible.
  Pass endBarrierProblem() {
    ++iteration_;
    system_.evaluateValues(np_.current(), nullptr);
    const double violation = block_.maxViolation();
    if (violation <= p_.feasibility_tolerance) return end(Termination::Converged, "converged");
    if (!free_slacks_ && penalty_raises_ == 0 && violation <= p_.penalty_raise_violation) {
      ++penalty_raises_;
      rho_ *= p_.fixed_step.penalty_growth;
      mu_ = mu_start_;
      test_.restart(iteration_);
      block_.initialize(mu_, rho_,
                        p_.initial_multiplier_cap * scales_.f_scale / scales_.constraints);
      // The raise is counted as an iteration (the step before it ended a pass too): reported,
      // at the same iterate, so that the context's count is the solve's.
      if (report(cost_, relative_decrement_, 0.0)) return Pass::Continue;
      ++iteration_;
      return end(Termination::Cancelled, "cancelled");
    }
    return end(Termination::Infeasible, "infeasible");
  }

  /// The problem as the iterate poses it: with a pointing end condition, R_N at the iterate's
  /// twist (the plan is judged against the end attitude it chose).
  PlanningProblem posedAtIterate() const {
    PlanningProblem posed = problem_;
    if (np_.hasTwist()) {
      const Matrix3 end = np_.attitudes(np_.current()).back();
      posed.final_attitude =
          pointingAttitude(problem_.end_condition, twistOf(end, problem_.end_condition));
    }
    return posed;
  }

  /// The pointing summary of the plan: ψ, the end condition's residual, ∂L/∂ψ and its relative
  /// size (relativeStationarity formed them).
  void reportTwist(const Maneuver& planned, PlanResult* result) const {
    PointingSummary& p = result->pointing;
    summarizePointingEnd(planned.attitude.back(), problem_.end_condition, &p);
    p.twist_gradient = system_.twistGradient();
    p.twist_stationarity = system_.twistStationarity();
  }

  /// The result: the plan at the last accepted iterate, its figures and the message.
  GridOutcome finish() {
    GridOutcome out;
    out.stopped_by_watch = stopped_by_watch_;
    PlanResult& result = out.result;
    result.solver = "interior_point";
    result.iterations = iteration_;
    result.newton_decrement = relative_decrement_;
    result.history = history_;
    out.steps = np_.current();
    if (free_slacks_) out.duals = system_.duals();
    // A solve stopped on a coarser level of a continuation is not evaluated here: its iterate is
    // carried to the requested grid and evaluated there (carryToGrid). Otherwise the plan's
    // residuals are measured, a stopped one's too (one more gradient at N: what a user reads to
    // tell a stopped iterate from an answer).
    result.max_residual = std::numeric_limits<double>::quiet_NaN();
    const PlanningProblem posed = posedAtIterate();
    if (!stoppedByRequest(termination_) || request_.evaluate_when_stopped) {
      const Maneuver planned = np_.maneuver(np_.current());
      result.switching_function = system_.switchingFunction(planned.torque);
      result.max_residual = system_.relativeStationarity(mu_, rho_, &rhs_, &merit_gradient_);
      evaluatePlan(posed, planned.torque, &result, &planned);
      if (np_.hasTwist()) reportTwist(planned, &result);
    }
    std::ostringstream msg;
    if (termination_ == Termination::Infeasible) {
      const ConstraintCheck check = checkConstraints(posed, result.maneuver);
      msg << "infeasible: " << (check.worst.empty() ? std::string("the constraints") : check.worst)
          << " " << describeManeuverSpan(problem_)
          << " (the violation stopped decreasing; the last iterate exceeds it " << check.worst_where
          << ")";
    } else {
      if (termination_ == Termination::Converged) {
        const std::string inconsistent = planInconsistency(posed, result, true);
        if (!inconsistent.empty()) {
          termination_ = Termination::NotConverged;
          reason_ = inconsistent;
        }
      }
      msg << reason_;
    }
    result.termination = termination_;
    recordVerdict(&result,
                  verdicts::InteriorPointEnded{msg.str(), iteration_, relative_decrement_,
                                               mu_ / scales_.f_scale, block_.maxViolation()});
    result.levels.push_back({np_.steps(), iteration_, termination_, result.max_residual,
                             relative_decrement_,
                             std::string(free_slacks_ ? "interior point (free slacks): "
                                                      : "interior point (elastic): ") +
                                 renderMessage(result)});
    return out;
  }

  const PlanningProblem& problem_;
  const SolverOptions& options_;
  SolveContext& context_;
  const GridRequest request_;
  ConstrainedSystem& system_;
  const bool free_slacks_;
  DecrementTest test_;  ///< the stopping test and its memory (stalls, the last step)
  Eigen::VectorXd merit_gradient_;
  double mu_start_ = 0.0;
  double nu_ = 0.0;    ///< free slacks: the merit's ν ≥ the multipliers (raised as needed)
  double cost_ = 0.0;  ///< f at the iterate (the line search's φ_μ)
  ReducedProblem::StepVectors trial_;  ///< the line search's trial point
  double alpha_dual_ = 1.0, alpha_slack_ = 1.0;
  double relative_decrement_ = 0.0;
  int penalty_raises_ = 0;
  bool stopped_by_watch_ = false;
  std::vector<IterationInfo> history_;
};

template <typename Scalar>
GridOutcome solveIn(const PlanningProblem& problem, const SolverOptions& options,
                    const InteriorPointParameters& parameters, SolveContext& context,
                    const GridRequest& request) {
  std::optional<ReducedProblem> reduced;
  GridOutcome out;
  out.result.solver = "interior_point";
  try {
    reduced.emplace(problem);
  } catch (const StepTooLarge& e) {
    recordVerdict(&out.result, verdicts::NoBoundaryStep{e.what()});
    out.result.termination = Termination::StepTooLarge;
    return out;
  }
  ReducedProblem& np = *reduced;
  // The initial guess: the warm start (the unconstrained optimum), a coarser grid's solution,
  // else the geodesic.
  if (options.warm_start) np.setInteriorFromAttitudes(options.warm_start->attitude);
  if (request.coarse_steps && static_cast<int>(request.coarse_steps->size()) == problem.steps) {
    np.setCurrent(*request.coarse_steps);  // an initial guess's own steps (same N)
  } else if (request.coarse_steps) {
    np.initializeFromCoarser(*request.coarse_steps);
  }
  // R_0 and R_N are checked up front (problem validation); R_1, R_{N−1} where the boundary
  // velocities fix them are not unknowns: no plan at this N repairs a cone they violate.
  // A free twist moves R_{N−1} (paper, variational): its cone is a row then, not data.
  const std::string fixed = np.hasTwist()
                                ? fixedNodeConeViolation(problem, np, {1})
                                : fixedNodeConeViolation(problem, np, {1, np.steps() - 1});
  if (!fixed.empty()) {
    out.result.termination = Termination::Infeasible;
    recordVerdict(&out.result, verdicts::ConeAtFixedNode{fixed});
    return out;
  }
  ConstrainedSystem system(problem, &np, request.formulation, parameters);
  return GridSolve<Scalar>(problem, options, parameters, context, request, &np, &system).run();
}

}  // namespace

GridOutcome carryToGrid(const PlanningProblem& problem,
                        const ReducedProblem::StepVectors& coarse_steps, Termination termination,
                        const std::vector<MessageClause>& said) {
  GridOutcome out;
  PlanResult& result = out.result;
  result.solver = "interior_point";
  result.termination = termination;
  takeReason(&result, said);
  std::optional<ReducedProblem> reduced;
  try {
    reduced.emplace(problem);
  } catch (const StepTooLarge& e) {
    result.termination = Termination::StepTooLarge;
    recordVerdict(&result, verdicts::NoBoundaryStep{e.what()});
    return out;
  }
  if (coarse_steps.empty()) {
    // Stopped before any level held an iterate: there is no plan to carry, and no input error.
    result.levels.push_back({problem.steps, 0, termination,
                             std::numeric_limits<double>::quiet_NaN(), 0.0,
                             "interior point: stopped before any level held an iterate (" +
                                 renderMessage(result) + ")"});
    return out;
  }
  ReducedProblem& np = *reduced;
  np.initializeFromCoarser(coarse_steps);
  out.steps = np.current();
  const Maneuver planned = np.maneuver(np.current());
  result.max_residual = std::numeric_limits<double>::quiet_NaN();  // not measured
  evaluatePlan(problem, planned.torque, &result, &planned);
  result.levels.push_back(
      {np.steps(), 0, termination, result.max_residual, 0.0,
       "interior point: carried from a coarser level (" + renderMessage(result) + ")"});
  return out;
}

namespace {

/// long double is the x87 extended format here (64-bit significand, in hardware).
constexpr bool kLongDoubleIsX87 = std::numeric_limits<long double>::digits == 64;

}  // namespace

SystemPrecision resolvePrecision(Precision precision, int steps) {
  switch (precision) {
    case Precision::Double:
      return SystemPrecision::Double;
    case Precision::Extended:
      return kLongDoubleIsX87 ? SystemPrecision::LongDouble : SystemPrecision::DoubleDouble;
    case Precision::DoubleDouble:
      return SystemPrecision::DoubleDouble;
    case Precision::Auto:
      break;
  }
  if (steps <= kAutoDoubleMaxSteps) return SystemPrecision::Double;
  if (kLongDoubleIsX87 && steps <= kAutoExtendedMaxSteps) return SystemPrecision::LongDouble;
  return SystemPrecision::DoubleDouble;
}

GridOutcome solveOnGrid(const PlanningProblem& problem, const SolverOptions& options,
                        const InteriorPointParameters& parameters, SolveContext& context,
                        const GridRequest& request) {
  switch (resolvePrecision(options.precision, problem.steps)) {
    case SystemPrecision::Double:
      return solveIn<double>(problem, options, parameters, context, request);
    case SystemPrecision::LongDouble:
      return solveIn<long double>(problem, options, parameters, context, request);
    case SystemPrecision::DoubleDouble:
      break;
  }
  return solveIn<DoubleDouble>(problem, options, parameters, context, request);
}

}  // namespace attitude_planner
