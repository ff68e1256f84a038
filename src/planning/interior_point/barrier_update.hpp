// The interior point's barrier update μ as a strategy: Mehrotra's predictor–corrector (μ chosen
// for each step from its affine-scaling predictor), the monotone Fiacco–McCormick rule (IPOPT's:
// μ falls once the barrier problem is solved to κ_ε μ) and LOQO's adaptive rule (μ from the
// complementarity's mean and spread after every step). The primal–dual loop calls the hooks;
// each rule uses the ones it needs.
#pragma once

#include <functional>
#include <memory>
#include <vector>

#include <Eigen/Dense>

#include "attitude_planner/planning/interior_point_parameters.hpp"
#include "planning/interior_point/barrier_forms.hpp"
#include "planning/interior_point/stopping_tests.hpp"

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

/// What a rule reads and moves of the problem's barrier (PrimalDualProblem::barrier): μ, its
/// scales, the rows (fixed h's slack rows; null where the problem has none a rule reads), the
/// elastic penalty and the last step's relative decrement (+∞ before the first).
struct BarrierAccess {
  double* mu = nullptr;
  BarrierScales scales;
  BarrierRows* rows = nullptr;
  double rho = 0.0;
  double previous_decrement = 0.0;
};

/// What the step just accepted looked like (for the rules updating after a step).
struct AcceptedStep {
  double relative_decrement = 0.0;
  double alpha = 1.0;  ///< its length
};

/// Solves H x = b in place with the current factor.
using FactorSolve = std::function<void(Eigen::VectorXd*)>;

/// The μ rule as the primal–dual loop (primal_dual_loop.hpp) calls it, each rule using the hooks
/// it needs: whether the barrier problem is solved at the top of a pass (then `decrease`, a pass
/// without a step), the predictor before a step, the update after one.
class BarrierUpdate {
 public:
  virtual ~BarrierUpdate() = default;
  virtual BarrierRule rule() const = 0;
  /// At the top of a pass, at the assembled iterate: the barrier problem is solved.
  virtual bool subproblemSolved(const BarrierState& /*state*/, const BarrierAccess& /*b*/) const {
    return false;
  }
  /// After a solved barrier problem: the next μ.
  virtual void decrease(const BarrierAccess& /*b*/) {}
  /// Before a primal–dual step above μ_final, the system factored and `delta` solved for `rhs`
  /// at μ: may set μ for this step and replace `delta` (the predictor–corrector).
  virtual void beforeStep(const BarrierAccess& /*b*/, const FactorSolve& /*solve*/,
                          const Eigen::VectorXd& /*rhs*/, Eigen::VectorXd* /*delta*/) {}
  /// After an accepted step above μ_final (not a barrier problem's last): the next μ.
  virtual void afterStep(const BarrierAccess& /*b*/, const AcceptedStep& /*step*/) {}
};

/// How the monotone rule tells that a barrier problem is solved (IPOPT's κ_ε μ test, on one of two
/// residuals).
enum class BarrierProblemTest {
  /// After each accepted step: the relative decrement and the slack residual ≤ κ_ε μ (scaled), or
  /// the decrement stalled at round-off (fixed h).
  Decrement,
  /// Before each step: the barrier problem's KKT residual max(‖∇L‖∞, |zc − μ|) ≤ κ_ε μ; the
  /// caller then lowers μ at the same iterate (free time).
  KktResidual,
};

/// One monotone rule, two parameter profiles: θ_μ, the test, and whether a μ near μ_final snaps
/// to it.
struct MonotoneProfile {
  double theta_mu = 1.5;
  BarrierProblemTest test = BarrierProblemTest::Decrement;
  bool snap_to_final = true;
};
/// Fixed h: the fixed-step profile's θ_μ (IPOPT's 1.5), the decrement test, snapped.
MonotoneProfile fixedStepMonotone(const InteriorPointParameters& parameters);
/// Free time: the free-time profile's θ_μ, the KKT residual test, not snapped.
MonotoneProfile freeTimeMonotone(const InteriorPointParameters& parameters);

/// Monotone (Fiacco–McCormick, as IPOPT's): μ falls only once the barrier problem is solved to
/// κ_ε μ, to min(κ_μ μ, μ^θ_μ) in the scaled μ (μ m/f_scale); an adaptive rule would drive μ to
/// μ_final while the iterate is still far from feasible, and the slacks' fraction to the boundary
/// then stalls. With the decrement test a barrier problem whose decrement stalls at the round-off
/// floor above κ_ε μ (full steps that no longer halve it) is solved as far as it can be.
class MonotoneBarrier final : public BarrierUpdate {
 public:
  MonotoneBarrier(const InteriorPointParameters& parameters, const MonotoneProfile& profile)
      : parameters_(parameters), profile_(profile) {}
  BarrierRule rule() const override { return BarrierRule::Monotone; }
  /// The KKT residual test (BarrierProblemTest::KktResidual) above μ_final, or a barrier problem
  /// the problem found solved to round-off.
  bool subproblemSolved(const BarrierState& state, const BarrierAccess& b) const override;
  void decrease(const BarrierAccess& b) override { *b.mu = decreased(*b.mu, b.scales); }
  /// The decrement test (BarrierProblemTest::Decrement): μ falls after a step that solves it.
  void afterStep(const BarrierAccess& b, const AcceptedStep& step) override;
  /// The KKT residual test (BarrierProblemTest::KktResidual) at μ.
  bool solved(double kkt_residual, double mu, const BarrierScales& scales) const;
  /// The next barrier: max(μ_final, min(κ_μ μ, μ^θ_μ)), snapped where the profile says.
  double decreased(double mu, const BarrierScales& scales) const;

 private:
  const InteriorPointParameters& parameters_;
  MonotoneProfile profile_;
  int stalled_steps_ = 0;  ///< full steps in a row that did not halve the decrement
};

/// Mehrotra and Loqo; Monotone in the fixed-h profile.
std::unique_ptr<BarrierUpdate> makeBarrierUpdate(BarrierRule rule,
                                                 const InteriorPointParameters& parameters);

/// μ within parameters.barrier_snap_factor of μ_final becomes μ_final: complementarity there is
/// round-off and a rule could leave μ just above μ_final for good.
double snapToFinalBarrier(double mu, double mu_final, const InteriorPointParameters& parameters);

}  // namespace attitude_planner
