// Internal to the interior-point solver (constrained_system.hpp) and its tests: the node
// constraints that are not functions of a torque, with exact first and second derivatives under
// the reduced problem's retraction R_j → R_j exp(δ_j^) (reduced_problem.hpp).
#pragma once

#include <Eigen/Core>

#include "attitude_planner/dynamics/discrete_scheme.hpp"

namespace attitude_planner {

/// φ = ½|Ω(F)|² of one step F = exp(ω^) = R_kᵀR_{k+1} (Ω the scheme's reported velocity:
/// paper log(F)/h, variational J⁻¹μ(F)), as a function of (δ_k, δ_{k+1}) through
/// F → exp(−δ_k^) F exp(δ_{k+1}^).
struct AngularRateTerms {
  double half_squared_rate = 0.0;        ///< φ [rad²/s²]
  Eigen::Matrix<double, 6, 1> gradient;  ///< ∂φ/∂(δ_k, δ_{k+1})
  Eigen::Matrix<double, 6, 6> hessian;   ///< ∂²φ/∂(δ_k, δ_{k+1})², symmetric
};
AngularRateTerms angularRateTerms(const DiscreteScheme& scheme, const Vector3& omega);

/// p = sᵀ R exp(δ^) b (the cosine of the angle between R b and s, b and s unit) as a function
/// of δ at δ = 0.
struct PointingTerms {
  double cosine = 0.0;  ///< p
  Vector3 gradient;     ///< ∂p/∂δ = b × Rᵀs
  Matrix3 hessian;      ///< ∂²p/∂δ² = ½(v bᵀ + b vᵀ) − (v·b) I, v = Rᵀs
};
PointingTerms pointingTerms(const Matrix3& R, const Vector3& body_axis,
                            const Vector3& world_direction);

/// The slacks of one elastic constraint c(x) + v − s = 0, s, v > 0, that minimize the barrier
/// term ρ v − μ ln s − μ ln v for a given c (closed form of μ/s + μ/v = ρ, s − v = c; both
/// computed without cancellation). ψ = ρ v − μ ln s − μ ln v is then a smooth function of c
/// (ψ' = −μ/s, ψ'' = μ/(s² + v²)): the merit function of the solver.
struct ElasticSlacks {
  double s = 0.0;  ///< slack of c ≥ 0 (s − v = c)
  double v = 0.0;  ///< elastic violation, ≈ max(0, −c) as μ → 0
  double psi = 0.0;
};
ElasticSlacks elasticSlacks(double c, double mu, double rho);

}  // namespace attitude_planner
