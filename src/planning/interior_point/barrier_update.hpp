// The interior point's barrier update μ as a strategy: Mehrotra's predictor–corrector (μ chosen
// for each step from its affine-scaling predictor), the monotone Fiacco–McCormick rule (IPOPT's:
// μ falls once the barrier problem is solved to κ_ε μ) and LOQO's adaptive rule (μ from the
// complementarity's mean and spread after every step). The solver calls both hooks; each rule
// uses the one it needs.
#pragma once

#include <functional>
#include <memory>
#include <vector>

#include <Eigen/Dense>

#include "planning/interior_point/constrained_system.hpp"
#include "planning/interior_point/interior_point_parameters.hpp"

namespace attitude_planner {

enum class BarrierRule {
  Mehrotra,  ///< predictor–corrector, μ chosen per step (free slacks, first solve of a level)
  Monotone,  ///< Fiacco–McCormick with IPOPT's κ_ε, κ_μ, θ_μ (free slacks, retry)
  Loqo,      ///< Vanderbei–Shanno's adaptive rule (the elastic form)
};

/// The fixed scales a barrier rule works in.
struct BarrierScales {
  double f_scale = 1.0;   ///< the start's cost (floored)
  int constraints = 1;    ///< m, at least 1
  int steps = 0;          ///< N
  double mu_final = 0.0;  ///< the final barrier
};

/// What the step just accepted looked like (for the rules updating after a step).
struct AcceptedStep {
  double relative_decrement = 0.0;
  double previous_decrement = 0.0;  ///< of the step before (+∞ at the first)
  double alpha = 1.0;               ///< its length
  double rho = 0.0;                 ///< the elastic penalty
};

/// Solves H x = b in place with the current factor.
using FactorSolve = std::function<void(Eigen::VectorXd*)>;

class BarrierUpdate {
 public:
  virtual ~BarrierUpdate() = default;
  virtual BarrierRule rule() const = 0;
  /// Before a primal–dual step, the system factored and `delta` solved for `rhs` at μ: may set μ
  /// for this step and replace `delta` (the predictor–corrector). `previous_decrement` is the
  /// last step's relative decrement (+∞ at the first).
  virtual void beforeStep(ConstrainedSystem& /*system*/, const FactorSolve& /*solve*/,
                          const Eigen::VectorXd& /*rhs*/, const BarrierScales& /*scales*/,
                          double /*previous_decrement*/, double* /*mu*/,
                          Eigen::VectorXd* /*delta*/) {}
  /// After an accepted step above μ_final: the next μ.
  virtual void afterStep(const ConstrainedSystem& /*system*/, const BarrierScales& /*scales*/,
                         const AcceptedStep& /*step*/, double* /*mu*/) {}
};

std::unique_ptr<BarrierUpdate> makeBarrierUpdate(BarrierRule rule,
                                                 const InteriorPointParameters& parameters);

/// μ within parameters.barrier_snap_factor of μ_final becomes μ_final: complementarity there is
/// round-off and a rule could leave μ just above μ_final for good.
double snapToFinalBarrier(double mu, double mu_final, const InteriorPointParameters& parameters);

}  // namespace attitude_planner
