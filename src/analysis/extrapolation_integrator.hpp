// Gragg–Bulirsch–Stoer extrapolation: a fixed-step, high-order (order 2K) integrator for smooth
// ODEs ẋ = f(x), templated on the scalar so that the same code propagates dual numbers (exact
// sensitivities of the discrete flow, for shooting Newton).
//
// One macro step H: the modified midpoint rule with n_j = 2j substeps, j = 1..K, extrapolated to
// substep 0 in powers of (H/n_j)² (Aitken–Neville; Hairer–Nørsett–Wanner I, Sec. II.9). The
// continuous reference (continuous_reference.cpp) and the zero-order-hold replay
// (accuracy.cpp) both integrate with it; their states hold a quaternion, renormalized after
// each macro step (the flow keeps |q| = 1; the extrapolation only to its order).
#pragma once

#include <Eigen/Core>
#include <array>
#include <utility>

namespace attitude_planner {

/// Extrapolation stages K (order 2K = 16). Enough that a macro step of 1/64 of a smooth
/// maneuver's duration is accurate to round-off (test_accuracy.cpp).
constexpr int kExtrapolationStages = 8;

/// One GBS macro step of length H from x; `f(x)` returns ẋ (same type as x).
template <typename Vec, typename F>
Vec extrapolationStep(const F& f, const Vec& x, double H) {
  using S = typename Vec::Scalar;
  std::array<Vec, kExtrapolationStages> previous, current;  // rows of the Neville tableau
  for (int j = 0; j < kExtrapolationStages; ++j) {
    const int n = 2 * (j + 1);
    const S hs = S(H / n);
    // Modified midpoint: z_1 = z_0 + hs f(z_0), z_{m+1} = z_{m−1} + 2 hs f(z_m), smoothed end.
    Vec z_prev = x;
    Vec z = x + hs * f(x);
    for (int m = 1; m < n; ++m) {
      Vec z_next = z_prev + S(2) * hs * f(z);
      z_prev = z;
      z = z_next;
    }
    current[0] = S(0.5) * (z + z_prev + hs * f(z));
    // T_{j,k} = T_{j,k−1} + (T_{j,k−1} − T_{j−1,k−1}) / ((n_j/n_{j−k})² − 1)
    for (int k = 1; k <= j; ++k) {
      const double ratio = double(j + 1) / double(j - k + 1);
      current[k] = current[k - 1] + (current[k - 1] - previous[k - 1]) / S(ratio * ratio - 1.0);
    }
    std::swap(previous, current);
  }
  return previous[kExtrapolationStages - 1];
}

}  // namespace attitude_planner
