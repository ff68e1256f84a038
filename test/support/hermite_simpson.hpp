// The peer a user would pick instead of our discrete schemes, a standard direct
// collocation of the *continuous* problem (seed 000, Problem 2.2), as a plain NLP (no solver
// here: studies/frontier_study.cpp hands it to IPOPT; test/unit/test_hermite_simpson.cpp checks
// its derivatives against finite differences).
//
//   minimize ½∫₀ᵀ|τ|²dt   s.t.   q̇ = ½ q ⊗ (0, Ω),   J Ω̇ = (JΩ) × Ω + τ,
//                                q(0), Ω(0), Ω(T) given,   q(T) = ±q_T.
//
// Hermite–Simpson collocation, separated form: mesh t_k = k h (h = T/N, k = 0..N) and midpoints
// t_k + h/2; every one of the 2N + 1 points p (node k is p = 2k, the midpoint of interval k is
// p = 2k + 1) carries a state x_p = (q_p, Ω_p) ∈ R⁷ and a control τ_p ∈ R³, laid out as
// [q (4), Ω (3), τ (3)] at 10 p. Per interval k (points L = 2k, M = 2k + 1, R = 2k + 2), with
// f = (½ q ⊗ (0, Ω), J⁻¹((JΩ) × Ω + τ)):
//   interpolation  x_M − ½(x_L + x_R) − h/8 (f_L − f_R) = 0          (7 rows, 14k…14k+6)
//   collocation    x_R − x_L − h/6 (f_L + 4 f_M + f_R) = 0           (7 rows, 14k+7…14k+13)
// the terminal attitude vec(q̄_T ⊗ q_N) = 0 (3 rows, 14N…14N+2: q_N ∥ q_T, either sign), and the
// objective by Simpson's rule, Σ_k h/6 (½|τ_L|² + 4·½|τ_M|² + ½|τ_R|²) (consistent with HS).
// q_0, Ω_0 and Ω_N are fixed through equal variable bounds.
//
// No unit-norm constraints at the nodes: the continuous kinematics keep |q| constant and HS keeps
// it to O(h⁴) (exactly while Ω is constant over an interval: the stability function of Lobatto
// IIIA is the (2,2) Padé approximant), and the 4 collocation rows already determine q_{k+1};
// adding |q_k|² = 1 would over-determine the state and make the optimizer bend the torques to
// cancel the method's norm error. The terminal condition therefore fixes only the direction of
// q_N (3 rows, full rank at q_N ∥ q_T) and attitudes are read as q/|q|.
//
// Exact derivatives, hand-derived (f is polynomial in (q, Ω, τ)): the Jacobian blocks are
// a·I + b·∂f/∂(x, τ) per point; the Hessian of the Lagrangian is, per point p, ∇²(ν_pᵀ f) with
// ν_p the multipliers weighted by the point's coefficients b in the rows that touch it:
//   ∂²/∂Ω_j ∂q = ½ R((0, e_j))ᵀ ν_q,   ∂²/∂Ω² = ŵ J − J ŵ (w = J⁻¹ ν_Ω),   ∂²/∂τ² = σ·weight.
#pragma once

#include <vector>

#include "attitude_planner/planning/problem.hpp"

namespace attitude_planner {
namespace peers {

class HermiteSimpsonTranscription {
 public:
  /// Uses the problem's inertia, duration, steps (N mesh intervals) and boundary data.
  explicit HermiteSimpsonTranscription(const PlanningProblem& problem);

  int intervals() const { return N_; }
  int points() const { return 2 * N_ + 1; }
  int variables() const { return 10 * points(); }
  int constraints() const { return 14 * N_ + 3; }
  /// Offsets of point p's q (4), Ω (3) and τ (3).
  static int qIndex(int p) { return 10 * p; }
  static int omegaIndex(int p) { return 10 * p + 4; }
  static int torqueIndex(int p) { return 10 * p + 7; }
  /// t_p = p h/2 [s].
  double time(int p) const { return 0.5 * h_ * p; }

  /// Variable bounds (±1e19 = none; q_0, Ω_0, Ω_N fixed). Constraints are all equalities (0).
  void bounds(double* lower, double* upper) const;
  /// The geodesic start: q(t) = q_0 ⊗ e(t φ/T), φ = log(R_0ᵀ R_T) (the constant-rate rotation our
  /// Newton solver also starts from), Ω = φ/T between the ends (the data at the ends), τ the
  /// torque that holds that rate, −(JΩ) × Ω.
  void startingPoint(double* x) const;

  double objective(const double* x) const;
  void objectiveGradient(const double* x, double* gradient) const;
  void constraintValues(const double* x, double* values) const;

  /// Sparse Jacobian: (row, column) pattern, fixed; values in the same order.
  const std::vector<int>& jacobianRows() const { return jac_rows_; }
  const std::vector<int>& jacobianColumns() const { return jac_cols_; }
  void jacobianValues(const double* x, double* values) const;

  /// Sparse Hessian of σ f + Σ λ_i c_i, lower triangle (row ≥ column), fixed pattern.
  const std::vector<int>& hessianRows() const { return hess_rows_; }
  const std::vector<int>& hessianColumns() const { return hess_cols_; }
  void hessianValues(const double* x, double sigma, const double* lambda, double* values) const;

  /// τ at the points p = 0..2N (nodes at even p) [N·m].
  std::vector<Vector3> torques(const double* x) const;
  /// The Simpson weight of |τ_p|²/2 in the objective: h/6 (end nodes), h/3 (interior nodes),
  /// 2h/3 (midpoints).
  double weight(int p) const;

 private:
  using Vector4 = Eigen::Matrix<double, 4, 1>;
  using Vector7 = Eigen::Matrix<double, 7, 1>;
  Vector7 dynamics(const double* x, int p) const;
  /// ∂f/∂(q, Ω, τ) at point p (7 × 10).
  Eigen::Matrix<double, 7, 10> dynamicsJacobian(const double* x, int p) const;
  /// Appends one block's pattern: rows r0..r0+6 against point p; `full`: the ∂f pattern
  /// (q rows × (q, Ω) and Ω rows × (Ω, τ)), else the diagonal of the state.
  void appendBlock(int r0, int p, bool full);

  int N_;
  double h_;
  Matrix3 J_, J_inverse_;
  Vector4 q0_, qT_;
  Vector3 omega0_, omegaT_;
  std::vector<int> jac_rows_, jac_cols_, hess_rows_, hess_cols_;
};

}  // namespace peers
}  // namespace attitude_planner
