#include <limits>

#include "attitude_planner/dynamics/effects.hpp"
#include "attitude_planner/lie/so3.hpp"
#include "attitude_planner/planning/pointing.hpp"
#include "attitude_planner/planning/problem.hpp"

namespace attitude_planner {

namespace {
/// The angle [rad] between R_0 b and d below which they are the same direction in floating point.
constexpr double kPointingRoundOff = 8 * std::numeric_limits<double>::epsilon();
}  // namespace

bool PlanningProblem::zeroManeuverReachesTheEnd() const {
  // A pointing end is reached where R_0 b = d (its final_attitude is no datum of the request), to
  // the round-off of normalizing b and d and of R_0 b: no plan ends closer.
  const bool there = end_condition.pointing()
                         ? pointingError(initial_attitude, end_condition) <= kPointingRoundOff
                         : so3::angleBetween(initial_attitude, final_attitude) == 0.0;
  return initial_velocity.isZero(0.0) && final_velocity.isZero(0.0) && there &&
         direction == RotationDirection::Shortest && extra_revolutions == 0 &&
         (!effects || effects->empty());
}

}  // namespace attitude_planner
