// What the interior point's strategies ask of a problem: the barrier problem φ_μ at the accepted
// iterate and at trial points along a direction. Two implementations: the fixed-h band
// (grid_solve.cpp: ConstrainedSystem over the ReducedProblem) and free time
// (free_time_solver.cpp: the node unknowns bordered by η = h/h₀ and, while elastic, θ).
#pragma once

#include <Eigen/Core>

namespace attitude_planner {

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

}  // namespace attitude_planner
