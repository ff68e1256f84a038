#include "attitude_planner/dynamics/maneuver.hpp"

#include <cstdio>
#include <fstream>
#include <memory>
#include <sstream>

#include "attitude_planner/errors.hpp"

namespace attitude_planner {}  // namespace attitude_planner

namespace attitude_planner {

std::vector<Matrix3> resampleAttitudes(const Maneuver& m, int steps) {
  const int n = m.steps();
  if (n < 1 || steps < 1) throw InvalidInput("resampleAttitudes: need at least one step");
  // Δ_i = log(R_iᵀ R_{i+1}); the body velocity (× step) at node i, in frame R_i: ½(Δ_{i−1} + Δ_i)
  // (a step's rotation vector is the same in both of its end frames).
  std::vector<Vector3> delta(n);
  for (int i = 0; i < n; ++i)
    delta[i] = so3::log(Matrix3(m.attitude[i].transpose() * m.attitude[i + 1]));
  const auto slope = [&](int i) {
    if (i <= 0) return delta[0];
    if (i >= n) return delta[n - 1];
    return Vector3(0.5 * (delta[i - 1] + delta[i]));
  };
  std::vector<Matrix3> out(steps + 1);
  for (int j = 0; j <= steps; ++j) {
    const double x = double(j) * n / steps;  // position in original steps
    int i = std::min(static_cast<int>(x), n - 1);
    const double s = x - i;
    // Hermite basis on [0, 1]: φ(0) = 0, φ'(0) = v_i, φ(1) = Δ_i, φ'(1) = v_{i+1} (frame R_i:
    // F_i leaves Δ_i fixed, and the slope at i+1 is rotated back by F_i).
    const Matrix3 F = so3::exp(delta[i]);
    const Vector3 v0 = slope(i), v1 = F * slope(i + 1);
    const double h10 = s * s * s - 2 * s * s + s, h01 = -2 * s * s * s + 3 * s * s,
                 h11 = s * s * s - s * s;
    out[j] = m.attitude[i] * so3::exp(Vector3(h10 * v0 + h01 * delta[i] + h11 * v1));
  }
  return out;
}

}  // namespace attitude_planner
