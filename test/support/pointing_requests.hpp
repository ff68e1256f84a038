// Seeded random pointing requests and the reference a pointing answer is judged against: the best
// fixed-attitude optimum over the twist, found by a 5° sweep refined by golden section (the test
// and studies/pointing_study share them).
#pragma once

#include <vector>

#include "attitude_planner/planner.hpp"

namespace attitude_planner::test_support {

/// A seeded random pointing request: random SPD physical inertia (moments in [1, 2] kg m², random
/// axes), random b, d and R_0, T in [8, 12] s; `spinning`: |Ω_0| = 0.2, |Ω(T)| = 0.1 rad/s in
/// random directions, else rest to rest.
PlanningProblem randomPointingRequest(unsigned seed, int steps, bool spinning, SchemeKind scheme);

/// What binds in a constrained pointing request (randomConstrainedPointingRequest).
enum class PointingBinding {
  KeepOut,     ///< a keep-out cone about the boresight b, between R_0 b and the target d
  TorqueBox,   ///< |τ_i| ≤ 0.7 × the unconstrained pointing answer's largest |τ_i|
  TorqueNorm,  ///< |τ| ≤ 0.7 × the unconstrained pointing answer's largest |τ|
};

/// randomPointingRequest (seed, seed + 1000, … until R_0 b is 0.8 … 2.6 rad from d, for a cone)
/// with one constraint that binds: the keep-out cone's world direction is the bisector of R_0 b
/// and d, its half angle 0.35 of their angle (the target and the start clear of it); the torque
/// bounds are 0.7 of the unconstrained pointing answer's largest torque.
PlanningProblem randomConstrainedPointingRequest(unsigned seed, int steps, bool spinning,
                                                 SchemeKind scheme, PointingBinding binding);

/// A seeded random minimum-time pointing request on Betts's body (scenes/min_time_betts.yaml: J =
/// diag(5621, 4547, 2364) kg m², |τ_i| ≤ 50 N m), rest to rest: random b, d and R_0.
PlanningProblem randomBettsPointingRequest(unsigned seed, int steps, SchemeKind scheme);

/// randomBettsPointingRequest (seed, seed + 1000, … until R_0 b is 0.8 … 2.6 rad from d) with a
/// keep-out cone on the boresight about the bisector of R_0 b and d (half angle 0.35 of their
/// angle) and a rate limit of 0.7 × the largest rate of that request's answer without them.
PlanningProblem randomBettsConstrainedPointingRequest(unsigned seed, int steps, SchemeKind scheme);

/// The fixed-attitude optimum (planManeuver, classes enumerated) over the twist ψ of `pointing`'s
/// end condition: every 5° (`sweep` receives the 72 costs, NaN where a solve did not converge),
/// the best bracket refined by golden section to |Δψ| < 1e-7 rad. The cost; with objective
/// minimum time, T*. A twist whose R_N a cone excludes has no plan (+∞, NaN in `costs`).
struct TwistSweep {
  std::vector<double> twists, costs;
  double best = 0.0, best_twist = 0.0;  ///< the refined minimum
  double worst = 0.0;                   ///< the sweep's largest converged cost
};
TwistSweep sweepTwist(const PlanningProblem& pointing);

}  // namespace attitude_planner::test_support
