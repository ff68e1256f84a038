// What the interior point's strategies ask of a problem: the barrier problem φ_μ at the accepted
// iterate and at trial points along a direction. Two implementations: the fixed-h band
// (grid_solve.cpp: ConstrainedSystem over the ReducedProblem) and free time
// (free_time_solver.cpp: the node unknowns bordered by η = h/h₀ and, while elastic, θ).
#pragma once

#include <Eigen/Core>

#include "attitude_planner/termination.hpp"
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
  /// The second-order correction of the full step d, the iterate at x + d: the same Newton system
  /// solved with the constraints' curvature along d (r = c(x + d) − c − gᵀd) in their linear
  /// model, with the step's factor. False where the problem has none or no r is nonzero.
  virtual bool correctedStep(const Eigen::VectorXd& /*d*/, Eigen::VectorXd* /*corrected*/) {
    return false;
  }
  /// Drops the curvature terms of a correction not taken (the dual step reads them).
  virtual void clearCorrection() {}
};

/// What the primal–dual loop (primal_dual_loop.hpp) asks beyond the line search; the loop calls
/// the stopping test (ConvergenceCheck) on what `state` says. The problem owns the count of
/// passes (the loop advances it after each counted pass; a hook that ends the solve on a pass it
/// has reported counts that pass itself) and the termination.
class PrimalDualProblem : public BarrierProblem {
 public:
  /// Before the stopping test: free time assembles at the iterate and measures its residuals;
  /// fixed h assembles in direction().
  virtual void prepare() {}
  /// What the stopping test reads of the iterate.
  virtual BarrierState state() const = 0;
  /// After the stopping test, before the direction: free time's barrier problem solved (μ falls,
  /// a counted pass without a step); fixed h has nothing to do.
  virtual Pass beforeDirection() { return Pass::Step; }
  /// The Newton direction at the iterate (assembly where not done, inertia correction, the
  /// barrier rule's predictor), the line search's request and what the stopping test reads of
  /// the direction; *d the step.
  virtual Pass direction(LineSearchRequest* request, Eigen::VectorXd** d,
                         DirectionMeasures* measures) = 0;
  /// The line search accepted a step of length result.alpha (the iterate at the trial point) with
  /// the stopping test's verdict: the dual step, the strategies' updates after a step, the report.
  virtual Pass accept(const LineSearchResult& result, const StopVerdict& verdict) = 0;
  /// The line search took no step at a barrier problem it has solved as far as round-off allows
  /// (free time: the next μ, a counted pass); Step: the stopping test, then rejected().
  virtual Pass solvedToRoundOff(const LineSearchResult& /*result*/) { return Pass::Step; }
  /// No step and the stopping test did not end the solve: a retry or a failure.
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
