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

/// The fixed-attitude optimum (planManeuver, classes enumerated) over the twist ψ of `pointing`'s
/// end condition: every 5° (`sweep` receives the 72 costs, NaN where a solve did not converge),
/// the best bracket refined by golden section to |Δψ| < 1e-7 rad.
struct TwistSweep {
  std::vector<double> twists, costs;
  double best = 0.0, best_twist = 0.0;  ///< the refined minimum
  double worst = 0.0;                   ///< the sweep's largest converged cost
};
TwistSweep sweepTwist(const PlanningProblem& pointing);

}  // namespace attitude_planner::test_support
