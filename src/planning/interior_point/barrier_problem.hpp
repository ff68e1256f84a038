// What the interior point's strategies ask of a problem: the barrier problem φ_μ at the accepted
// iterate and at trial points along a direction. Two implementations, the profiles of one
// BarrierProblemSolve (barrier_problem_solve.hpp): the fixed-h band (grid_solve.cpp:
// ConstrainedSystem over the ReducedProblem) and free time (free_time_solver.cpp: the node
// unknowns bordered by η = h/h₀ and a pointing end's twist ψ).
#pragma once

#include <Eigen/Core>

#include "attitude_planner/termination.hpp"
#include "planning/interior_point/barrier_update.hpp"
#include "planning/interior_point/kkt_system.hpp"
#include "planning/interior_point/stopping_tests.hpp"

namespace attitude_planner {

struct LineSearchRequest;  // line_search.hpp
struct LineSearchResult;

/// What a pass of the primal–dual loop (primal_dual_loop.hpp) does next.
enum class Pass {
  Step,      ///< go on within this pass (to the direction, to the line search)
  Continue,  ///< the pass is over and counted: the next iteration
  Stop,      ///< the solve has ended (the problem holds its termination and why)
  Reject,    ///< no direction: the pass goes on as after a line search that took no step
  Retry,     ///< not a descent direction: assembled again with the primal multipliers
};

class BarrierProblem {
 public:
  virtual ~BarrierProblem() = default;
  /// φ_μ at the accepted iterate, at the barrier (and penalty) of the step being searched.
  virtual double merit() = 0;
  /// Moves the iterate to x + α d and returns φ_μ there; +∞ (or NaN) where that point is not
  /// admissible (outside the fraction to the boundary, h ≤ 0, no boundary step at that h).
  /// `moved` (optional): whether the iterate is at the trial point now.
  virtual double trialMerit(const Eigen::VectorXd& d, double alpha, bool* moved) = 0;
  /// Moves the iterate to x + α d without evaluating φ_μ (a step taken outright).
  virtual void moveTo(const Eigen::VectorXd& d, double alpha) = 0;
  /// Back to the accepted iterate after a search that accepted no step.
  virtual void restore() = 0;
  /// The second-order correction of a trial step d (the full step or a shorter one, α d), the
  /// iterate at x + d: the same Newton system
  /// solved with the constraints' curvature along d (r = c(x + d) − c − gᵀd) in their linear
  /// model, with the step's factor. False where the problem has none or no r is nonzero.
  virtual bool correctedStep(const Eigen::VectorXd& /*d*/, Eigen::VectorXd* /*corrected*/) {
    return false;
  }
  /// Drops the curvature terms of a correction not taken (the dual step reads them).
  virtual void clearCorrection() {}
};

/// The system of one pass as the loop factors it: K (ShiftedSystem), the right-hand side, and
/// where the step goes.
struct NewtonSystem {
  ShiftedSystem* kkt = nullptr;
  const Eigen::VectorXd* rhs = nullptr;
  Eigen::VectorXd* d = nullptr;
};

/// What the primal–dual loop (primal_dual_loop.hpp) asks beyond the line search; the loop calls
/// the strategies (the stopping test, the μ rule, the inertia correction) on what `state`,
/// `barrier` and `newtonSystem` expose. The problem owns the count of passes (the loop advances
/// it after each counted pass; a hook that ends the solve on a pass it has reported counts that
/// pass itself) and the termination.
class PrimalDualProblem : public BarrierProblem {
 public:
  /// Before the stopping test: free time assembles at the iterate and measures its residuals;
  /// fixed h assembles in assemble().
  virtual void prepare() {}
  /// What the stopping test and the μ rule read of the iterate.
  virtual BarrierState state() const = 0;
  /// μ and what the μ rule reads with it.
  virtual BarrierAccess barrier() = 0;
  /// The μ rule found the barrier problem solved: the observer's say (free time: the watch,
  /// which may stop the solve, and the elastic penalty's growth); Step: μ falls.
  virtual Pass atSolvedBarrier() { return Pass::Step; }
  /// μ fell at the same iterate: a counted pass without a step (free time reports it).
  virtual void barrierDecreased() {}
  /// Before a factorization: the Newton system at the iterate, with the primal multipliers μ/s
  /// where asked (fixed h assembles here; free time did in prepare()). Stop: the solve has ended.
  virtual Pass assemble(bool /*primal_multipliers*/) { return Pass::Step; }
  /// The assembled system the inertia correction factors.
  virtual NewtonSystem newtonSystem() = 0;
  /// The factored direction (after the μ rule's predictor): Step with the line search's request
  /// and what the stopping test reads of it (*d the step); Retry: no descent direction, assemble
  /// again with the primal multipliers.
  virtual Pass direction(bool primal_multipliers, double shift, LineSearchRequest* request,
                         Eigen::VectorXd** d, DirectionMeasures* measures) = 0;
  /// No shift within the schedule gave a direction: Reject (the rejection path), or Stop.
  virtual Pass noDirection() { return Pass::Reject; }
  /// The line search accepted a step of length result.alpha (the iterate at the trial point) with
  /// the stopping test's verdict: the dual step, the report; Stop where it ends the solve.
  virtual Pass accept(const LineSearchResult& result, const StopVerdict& verdict) = 0;
  /// The line search took no step at a barrier problem it has solved as far as round-off allows
  /// (free time: the next μ, a counted pass); Step: the stopping test, then a retry or rejected().
  virtual Pass solvedToRoundOff(const LineSearchResult& /*result*/) { return Pass::Step; }
  /// The inertia correction regularized more after a rejection: a pass counted at the same
  /// iterate (fixed h reports it).
  virtual Pass retry(const StopVerdict& /*verdict*/) { return Pass::Continue; }
  /// No step, the stopping test did not end the solve and no retry is left: a failure.
  virtual Pass rejected(const LineSearchResult& result, const StopVerdict& verdict) = 0;
  /// The stopping test ends the solve.
  virtual Pass ended(const LoopEnd& end) = 0;
  /// The solve ends at the iteration limit.
  virtual void iterationLimit() = 0;
  /// The solve ends cancelled or out of time; `inside_pass`: interrupted inside an assembly or a
  /// factorization (the assembled system is not the iterate's).
  virtual void stopped(Termination termination, bool inside_pass) = 0;
};

}  // namespace attitude_planner
