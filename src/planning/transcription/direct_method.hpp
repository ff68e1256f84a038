// The direct (shooting) formulation used by the NLopt cross-check: the torques τ_1..τ_{N−1} are
// the unknowns, the state follows from simulate(), and the terminal state is constrained.
//
//   minimize  Σ_{k=1}^{N−1} ½|τ_k|²   subject to   log(R_N*ᵀ R_N(τ)) = 0,  Ω_{N−1}(τ) − Ω*_{N−1} =
//   0.
//
// Exact constraint gradients come from the tangent of the step map (right perturbations):
//   μ(F_k) = G(F_{k−1}) + h τ_k,  G(F) = Fᵀ μ(F)
//   ⇒ δF_k = dμ(F_k)⁻¹ (dG(F_{k−1}) δF_{k−1} + h δτ_k),   dG(F) = (Fᵀμ(F))^ + Fᵀ dμ(F),
//   δθ_{k+1} = F_kᵀ δθ_k + δF_k   (R_{k+1} = R_k F_k),   δF_0 = δθ_1 = 0,
// accumulated backwards (adjoint), O(N) per Jacobian.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "attitude_planner/dynamics/discrete_scheme.hpp"
#include "attitude_planner/dynamics/maneuver.hpp"
#include "attitude_planner/planning/problem.hpp"
#include "attitude_planner/planning/result.hpp"

namespace attitude_planner {

/// Number of terminal equality constraints: 3 attitude [rad] + 3 velocity [rad/s].
constexpr int kTerminalConstraints = 6;

/// Terminal constraints at one torque sequence, and optionally their Jacobian.
struct TerminalConstraints {
  /// (log(R_N*ᵀ R_N) [rad], Ω_{N−1} − Ω*_{N−1} [rad/s]).
  Eigen::Matrix<double, kTerminalConstraints, 1> value;
  /// d value / d(τ_1, ..., τ_{N−1}), 6 × 3(N−1) [rad/(N·m), rad/(s·N·m)]; empty if not asked.
  Eigen::MatrixXd jacobian;
  Maneuver maneuver;  ///< the simulated trajectory
};

/// τ_0..τ_N [N·m] (zero at both ends) from the stacked unknowns x = (τ_1, ..., τ_{N−1}).
std::vector<Vector3> torqueSequenceFromUnknowns(const Eigen::VectorXd& x);

/// The stacked unknowns (τ_1, ..., τ_{N−1}) [N·m] of a torque sequence τ_0..τ_N.
Eigen::VectorXd unknownsFromTorqueSequence(const std::vector<Vector3>& torque);

/// Simulates x = (τ_1..τ_{N−1}) from the problem's initial state and evaluates the terminal
/// constraints (and their exact Jacobian if `with_jacobian`). Throws StepTooLarge if a step fails.
TerminalConstraints evaluateTerminalConstraints(const PlanningProblem& problem,
                                                const Eigen::VectorXd& x, bool with_jacobian);

/// dG/dε of the carried momentum G(F) = Fᵀ μ(F) under F → F exp(ε^) [N·m·s/rad]:
/// (Fᵀμ(F))^ + Fᵀ dμ(F).
Matrix3 carriedMomentumJacobian(const DiscreteScheme& scheme, const Matrix3& F);

/// First-order optimality residual of min ½|x|² s.t. c(x) = 0 at x: the part of ∇f = x outside
/// the row space of the constraint Jacobian, x − Cᵀ(CCᵀ)⁻¹C x (least-squares multipliers) [N·m].
Eigen::VectorXd stationarityResidual(const Eigen::VectorXd& x, const Eigen::MatrixXd& jacobian);

}  // namespace attitude_planner
