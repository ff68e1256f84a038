// Shared pieces of the rostest gtests: the seed request (seed 000, example 1) at small N.
#pragma once

#include <cmath>

#include "attitude_planner/ros/conversions.hpp"

namespace attitude_planner {
namespace ros_testing {

/// Seed 000's inertia J [kg·m²], row-major.
inline boost::array<double, 9> seedInertia() {
  return {13.25, -7.80, -11.40, -7.80, 16.25, 4.71, -11.40, 4.71, 18.37};
}

/// Fills a service request / action goal with the seed's rest-to-rest slew by `angle` [rad]
/// about body x in T = 12.8 s and `steps` steps.
template <class Request>
void fillSeedRequest(Request* r, int steps = 32, double angle = M_PI / 3) {
  r->inertia = seedInertia();
  r->allow_nonphysical_inertia = true;  // the seed's J violates J1 + J2 >= J3
  r->initial_attitude.w = 1.0;
  r->final_attitude = ros_conversions::attitudeToMsg(so3::fromAxisAngle(Vector3::UnitX(), angle));
  r->duration = 12.8;
  r->steps = steps;
}

}  // namespace ros_testing
}  // namespace attitude_planner
