// The discrete optimal control problem (seed 000, Problem 3.2) reduced to an unconstrained
// minimization over the interior attitudes R_2..R_{N−2}.
//
// The boundary data fix R_0, R_1 = R_0 F_0 (F_0 from Ω_0), R_{N−1} = R_N F_{N−1}ᵀ (F_{N−1} from
// Ω_{N−1}) and R_N. Each torque is then an explicit function of three consecutive attitudes
// (discrete_scheme.hpp):  τ_k = (μ(F_k) − F_{k−1}ᵀ μ(F_{k−1}))/h,  F_k = R_kᵀ R_{k+1}, and the
// problem is min C = Σ_{k=1}^{N−1} ½|τ_k|² over R_2..R_{N−2} (3(N−3) unknowns: the seed's
// 3(2N−3) unknowns τ, Ω with its 3(N−1) dynamics equations eliminated exactly). ∇C = 0 are the
// discrete necessary conditions (docs/necessary_conditions.md relates them to the seed's eq. 28).
#pragma once

#include <vector>

#include "attitude_planner/banded_matrix.hpp"
#include "attitude_planner/discrete_scheme.hpp"
#include "attitude_planner/maneuver.hpp"
#include "attitude_planner/planner.hpp"

namespace attitude_planner {

class ReducedProblem {
 public:
  /// Fixes R_0, R_1, R_{N−1}, R_N; throws StepTooLarge if a boundary velocity has no step.
  explicit ReducedProblem(const PlanningProblem& problem);

  int steps() const { return N_; }
  /// Number of unknowns, 3(N − 3).
  int unknowns() const { return 3 * (N_ - 3); }
  const DiscreteScheme& scheme() const { return scheme_; }

  /// The current attitudes R_0..R_N.
  const std::vector<Matrix3>& attitudes() const { return R_; }
  /// Replaces the interior attitudes (the fixed four are kept).
  void setInterior(const std::vector<Matrix3>& attitudes);
  /// Interior on the geodesic from R_1 to R_{N−1} (uniform in angle).
  void initializeOnGeodesic();

  /// τ_k, k = 0..N (τ_0 = τ_N = 0), of the attitudes R.
  std::vector<Vector3> torques(const std::vector<Matrix3>& R) const;
  /// C = Σ ½|τ_k|² of the attitudes R.
  double cost(const std::vector<Matrix3>& R) const;

  /// Cost, gradient and exact Hessian of δ ↦ C(R_j exp(δ_j^)) at δ = 0 for the current
  /// attitudes. `gradient_scale` = max|∂τ/∂δ| · max|τ| (for a relative gradient).
  /// With hessian == nullptr only the gradient is formed.
  double evaluate(Eigen::VectorXd* gradient, BandedSymmetricMatrix* hessian,
                  double* gradient_scale) const;

  /// R_j exp(α δ_j^) for the free attitudes; the fixed ones unchanged.
  std::vector<Matrix3> retract(const Eigen::VectorXd& delta, double alpha) const;

  /// Index of R_j's first unknown, or −1 if R_j is fixed.
  int variableIndex(int j) const { return (j >= 2 && j <= N_ - 2) ? 3 * (j - 2) : -1; }

 private:
  int N_;
  DiscreteScheme scheme_;
  std::vector<Matrix3> R_;
};

}  // namespace attitude_planner
