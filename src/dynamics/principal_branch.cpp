// Why short steps are on the principal branch. Both momentum maps have h ∂μ/∂ε = (J + E) G with
// det G > 0 and E = 0 at ω = 0 (DiscreteScheme::momentumJacobian):
// - variational, second_order, fourth_order: μ = (F J_d − J_d Fᵀ)^∨/h, h ∂μ/∂ε = (tr(M) I − M) F
//   with M = F J_d, and tr(J_d) I − J_d = J, so E = tr((F − I) J_d) I − (F − I) J_d and
//   ‖E‖₂ ≤ ‖F − I‖₂ (‖J_d‖_* + ‖J_d‖₂) ≤ θ (‖J_d‖_* + ‖J_d‖₂)  (|tr(AB)| ≤ ‖A‖₂‖B‖_*,
//   ‖F − I‖₂ = 2 sin(θ/2) ≤ θ);
// - paper: μ = F J ω/h, h ∂μ/∂ε = F (J Jr⁻¹(ω) − (Jω)^), so E = J (½ ω^ + c ω^²) − (Jω)^ and
//   ‖E‖₂ ≤ λ_max(J) (3θ/2 + c θ²) ≤ 1.6 θ λ_max(J) for θ ≤ 1 (c(θ²) ≤ 0.085 there).
// Both bounds grow with θ, so along the segment s ω (0 ≤ s ≤ 1) ‖E‖₂ ≤ λ_min(J)/2 where it holds
// at ω: J + E stays nonsingular with σ_min ≥ λ_min(J)/2, and its determinant keeps the sign it
// has at s = 0, det J > 0.
#include "dynamics/principal_branch.hpp"

#include <algorithm>

#include <Eigen/Eigenvalues>

namespace attitude_planner {

double principalBranchRadius(const DiscreteScheme& scheme) {
  const Matrix3& J = scheme.inertia();
  const Vector3 moments =
      Eigen::SelfAdjointEigenSolver<Matrix3>(J, Eigen::EigenvaluesOnly).eigenvalues();  // ascending
  const double least = moments(0), largest = moments(2);
  if (!(least > 0.0) || largest > kPrincipalBranchConditionLimit * least) return 0.0;
  const double margin = 0.5 * least;  // ‖E‖₂ allowed
  switch (scheme.kind()) {
    case SchemeKind::Paper:
      return std::min(1.0, margin / (1.6 * largest));
    case SchemeKind::Variational:
    case SchemeKind::SecondOrder:
    case SchemeKind::FourthOrder: {
      // J_d = ½ tr(J) I − J: its eigenvalues from J's
      const Vector3 nonstandard = Vector3::Constant(0.5 * moments.sum()) - moments;
      const double nuclear = nonstandard.cwiseAbs().sum();
      const double spectral = nonstandard.cwiseAbs().maxCoeff();
      return margin / (nuclear + spectral);
    }
  }
  return 0.0;  // a scheme without a bound here: every step takes the determinant test
}

}  // namespace attitude_planner
