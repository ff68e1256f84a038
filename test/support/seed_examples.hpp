// The seed's two examples as problems, and the least-squares order fit the accuracy tests share.
#pragma once

#include <cmath>
#include <vector>

#include "attitude_planner/planning/problem.hpp"
#include "support/robustness_cases.hpp"

namespace attitude_planner::test_support {

/// scenes/rest_to_rest.yaml (π/3 about x in 12.8 s) or slew_up.yaml (π/6, arriving at
/// (0.3, 0.2, 0.3) rad/s), with the seed's inertia, in `scheme`.
inline PlanningProblem seedProblem(bool slew_up, SchemeKind scheme = SchemeKind::Paper) {
  PlanningProblem p;
  p.inertia = robustness::seedInertia();
  p.allow_nonphysical_inertia = true;
  p.duration = 12.8;
  p.final_attitude = so3::fromAxisAngle(Vector3::UnitX(), slew_up ? M_PI / 6 : M_PI / 3);
  if (slew_up) p.final_velocity = Vector3(0.3, 0.2, 0.3);
  p.scheme = scheme;
  return p;
}

/// Least-squares slope of −log(error) against log(N).
inline double fittedOrder(const std::vector<int>& N, const std::vector<double>& error) {
  double sx = 0, sy = 0, sxx = 0, sxy = 0;
  const double n = static_cast<double>(N.size());
  for (size_t i = 0; i < N.size(); ++i) {
    const double x = std::log(double(N[i])), y = std::log(error[i]);
    sx += x;
    sy += y;
    sxx += x * x;
    sxy += x * y;
  }
  return -(n * sxy - sx * sy) / (n * sxx - sx * sx);
}

}  // namespace attitude_planner::test_support
