// A proven lower bound on the duration of any plan of a problem, from the bounds in force: the
// verdicts of bounded requests rest on it where it decides ("infeasible: any plan needs T >= X,
// proven"), so that no local minimum-time plan's duration is ever worded as a requirement.
//
// The argument (continuous time; the transcriptions below): the spatial angular momentum
// π = R J Ω changes only by the control torque, π̇ = R τ (no effects), so |π̇| ≤ a, the largest
// torque magnitude the bounds allow (the norm bound, or the corner of the box). Hence
//   |π(t)| ≤ f(t) = min(|π₀| + a t, |π_T| + a (T − t)),
// the body rate |Ω| = |J⁻¹Rᵀπ| ≤ |π| / λ_min(J), and, with a rate limit w, |Ω| ≤ w as well. The
// path from R₀ to R_N has length ∫|Ω| dt ≥ θ, the angle of R₀ᵀR_N (the bi-invariant distance), so
//   θ ≤ g(T) = ∫₀ᵀ min(w, f(t)/λ_min) dt,   and   a T ≥ |π_T − π₀|.
// g increases with T; the least T meeting both is T_c. On the grid (paper: π_k = π_{k−1} +
// h R_k τ_k, step angle h|Ω_k|) each step's term is bounded by the integral over its step, so
// T_c bounds the discrete problem too; the schemes with end torques (half-weighted end impulses)
// and the variational map (step angle asin of its momentum) differ from it by O(h), covered by
// the margin of discreteDurationLowerBound.
#pragma once

#include <string>

#include "attitude_planner/planning/problem.hpp"

namespace attitude_planner {

/// What the torque bounds in force allow [N m], +∞ where nothing bounds the torque. Two figures
/// of one reading of the bounds: the largest |τ| any allowed torque has (the norm bound, or the
/// box's corner), which the proof of T_c needs, and the least torque available about every axis
/// (the smallest box side, or the norm bound), which duration guesses need.
struct TorqueAuthority {
  double largest_magnitude;
  double smallest_about_any_axis;
};
TorqueAuthority torqueAuthority(const PlanningProblem& problem);

/// T_c and what proves it.
struct DurationLowerBound {
  double seconds = 0.0;  ///< T_c [s]: no plan of the continuous problem is shorter (0: no bound)
  /// How it is proven, for messages: "momentum (|tau| <= a ...)". Empty where no bound applies
  /// (no torque or rate bound, or effects: their torques are not bounded by the request).
  std::string basis;
  /// The figures the proof used, rendered in `basis`: the rate limit w [rad/s] and the largest
  /// torque magnitude a [N m] the bounds allow (0 where none bounds it, or no bound applies).
  double rate_limit = 0.0;
  double torque_limit = 0.0;
};

/// The bound T_c for `problem` (its boundary data, inertia, torque bounds and rate limits).
DurationLowerBound durationLowerBound(const PlanningProblem& problem);

/// T_c / (1 + kDiscreteMargin / N): what a grid of `steps` steps is held to (the O(h) of the
/// schemes with end torques and of the variational map, see above). Tested against every
/// scheme's minimum time on random problems (test_duration_bound).
double discreteDurationLowerBound(const DurationLowerBound& bound, int steps);
/// The same for `problem`'s own bound on its own grid (0: no bound applies).
double discreteDurationLowerBound(const PlanningProblem& problem);
constexpr double kDiscreteMargin = 4.0;

}  // namespace attitude_planner
