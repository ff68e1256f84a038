// The seed's printed necessary conditions (seed 000, Theorem 3.1 / eq. (28)) and their corrected
// form, evaluated at a maneuver of the `paper` scheme: a check of the printed equations against
// the optimum our solver finds (docs/results/necessary_conditions.md).
//
// Vector forms used (seed Sec. 4): Ad_g ξ = g ξ, Ad*_g Π = gᵀ Π, [Π, ξ] = Π × ξ, 𝕁(ξ) = J ξ.
#pragma once

#include <vector>

#include "attitude_planner/dynamics/maneuver.hpp"

namespace attitude_planner {

/// Which form of the k = 2..N−2 conditions to evaluate.
enum class SeedConditionForm {
  /// Theorem 3.1 exactly as printed: Ad*_{g_k} = g_kᵀ, inner 1/h on the last bracket, no dexp.
  Printed,
  /// Printed, with Ad*_{g_k} read as Ad*_{g_k⁻¹} = g_k (as in the seed's Sec. 4 restatement)
  /// and the dimensionally inconsistent inner 1/h removed; still without dexp factors.
  PrintedWithTyposFixed,
  /// The exact stationarity conditions of the printed problem: the above with J replaced by
  /// Jr⁻ᵀ(hΩ) J, the dexp factor that the variation δg_k = h g_k δΩ_k (seed eq. (21)) drops.
  Corrected,
};

/// Residual of each condition k = 2..N−2 divided by the largest of its terms' magnitudes
/// (0 = satisfied, O(1) = violated). `maneuver` must come from the `paper` scheme with inertia J.
std::vector<double> seedConditionRelativeResiduals(const Maneuver& maneuver, const Matrix3& J,
                                                   SeedConditionForm form);

/// The printed boundary conditions on τ_1 (first) and τ_{N−1} (second), relative as above.
std::pair<double, double> seedBoundaryConditionRelativeResiduals(const Maneuver& maneuver,
                                                                 const Matrix3& J);

}  // namespace attitude_planner
