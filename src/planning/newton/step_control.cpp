#include "planning/newton/step_control.hpp"

#include <algorithm>
#include <cmath>

namespace attitude_planner {

double raisedShift(double from, int raises, const NewtonParameters& p) {
  double shift = from;
  for (int i = 0; i < raises; ++i) {
    shift = shift == 0.0 ? p.smallest_shift : p.indefinite_shift_growth * shift;
  }
  return shift;
}

bool TrustRegionControl::judge(const StepTrial& t) {
  const double trial_cost = t.problem.cost(*t.trial, t.forms);
  // Model m(δ) = C + gᵀδ + ½δᵀHδ with (H + λI)δ = −g: C − m(δ) = ½(−gᵀδ + λ|δ|²).
  const double predicted = 0.5 * (-t.slope + shift() * t.shift_scale * t.delta.squaredNorm());
  const double ratio = (t.cost - trial_cost) / predicted;
  if (std::isfinite(trial_cost) && ratio >= p_.accept_ratio) {
    const double s = 2.0 * ratio - 1.0;
    carry(shift() * std::max(p_.shift_min_factor, 1.0 - s * s * s));
    return true;
  }
  reject();
  return false;
}

bool LineSearchControl::judge(const StepTrial& t) {
  bool accepted = false;
  for (int halving = 0; halving < p_.max_halvings && !accepted; ++halving) {
    if (halving > 0) *t.trial = t.problem.retract(t.delta, *t.step_length *= p_.backtrack_factor);
    const double trial_cost = t.problem.cost(*t.trial, t.forms);
    accepted =
        std::isfinite(trial_cost) && trial_cost <= t.cost + p_.armijo * *t.step_length * t.slope;
  }
  // The next iteration starts from a fraction of this shift (as IPOPT's inertia correction).
  carry(shift() * p_.line_search_shift_carry);
  if (!accepted) {
    *t.step_length = 1.0;
    reject();
  }
  return accepted;
}

std::unique_ptr<StepControl> makeStepControl(Globalization globalization,
                                             const NewtonParameters& parameters) {
  if (globalization == Globalization::LineSearch) {
    return std::make_unique<LineSearchControl>(parameters);
  }
  return std::make_unique<TrustRegionControl>(parameters);
}

}  // namespace attitude_planner
