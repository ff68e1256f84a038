// A discrete maneuver: what the planner returns, the tracker replays and the CSV holds.
#pragma once

#include <string>
#include <vector>

#include "attitude_planner/lie/so3.hpp"

namespace attitude_planner {

/// Rows k = 0..N at t_k = k h (docs/DESIGN.md, "Trajectory CSV").
struct Maneuver {
  double time_step = 0.0;                 ///< h [s]
  std::vector<double> time;               ///< t_k [s], k = 0..N
  std::vector<Matrix3> attitude;          ///< R_k, body → world, k = 0..N
  std::vector<Vector3> angular_velocity;  ///< Ω_k [rad/s] body; row N repeats Ω_{N−1}
  std::vector<Vector3> torque;            ///< τ_k [N·m] body; τ_0 = τ_N = 0

  int steps() const { return static_cast<int>(attitude.size()) - 1; }
};

}  // namespace attitude_planner

namespace attitude_planner {

/// The attitudes of `maneuver` (uniform grid on [0, T]) resampled on a uniform grid of `steps`
/// steps over the same interval: on each original step R_i exp(φ(s)), φ a cubic Hermite curve
/// in the Lie algebra with φ(1) = log(R_iᵀ R_{i+1}) and end slopes from central differences,
/// so the result is C¹ and exact at the original nodes that fall on the new grid.
std::vector<Matrix3> resampleAttitudes(const Maneuver& maneuver, int steps);

}  // namespace attitude_planner
