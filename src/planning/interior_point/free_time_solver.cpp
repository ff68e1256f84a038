// Minimum time as one feasible primal–dual barrier problem over x = (δ, η = h/h₀): min T/T₀ + εC
// s.t. c_i(δ, h) ≥ 0, ε = ε₀ μ/μ₀ vanishing with μ (it makes the Newton system definite where a
// torque is strictly inside its bounds; at μ → 0 the end is a KKT point of minimum time itself).
// A start h cannot bring inside (spinning ends) is made feasible by an ℓ1-elastic phase, one
// relaxation per row. The derivation: docs/notes/interior_point_formulation.md.
#include "planning/interior_point/free_time_solver.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <optional>

#include "attitude_planner/planning/interior_point_parameters.hpp"
#include "planning/interior_point/barrier_forms.hpp"
#include "planning/interior_point/barrier_problem_solve.hpp"
#include "planning/interior_point/barrier_update.hpp"
#include "planning/interior_point/inertia_correction.hpp"
#include "planning/interior_point/kkt_system.hpp"
#include "planning/interior_point/line_search.hpp"
#include "planning/interior_point/primal_dual_loop.hpp"
#include "planning/interior_point/stopping_tests.hpp"
#include "planning/linalg/bordered_band.hpp"
#include "planning/problem/duration_bound.hpp"
#include "planning/problem/message_notes.hpp"
#include "planning/transcription/minimum_time_objective.hpp"
#include "planning/transcription/node_constraints.hpp"
#include "planning/transcription/stage_constraints.hpp"

namespace attitude_planner {

namespace {

/// The free-time profile of the barrier problem: objective T/T₀ + ε(μ) C, every row Feasible but
/// an elastic start's, a stencil's block summed in double, the trial point h and then the nodes,
/// the second-order correction, the KKT residual test.
class FreeTimeSolver final : public BarrierProblemSolve<FreeTimeStep, double>,
                             public FreeTimeProblem {
 public:
  FreeTimeSolver(const PlanningProblem& problem, ReducedProblem* np,
                 const StageConstraints& constraints, const InteriorPointParameters& parameters,
                 ElasticBarrier elastic_barrier, StartBarrier start_barrier,
                 const FreeTimeScale& scale)
      : BarrierProblemSolve(*np, parameters, constraint_block_, nullptr,
                            {"iteration limit", "out of time"}),
        problem_(problem),
        N_(np->steps()),
        n_(np->unknowns()),
        feasible_(parameters),
        elastic_form_(parameters),
        constraint_block_(
            constraints, *np,
            [this](const FreeTimeRows& g) -> const BarrierForm<10>& { return form(g); }),
        elastic_barrier_(elastic_barrier),
        start_barrier_(start_barrier),
        scale_(scale) {
    rho_ = p_.free_time.initial_penalty;
  }

  double smallestValue(bool moves_with_h) const override {
    return smallestValue(QuantityInputs(np_, np_.current()), moves_with_h);
  }
  void beginAt(bool elastic) override {
    h0_ = np_.timeStep();
    if (!elastic) return;
    elastic_ = started_elastic_ = true;
    rho_ = p_.free_time.initial_penalty;
    least_time_step_ = discreteDurationLowerBound(problem_) / N_;  // 0: no bound applies
  }
  FreeTimeOutcome run(double tolerance, int max_iterations, SolveContext& context,
                      const BarrierWatch& watch) override;
  bool barrierHessianDefinite() const override;
  std::optional<LeastEigenpair> barrierHessianLeastEigenpair() const override {
    return leastEigenpair(kkt_blocks_);
  }

 private:
  /// Whether the group's rows are ℓ1-elastic now: the constraints that move with h, while the
  /// start is elastic (the others, the cones, hold strictly at every iterate).
  bool elasticRows(const FreeTimeRows& g) const {
    return elastic_ && g.quantity->dependsOnTimeStep();
  }
  const BarrierForm<10>& form(const FreeTimeRows& g) const {
    if (elasticRows(g)) return elastic_form_;
    return feasible_;
  }
  double smallestValue(const QuantityInputs& at, bool moves_with_h) const {
    return block_.rows.smallestValue(
        at, [&](const FreeTimeRows& g) { return g.quantity->dependsOnTimeStep() == moves_with_h; });
  }
  /// The quantities' inputs at the iterate (inputs_), while run() is in progress.
  const QuantityInputs& inputs() {
    if (!inputs_) inputs_.emplace(np_, np_.current());
    return *inputs_;
  }
  /// The global unknowns bordering the band: η, and a pointing end's twist ψ.
  int borderSize() const { return FreeTimeStep::globals(np_); }

  /// φ_μ = T/T₀ + εC plus the rows' terms at the iterate: +∞ at the first row outside its form's
  /// domain (at a trial also below (1 − τ) of its accepted value) or, at a trial, off the principal
  /// branch. Most trials are rejected at a row: the cost and the rows after it are left.
  double merit(double mu, double epsilon, bool trial) {
    const QuantityInputs& at = inputs();
    if (!block_.rowMeritsInside(at, mu, rho_, trial, &row_terms_, &row_outside_)) {
      return std::numeric_limits<double>::infinity();
    }
    if (trial && !np_.onPrincipalBranch(np_.current())) {
      return std::numeric_limits<double>::infinity();
    }
    const double cost = np_.scheme().cost(at.torques());
    return BarrierRowBlock<FreeTimeStep>::merit(objective_.value(np_.timeStep(), cost, epsilon),
                                                row_terms_);
  }

  double firstBarrier() const;
  void assemble(double mu, double epsilon);
  void leaveElasticIfInside();
  /// Back to the accepted R_N with the accepted steps (a trial's twist moved it).
  void restoreAcceptedEnd();
  // BarrierProblem, from the point the line search started at (accepted_).
  double merit() override { return merit(accepted_.mu, accepted_.epsilon, false); }
  double trialMerit(const Eigen::VectorXd& d, double alpha, bool* moved) override;
  void moveTo(const Eigen::VectorXd& d, double alpha) override;
  void restore() override;
  bool correctedStep(const Eigen::VectorXd& d, Eigen::VectorXd* corrected) override;
  void clearCorrection() override;
  // PrimalDualProblem: the free-time profile's pass.
  void prepare() override;
  void describe(BarrierState* s) const override {
    s->elastic = elastic_;
    s->stationarity = stationarity_;
    s->gap = gap_;
    s->barrier_residual = barrier_residual_;
    s->solved_to_round_off = solved_to_round_off_;
    s->end_game = late_;
  }
  Pass atSolvedBarrier() override;
  void barrierDecreased() override { report(0.0, stationarity_); }
  /// Assembled in prepare(); the end game is known before the factorization.
  Pass assemble(bool) override {
    late_ = mu_ <= p_.damped_barrier * mu0_;
    return Pass::Step;
  }
  Pass direction(bool primal, double shift, LineSearchRequest* request, Eigen::VectorXd** d,
                 DirectionMeasures* measures) override;
  Pass accept(const LineSearchResult& result, const StopVerdict& verdict) override;
  Pass solvedToRoundOff(const LineSearchResult& result) override;
  Pass rejected(const LineSearchResult& result, const StopVerdict& verdict) override;
  Pass ended(const LoopEnd& e) override { return end(e.termination, e.reason); }
  /// Stopped inside an assembly: the iterate's system is assembled once more without polling, so
  /// the residuals reported are the iterate's.
  void interruptedInsidePass() override {
    context_ = nullptr;
    assemble(mu_, epsilon_);
  }
  double meritSlope(const Eigen::VectorXd& d) const;
  double barrierResidual(double mu) const;
  /// Why `watch` stops the solve at this solved barrier problem (empty: it goes on).
  std::string watched(const BarrierWatch& watch, double mu, double gap, double epsilon,
                      int iterations) const;
  /// Reports one counted pass to the context: a step of length `alpha`, or (0) a barrier update.
  void report(double alpha, double stationarity) const;
  /// The outcome at the iterate the solve ended at (termination_, reason_).
  FreeTimeOutcome outcome() const;

  const PlanningProblem& problem_;
  int N_, n_;
  double h0_ = 0.0;
  Feasible feasible_;           ///< −μ ln c: how a row enters the barrier problem
  L1Elastic<10> elastic_form_;  ///< an elastic start's rows (elasticRows)
  BarrierRowBlock<FreeTimeStep> constraint_block_;  ///< block_: its rows in form(group)
  Eigen::VectorXd lagrangian_gradient_;  ///< ∇L at the assembled iterate (rhs_ is −∇φ_μ)
  // The run (run()): its barrier problems and the stopping test.
  double mu0_ = 0.0;
  MinimumTimeObjective objective_{1, 1.0, 0.0, 1.0};  ///< T/T₀ + ε(μ) C (set by run())
  double epsilon_ = 0.0;                              ///< ε(μ) of this pass's barrier problem
  KktResidualTest test_{0.0, 1};
  const BarrierWatch* watch_ = nullptr;
  bool stopped_by_watch_ = false;
  /// What this pass measured at the assembled iterate, and its step.
  double gap_ = 0.0, stationarity_ = 0.0, barrier_residual_ = 0.0;
  bool late_ = false;  ///< μ ≤ the damped barrier: the end game (damping, the correction)
  std::vector<double> row_terms_;  ///< the rows' merit terms at the iterate (merit)
  /// The quantities' inputs at the iterate (its torques and attitudes), formed once while it does
  /// not move: a trial's merit, its second-order correction, the accepted step's rows and the next
  /// search's first merit read one set (inputs(); every move resets it).
  std::optional<QuantityInputs> inputs_;
  int row_outside_ = -1;  ///< the row a merit last found outside its domain (rowMeritsInside)
  /// The barrier problem is solved as far as round-off allows (its Newton step no longer
  /// changes φ_μ): the next pass lowers μ.
  bool solved_to_round_off_ = false;
  /// The accepted iterate a line search starts from, and its barrier problem.
  struct SearchStart {
    double h = 0.0, mu = 0.0, epsilon = 0.0;
    ReducedProblem::StepVectors steps;
  } accepted_;
  Matrix3 accepted_end_ = Matrix3::Identity();  ///< R_N at the accepted iterate
  // An elastic start (beginAt): until the iterate is strictly inside every constraint that moves
  // with h, those constraints' rows are ℓ1-elastic with the penalty ρ.
  bool elastic_ = false, started_elastic_ = false;
  double least_time_step_ = 0.0;  ///< the proven least duration over N (0: no bound applies)
  const ElasticBarrier elastic_barrier_;
  const StartBarrier start_barrier_;
  const FreeTimeScale scale_;  ///< the objective's T₀ and C₀ (unset: the start's own)
  /// The request's context while run() is in progress: polled inside the assembly (null: no
  /// polls), reported to after every accepted step.
  SolveContext* context_ = nullptr;
};

/// w = ε r − Σ zᵢ ∂cᵢ/∂r: the Lagrangian's second-order weights of the residual r = √w τ (the
/// rows are prepared in the visit, after z entered w); a stencil's block, with every row's ω a aᵀ
/// in one 3×3 W, summed in double (BarrierRowBlock::assemble); the cones before the rows that
/// move with h (the order the band's sums were formed in).
void FreeTimeSolver::assemble(double mu, double epsilon) {
  const FreeTimeStep step{h0_};
  KktSink<double, FreeTimeStep> sink(np_, step, &kkt_blocks_);
  rhs_.setZero(n_ + borderSize());
  lagrangian_gradient_.setZero(n_ + borderSize());
  AssemblyChoices choices;
  choices.cost_weight = epsilon;
  choices.sum_in_double = choices.row_gradients = choices.fixed_quantities_first = true;
  block_.assemble(&sink, step, mu, rho_, choices, &rhs_, &lagrangian_gradient_, [&](int k) {
    if (context_ && k % kColumnsBetweenPolls == 0) context_->poll();
  });
  const double dT = objective_.timeGradient();  // ∂(T/T₀)/∂η = N h₀/T₀
  rhs_(n_) -= dT;
  lagrangian_gradient_(n_) += dT;
}

/// Leaves the elastic phase once every constraint holds strictly: the iterate is a plan (the
/// rows' multipliers carry over, safeguarded for the feasible form).
void FreeTimeSolver::leaveElasticIfInside() {
  if (!elastic_ || !(smallestValue(inputs(), true) > 0)) return;
  elastic_ = false;
}

void FreeTimeSolver::restoreAcceptedEnd() {
  if (np_.hasTwist()) np_.setCurrentWithFinalAttitude(accepted_.steps, accepted_end_);
}

void FreeTimeSolver::moveTo(const Eigen::VectorXd& d, double alpha) {
  inputs_.reset();
  // Back to the accepted iterate (its boundary steps at its h), then h, then the attitudes:
  // setTimeStep keeps the free attitudes, which the δ-step then moves.
  np_.setCurrent(accepted_.steps);
  restoreAcceptedEnd();
  np_.setTimeStep(accepted_.h + alpha * h0_ * d(n_));
  // The iterate's nodes moved by α d (and R_N by α dψ with a pointing end).
  block_.rows.accept(np_, block_.rows.retract(np_, d, alpha), d, alpha);
}

double FreeTimeSolver::trialMerit(const Eigen::VectorXd& d, double alpha, bool* moved) {
  if (moved) *moved = false;
  const double h = accepted_.h + alpha * h0_ * d(n_);
  if (h <= 0) return std::numeric_limits<double>::infinity();
  // An elastic iterate is no plan and can trade violation for a T below every plan's: while
  // elastic, h keeps the fraction to the boundary of the proven least duration.
  if (elastic_ && h < accepted_.h) {
    const double floor = least_time_step_;
    if (floor > 0 && h - floor < (1.0 - p_.fraction_to_boundary) * (accepted_.h - floor)) {
      return std::numeric_limits<double>::infinity();
    }
  }
  try {
    moveTo(d, alpha);
    if (moved) *moved = true;
    return merit(accepted_.mu, accepted_.epsilon, true);
  } catch (const std::exception&) {  // no boundary step at that h (StepTooLarge)
    return std::numeric_limits<double>::infinity();
  }
}

void FreeTimeSolver::restore() {
  inputs_.reset();
  restoreAcceptedEnd();
  np_.setTimeStep(accepted_.h);
  np_.setCurrent(accepted_.steps);
}

/// The second-order correction of a rejected trial step d (IPOPT's, Wächter & Biegler 2006 §2.4):
/// at x + d (the iterate on entry) each row misses its linear model by r = c(x + d) − c − gᵀd;
/// d' = d − K⁻¹ Σ (z/c) r g with the step's factorization (where minimum time is flat along an arc,
/// the bounds' curvature cuts the Newton step again and again). False where no r is nonzero or d'
/// is not finite.
bool FreeTimeSolver::correctedStep(const Eigen::VectorXd& d, Eigen::VectorXd* corrected) {
  Eigen::VectorXd v = Eigen::VectorXd::Zero(n_ + borderSize());
  bool curved = false;
  block_.rows.forEachValue(inputs(), [&](auto& g, int k, auto& in, double c) {
    in.r = c - in.c - block_.rows.dot(np_, g, k, in.g, d);
    const double w = -form(g).terms(in, 0.0).weight * in.r;
    if (w == 0.0) return;
    curved = true;
    block_.rows.addRow(np_, g, k, in.g, w, &v);
  });
  if (!curved) return false;
  kkt_->solve(&v);
  if (!v.allFinite()) return false;
  *corrected = d + v;
  return true;
}

void FreeTimeSolver::clearCorrection() {
  block_.rows.forEach([](FreeTimeRows&, int, FreeTimeRow& in) { in.r = 0.0; });
}

/// ∇φ_μ·d at the assembled point. The right-hand side is −∇φ_μ where every row's coefficient β
/// is its barrier's −ψ'(c): so for a feasible row (μ/c); an elastic row's β = z + q/D equals
/// ψ'(c) = −μ/s only at its primal multiplier, so the difference is taken out here.
double FreeTimeSolver::meritSlope(const Eigen::VectorXd& d) const {
  double slope = -d.dot(rhs_);
  if (!elastic_) return slope;
  block_.rows.forEach([&](const FreeTimeRows& g, int k, const FreeTimeRow& in) {
    if (elasticRows(g))
      slope += (form(g).terms(in, mu_).rhs - mu_ / in.s) * block_.rows.dot(np_, g, k, in.g, d);
  });
  return slope;
}

/// The barrier problem's KKT residual max(‖∇L‖∞, max |zc − μ|) at the assembled point.
double FreeTimeSolver::barrierResidual(double mu) const {
  const double stationarity = lagrangian_gradient_.lpNorm<Eigen::Infinity>();
  return std::max(stationarity, block_.complementarity(mu, rho_).worst);
}

std::string FreeTimeSolver::watched(const BarrierWatch& watch, double mu, double gap,
                                    double epsilon, int iterations) const {
  if (!watch || elastic_) return "";
  BarrierPoint point;
  point.mu = mu;
  point.duration = N_ * np_.timeStep();
  point.lower_bound = objective_.lowerBound(np_.timeStep(), gap, np_.cost(np_.current()), epsilon);
  point.attitudes = np_.attitudes(np_.current());
  point.iterations = iterations;
  point.locally_convex = barrierHessianDefinite();
  return watch(point);
}

void FreeTimeSolver::report(double alpha, double stationarity) const {
  IterationInfo info;
  info.gradient_norm = stationarity;
  info.step_length = alpha;
  info.steps = N_;
  if (context_->hasIterationCallback()) {  // the cost, O(N), only where a callback reads it
    info.cost = np_.cost(np_.current());
    info.effort = np_.timeStep() * info.cost;
  }
  context_->reportIteration(info);
}

FreeTimeOutcome FreeTimeSolver::run(double tolerance, int max_iterations, SolveContext& context,
                                    const BarrierWatch& watch) {
  context_ = &context;
  watch_ = &watch;
  inputs_.reset();  // the recipe may have moved the iterate since
  const int m = block_.rows.count;
  mu0_ = p_.free_time.initial_barrier / m;
  objective_ = scale_.set() ? MinimumTimeObjective(N_, h0_, scale_.cost, mu0_, scale_.duration)
                            : MinimumTimeObjective(N_, h0_, np_.cost(np_.current()), mu0_);
  test_ = KktResidualTest(tolerance, N_);
  // μ is already on the objective's scale (T/T₀ about 1 at the start): the rule's scaled μ is μ.
  scales_ = {1.0, 1, N_, p_.final_barrier_fraction * tolerance / m};
  mu_ = firstBarrier();
  // The first multipliers: the primal ones at the start's values (an elastic row safeguarded).
  block_.rows.evaluate(inputs());
  block_.prepare(mu_, rho_, true);
  solve({test_, std::make_unique<MonotoneBarrier>(p_, freeTimeMonotone(p_)),
         std::make_unique<PerturbationHandler>(p_)},
        {freeTimeLineSearch(p_), false, false}, context, max_iterations);
  FreeTimeOutcome out = outcome();
  out.stopped_by_watch = stopped_by_watch_;
  return out;
}

/// μ₀, or in an elastic phase begun FromViolations the μ that widens its rows' kinks to
/// elastic_kink_width of the largest violation (never below μ₀), or from a start that is a
/// neighbouring problem's KKT plan (StartBarrier::NearKktPoint) near_kkt_barrier × μ₀, low enough
/// not to carry it to another branch (docs/notes/interior_point_tuning.md).
double FreeTimeSolver::firstBarrier() const {
  if (!elastic_ && start_barrier_ == StartBarrier::NearKktPoint) return p_.near_kkt_barrier * mu0_;
  if (!elastic_ || elastic_barrier_ != ElasticBarrier::FromViolations) return mu0_;
  return std::max(mu0_, p_.elastic_kink_width * rho_ * -smallestValue(true));
}

/// Assembles at the iterate (every pass: the limits are tested after it, and the KKT residual
/// test reads what it measures).
void FreeTimeSolver::prepare() {
  epsilon_ = objective_.setBarrier(mu_);
  assemble(mu_, epsilon_);
  gap_ = block_.rows.dualityGap();
  stationarity_ = lagrangian_gradient_.lpNorm<Eigen::Infinity>();
  barrier_residual_ = mu_ > scales_.mu_final ? barrierResidual(mu_) : 0.0;  // the μ rule's test
}

/// A solved barrier problem (the μ rule's test, or solved to round-off): the watch, then the
/// elastic penalty; the loop lowers μ.
Pass FreeTimeSolver::atSolvedBarrier() {
  solved_to_round_off_ = false;
  const std::string stop = watched(*watch_, mu_, gap_, epsilon_, iteration_);
  if (!stop.empty()) {
    stopped_by_watch_ = true;
    return end(Termination::NotConverged, stop);
  }
  if (elastic_)
    rho_ *= p_.free_time.penalty_growth;  // solved still outside: the penalty was too low
  return Pass::Step;
}

/// The step found by the inertia correction, and the search from the accepted iterate: in the
/// end game each rejected trial step is first retried with its second-order correction.
Pass FreeTimeSolver::direction(bool, double, LineSearchRequest* request, Eigen::VectorXd** d,
                               DirectionMeasures*) {
  accepted_ = {np_.timeStep(), mu_, epsilon_, np_.current()};
  accepted_end_ = np_.finalAttitude();
  clearCorrection();
  *request = {meritSlope(d_), 1.0, false, false, late_ && !elastic_};
  *d = &d_;
  return Pass::Step;
}

/// The order is the method's: dual step, leaving the elastic phase, κ_Σ (the loop then damps).
Pass FreeTimeSolver::accept(const LineSearchResult& result, const StopVerdict&) {
  block_.applyDualStep(dualStep());
  leaveElasticIfInside();
  block_.rows.evaluate(inputs());
  block_.afterAccept(mu_);
  report(result.alpha, stationarity_);
  return Pass::Continue;
}

Pass FreeTimeSolver::solvedToRoundOff(const LineSearchResult& result) {
  // A barrier problem above μ_final whose Newton step no longer changes φ_μ beyond round-off
  // is solved as far as it can be (its test κ_ε μ may lie below the stationarity's round-off):
  // the next μ, as the fixed-h solver's stalled steps do.
  if (!elastic_ && mu_ > scales_.mu_final && result.at_round_off) {
    solved_to_round_off_ = true;
    report(0.0, stationarity_);
    return Pass::Continue;
  }
  return Pass::Step;
}

/// Not at the round-off floor (the KKT residual test ends the solve there).
Pass FreeTimeSolver::rejected(const LineSearchResult&, const StopVerdict&) {
  return end(Termination::NotConverged, "no descent step (line search failed)");
}

FreeTimeOutcome FreeTimeSolver::outcome() const {
  FreeTimeOutcome out;
  out.termination = termination_;
  out.steps = np_.current();
  out.time_step = np_.timeStep();
  out.start_time_step = h0_;
  out.elastic_start = started_elastic_;
  out.duration = N_ * out.time_step;
  out.iterations = iteration_;
  out.effort_weight = epsilon_;
  // Residuals of the Lagrangian T/T₀ + εC − Σ z c (ε → 0 with μ: minimum time at the end).
  out.stationarity = lagrangian_gradient_.lpNorm<Eigen::Infinity>();
  out.time_row = std::abs(lagrangian_gradient_(n_));
  if (np_.hasTwist() && lagrangian_gradient_.size() == n_ + borderSize()) {
    out.twist_gradient = lagrangian_gradient_(FreeTimeStep::twistIndex(np_));
  }
  out.complementarity = block_.rows.dualityGap();
  out.smallest_value = block_.smallestValue();
  out.torque_multipliers.assign(N_ + 1, Vector3::Zero());
  if (block_.rows.hasTorqueBox()) out.switching_function.assign(N_ + 1, Vector3::Zero());
  block_.rows.addBoxMultipliers(np_, np_.torques(out.steps), &out.switching_function,
                                &out.torque_multipliers);
  out.maneuver = np_.maneuver(out.steps);
  recordVerdict(&out,
                verdicts::FreeTimeEnded{reason_, iteration_, out.duration, out.stationarity,
                                        out.time_row, out.complementarity, out.smallest_value});
  return out;
}

/// The condensed barrier Hessian factored without a shift: FreeTimeOutcome::second_order_sufficient
/// at a converged point, BarrierPoint::locally_convex at a solved barrier problem.
bool FreeTimeSolver::barrierHessianDefinite() const {
  BorderedBandKkt<double> factor;
  return factor.factor(kkt_blocks_, Shift{}) && factor.inertia().positive == borderSize() &&
         factor.inertia().negative == 0;
}

}  // namespace

std::unique_ptr<FreeTimeProblem> makeFreeTimeProblem(
    const PlanningProblem& problem, ReducedProblem* np, const StageConstraints& constraints,
    const InteriorPointParameters& parameters, ElasticBarrier elastic_barrier,
    StartBarrier start_barrier, const FreeTimeScale& scale) {
  return std::make_unique<FreeTimeSolver>(problem, np, constraints, parameters, elastic_barrier,
                                          start_barrier, scale);
}

}  // namespace attitude_planner
