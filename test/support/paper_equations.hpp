// The paper scheme's equations of motion (seed 000, eq. 18) written out, for tests that check a
// maneuver against them independently of the package's own residual (measureStepResidual).
#pragma once

#include <algorithm>

#include "attitude_planner/dynamics/maneuver.hpp"
#include "attitude_planner/lie/so3.hpp"

namespace attitude_planner::test_support {

/// Largest miss of R_{k+1} = R_k exp(h Ω_k^), k = 0..N−1 (Frobenius norm), and of
/// J Ω_k = exp(h Ω_k^)ᵀ (h τ_k + J Ω_{k−1}), k = 1..N−1, relative to max_k |J Ω_k|, on `m`.
inline double paperEquationMiss(const Matrix3& inertia, const Maneuver& m) {
  const int N = m.steps();
  const double h = m.time_step;
  double momentum_scale = 0.0;
  for (int k = 0; k < N; ++k) {
    momentum_scale = std::max(momentum_scale, (inertia * m.angular_velocity[k]).norm());
  }
  double worst = 0.0;
  for (int k = 0; k < N; ++k) {
    const Matrix3 step = so3::exp(Vector3(h * m.angular_velocity[k]));
    worst = std::max(worst, (m.attitude[k] * step - m.attitude[k + 1]).norm());
    if (k == 0) continue;
    const Vector3 carried =
        step.transpose() * (h * m.torque[k] + inertia * m.angular_velocity[k - 1]);
    worst = std::max(worst, (inertia * m.angular_velocity[k] - carried).norm() / momentum_scale);
  }
  return worst;
}

}  // namespace attitude_planner::test_support
