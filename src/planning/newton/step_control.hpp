// Step control of the Newton solver: how a Newton step is globalized. Two controls behind one
// interface, both on the shift λ of (H + λI)δ = −g (relative to the Hessian's scale):
//  - TrustRegionControl: Levenberg–Marquardt with Nielsen's update — the full step is judged by
//    the ratio ρ of the actual to the model's decrease; a rejected step raises λ (×ν, ν doubling)
//    and is recomputed; an accepted one lowers λ by max(1/10, 1 − (2ρ − 1)³), to 0 = pure Newton.
//  - LineSearchControl: the least λ that makes H + λI definite (inertia correction, as IPOPT's),
//    then backtracking (Armijo) along the step; it takes other paths than the trust region and so
//    may reach other extremals (one of the more starts).
#pragma once

#include <memory>

#include <Eigen/Core>

#include "attitude_planner/planning/newton_parameters.hpp"
#include "attitude_planner/planning/result.hpp"
#include "planning/transcription/reduced_problem.hpp"

namespace attitude_planner {

/// One trial step as a step control judges it.
struct StepTrial {
  const ReducedProblem& problem;
  double cost = 0.0;                   ///< C at the current iterate
  double slope = 0.0;                  ///< gᵀδ (< 0)
  const Eigen::VectorXd& delta;        ///< the step δ
  double shift_scale = 0.0;            ///< what the relative shift multiplies
  ReducedProblem::StepVectors* trial;  ///< the full step on entry; the iterate to accept on return
  double* step_length;                 ///< 1 on entry; the step length taken on return
  /// Where the trials' step forms are kept (the accepted one's evaluation reads them); may be null.
  ReducedProblem::StepForms* forms = nullptr;
};

/// The shift after `raises` raises of `from` while H + λI is indefinite (0 → λ_min, then
/// ×growth each: steps fine enough to stay near the least definite λ), by the same products the
/// raises make one at a time.
double raisedShift(double from, int raises, const NewtonParameters& p);

class StepControl {
 public:
  explicit StepControl(const NewtonParameters& parameters) : p_(parameters) {}
  virtual ~StepControl() = default;

  /// A new iteration starts from the shift the last accepted step left.
  void beginIteration() {
    shift_ = carried_;
    growth_ = p_.initial_shift_growth;
  }
  /// λ of the next trial (relative).
  double shift() const { return shift_; }
  /// H + λI was not definite: λ raised `raises` times (raisedShift).
  void raiseForIndefinite(int raises = 1) { shift_ = raisedShift(shift_, raises, p_); }
  /// The step is taken without judging it (a final step, or a decrease below round-off): the
  /// next iteration is pure Newton.
  void acceptUnjudged() { carried_ = 0.0; }
  /// Judges the trial step: true if `trial` (and `step_length`) are to be accepted; otherwise
  /// λ is raised and the step must be recomputed.
  virtual bool judge(const StepTrial& trial) = 0;

 protected:
  /// A rejected step: λ grows by ν, ν itself doubles (Nielsen).
  void reject() {
    shift_ = shift_ == 0.0 ? p_.first_rejection_shift : growth_ * shift_;
    growth_ *= p_.shift_growth_growth;
  }
  /// The shift the next iteration starts from (a negligible one is pure Newton).
  void carry(double next) { carried_ = next < p_.negligible_shift ? 0.0 : next; }

  const NewtonParameters& p_;

 private:
  double shift_ = 0.0;
  double growth_ = 2.0;
  double carried_ = 0.0;
};

class TrustRegionControl : public StepControl {
 public:
  using StepControl::StepControl;
  bool judge(const StepTrial& trial) override;
};

class LineSearchControl : public StepControl {
 public:
  using StepControl::StepControl;
  bool judge(const StepTrial& trial) override;
};

std::unique_ptr<StepControl> makeStepControl(Globalization globalization,
                                             const NewtonParameters& parameters);

}  // namespace attitude_planner
