// The discrete optimal control problem (seed 000, Problem 3.2) reduced to an unconstrained
// minimization over the interior attitudes R_2..R_{N−2}.
//
// The boundary data fix R_0, R_1 = R_0 F_0 (F_0 from Ω_0), R_{N−1} = R_N F_{N−1}ᵀ (F_{N−1} from
// Ω_{N−1}) and R_N. Each torque is then an explicit function of three consecutive attitudes
// (discrete_scheme.hpp):  τ_k = (μ(F_k) − F_{k−1}ᵀ μ(F_{k−1}))/h,  F_k = R_kᵀ R_{k+1}, and the
// problem is min C = Σ_{k=1}^{N−1} ½|τ_k|² over R_2..R_{N−2} (3(N−3) unknowns: the seed's
// 3(2N−3) unknowns τ, Ω with its 3(N−1) dynamics equations eliminated exactly). ∇C = 0 are the
// discrete necessary conditions (docs/results/necessary_conditions.md relates them to the seed's
// eq. 28).
//
// With end torques (second_order, discrete_scheme.hpp) R_1 and R_{N−1} are free too, τ_0 and
// τ_N are functions of F_0 and F_{N−1} (the boundary velocities enter through the Legendre
// transforms at the end nodes), and the cost is the trapezoidal Σ ½ w_k |τ_k|², k = 0..N.
//
// The iterate is stored as the steps' rotation vectors ω_k = log F_k, not as attitudes: torques
// are second differences of the attitude, and absolute attitudes would lose them to round-off
// (relative error eps·N² instead of eps·N).
#pragma once

#include <functional>
#include <vector>

#include "attitude_planner/dynamics/discrete_scheme.hpp"
#include "attitude_planner/dynamics/maneuver.hpp"
#include "attitude_planner/planning/problem.hpp"
#include "attitude_planner/planning/result.hpp"
#include "planning/linalg/banded_matrix.hpp"
#include "planning/transcription/objective.hpp"

namespace attitude_planner {

class ReducedProblem {
 public:
  /// Rotation vectors ω_k of the steps F_k = exp(ω_k^), k = 0..N−1 (ω_0, ω_{N−1} fixed).
  using StepVectors = std::vector<Vector3>;

  /// What one torque contributes to the Newton system: the residual r_k = √w_k τ_k of the cost
  /// Σ ½ |r_k|² (w_k = 1 but at the end nodes of a scheme with end torques).
  struct Stencil {
    int k = 0;                             ///< torque index, 1..N−1 (0..N with end torques)
    Vector3 tau;                           ///< r_k = √w_k τ_k [N m]
    Eigen::Matrix<double, 3, 9> jacobian;  ///< ∂τ_k/∂(δ_{k−1}, δ_k, δ_{k+1})
    /// sym(Σ_i τ_{k,i} ∂jacobian_i/∂δ): with jacobianᵀ·jacobian, the exact Hessian block.
    Eigen::Matrix<double, 9, 9> second;
  };

  /// Fixes the boundary steps and starts on the geodesic from R_1 to R_{N−1}; throws
  /// StepTooLarge if a boundary velocity has no step.
  explicit ReducedProblem(const PlanningProblem& problem);

  /// Half bandwidth of the Newton systems in the unknowns δ (the one owner of this fact): a torque
  /// τ_k couples δ_{k−1}, δ_k, δ_{k+1}, 9 unknowns, so a row reaches 8 others on either side.
  static constexpr int kHalfBandwidth = 8;

  int steps() const { return N_; }
  /// Number of unknowns, 3(N − 3) (3(N − 1) with end torques).
  int unknowns() const { return 3 * (last_free_ - first_free_ + 1); }
  /// The free attitudes are R_j, j = firstFreeNode()..lastFreeNode() (2..N−2; 1..N−1 with end
  /// torques); the stencils run over k = firstFreeNode() − 1 .. lastFreeNode() + 1.
  int firstFreeNode() const { return first_free_; }
  int lastFreeNode() const { return last_free_; }
  const DiscreteScheme& scheme() const { return scheme_; }

  const StepVectors& current() const { return steps_; }
  void setCurrent(const StepVectors& steps) { steps_ = steps; }
  /// log(R_1ᵀ R_{N−1}): the principal rotation vector between the two fixed inner attitudes.
  Vector3 principalSpan() const { return principal_span_; }
  /// Interior on the constant-rate rotation by `span` from R_1 (span ≡ principalSpan() modulo
  /// whole turns about its axis, so that R_{N−1} is still reached).
  void initializeAlong(const Vector3& span);
  /// Interior on R_1 exp(φ(s)), s ∈ [0, 1] from R_1 to R_{N−1}: φ the cubic Hermite curve with
  /// φ(0) = 0, φ(1) = span, φ'(0) = start_slope, φ'(1) = end_slope (body rotation per unit s,
  /// frame of R_1). Matches boundary velocities, so spinning ends start the solve spinning.
  void initializeHermite(const Vector3& span, const Vector3& start_slope, const Vector3& end_slope);
  /// Interior from the attitudes of a maneuver with the same N (a warm start).
  void setInteriorFromAttitudes(const std::vector<Matrix3>& attitudes);
  /// Interior from the steps of this problem's solution on a coarser grid (grid continuation):
  /// the coarse rates ω^c_k/h_c, interpolated in time by a C¹ cubic, times h; then a smooth
  /// R_j → R_j exp(φ_j^) closes the small gap left at R_{N−1}. Composed in quaternions, so small
  /// steps keep their relative precision. Its torques differ from the fine solution's by about
  /// the coarse solution's own discretization error (resampling attitudes instead left O(1)
  /// torque jumps at the coarse nodes and the ends).
  /// With `coarser` (the solution on a still coarser grid) the two are extrapolated to this h.
  void initializeFromCoarser(const StepVectors& coarse, const StepVectors* coarser = nullptr);
  /// Interior from a guess of every step (N of them; the fixed boundary steps are kept): the
  /// free steps are taken from `guess` and the gap they leave at R_{N−1} is closed as in
  /// initializeFromCoarser.
  void initializeFromSteps(const StepVectors& guess);

  /// R_0..R_N of the steps (products from R_0).
  std::vector<Matrix3> attitudes(const StepVectors& steps) const;
  /// τ_k, k = 0..N (τ_0 = τ_N = 0 unless the scheme has end torques).
  std::vector<Vector3> torques(const StepVectors& steps) const;
  /// The planned maneuver itself: R_k = R_0 F_0 ⋯ F_{k−1}, Ω_k the scheme's reported velocity
  /// (paper, variational: of step k, row N repeating Ω_{N−1}; second_order: the node velocity
  /// J⁻¹Π_k, k = 0..N), τ_k as torques(); k = 0..N on t_k = k h.
  Maneuver maneuver(const StepVectors& steps) const;
  /// C = Σ ½ w_k |τ_k|² (DiscreteScheme::torqueWeight).
  double cost(const StepVectors& steps) const;

  /// What a pass over steps forms of each step alone, exp(ω^), exp(ω^) − I and μ (the values
  /// evaluate's own pass would form): kept by cost(steps, keep), read by evaluate(…, known) when
  /// its iterate is those steps (the trial a step control judged and accepted). Held by the
  /// caller: the problem's const methods keep no state.
  struct StepForms {
    StepVectors steps;          ///< the ω the forms below belong to
    double time_step = 0.0;     ///< and the h (μ reads it)
    std::vector<Matrix3> F, E;  ///< exp(ω^), exp(ω^) − I
    StepVectors mu;             ///< μ(F)
  };
  /// cost(steps), keeping the steps' forms in `keep`.
  double cost(const StepVectors& steps, StepForms* keep) const;
  /// Whether every step lies on the scheme's principal branch (DiscreteScheme::onPrincipalBranch):
  /// the interior points' domain, as h > 0 is (a trial iterate outside it has merit +∞).
  bool onPrincipalBranch(const StepVectors& steps) const;
  /// The torques C sums: the body's τ_k (torques()), with reaction wheels too (their torques u_k
  /// are functions of the body's motion, constrained, not summed: reaction_wheels.hpp). The one
  /// statement of it; planManeuver reports it (PlanResult::minimized_effort).
  static constexpr MinimizedEffort kMinimizedEffort = MinimizedEffort::BodyTorque;

  /// The current iterate moved by R_j → R_j exp(α δ_j^) for the free attitudes j = 2..N−2,
  /// i.e. F_j → exp(−α δ_j^) F_j exp(α δ_{j+1}^), composed in quaternions (full precision).
  StepVectors retract(const Eigen::VectorXd& delta, double alpha) const;

  /// Weights w_k(τ_k) for `second` in place of τ_k (see forEachStencil).
  using SecondOrderWeights = std::function<Vector3(int k, const Vector3& tau)>;

  /// Calls visit(stencil) for k = 1..N−1 at the current iterate; `second` is formed only if
  /// with_second_order. Returns the cost. With `weights`, `second` is sym(Σ_i w_i ∂jacobian_i/∂δ),
  /// w = weights(k, τ_k): the Hessian of a Lagrangian whose constraints are functions of τ_k
  /// (the formulas are linear in the weights; constrained_system.hpp).
  double forEachStencil(bool with_second_order, const std::function<void(const Stencil&)>& visit,
                        const SecondOrderWeights& weights = nullptr) const;

  /// The node momentum Π_k = (μ(F_k) + F_{k−1}ᵀ μ(F_{k−1}))/2 [N m s] (= μ(F_k) − (h/2)τ_k, the
  /// forced discrete Legendre transform of schemes with end torques; J⁻¹Π_k is the node velocity).
  struct NodeMomentum {
    int k = 0;                             ///< node, 1..N−1
    Vector3 momentum;                      ///< Π_k [N m s] (the effects cancel in the mean)
    Eigen::Matrix<double, 3, 9> jacobian;  ///< ∂Π_k/∂(δ_{k−1}, δ_k, δ_{k+1})
    Eigen::Matrix<double, 9, 9> second;    ///< sym(Σ_i w_i ∂jacobian_i/∂δ), with weights only
  };
  /// Calls visit(node) for k = 1..N−1 at the current iterate; `second` is formed with weights
  /// w = weights(k, Π_k) only.
  void forEachNodeMomentum(const std::function<void(const NodeMomentum&)>& visit,
                           const SecondOrderWeights& weights = nullptr) const;

  /// Cost, gradient and exact Hessian (normal equations) of δ ↦ C(R_j exp(δ_j^)) at δ = 0.
  /// `gradient_scale` = max|∂τ/∂δ| · max|τ| (for a relative gradient); hessian may be null.
  double evaluate(Eigen::VectorXd* gradient, BandedSymmetricMatrix* hessian,
                  double* gradient_scale) const;
  /// evaluate(), reading the steps' forms from `known` where it holds the current iterate's
  /// (bit for bit the values it would form; otherwise it forms them).
  double evaluate(Eigen::VectorXd* gradient, BandedSymmetricMatrix* hessian, double* gradient_scale,
                  const StepForms* known) const;

  // ---- the time step as a global unknown (objective.hpp, planning/linalg/bordered_band.hpp) ----
  // The unknowns are (δ, h): the free attitudes R_j exp(δ_j^) and h, with the boundary data held
  // (R_0, R_N, Ω(0), Ω(T)). Torque-free, μ(F) = μ̃(F)/h for every scheme, so at fixed steps the
  // interior torques scale as 1/h² and the end torques of second_order as a/h² + b/h; paper and
  // variational also move their fixed inner attitudes R_1, R_{N−1} with h (the first and last
  // steps honour Ω(0), Ω(T) at the new h). External effects enter as −τ_e(R_k, k h): they do not
  // scale with h but move with their time t_k = k h (EffectModel::timeDerivatives) and with
  // R_1, R_{N−1} where those move.

  double timeStep() const { return scheme_.timeStep(); }
  /// Sets h, keeping the free attitudes: the boundary steps are recomputed at the new h and the
  /// steps next to them follow. Throws StepTooLarge as the constructor, InvalidInput for h ≤ 0.
  void setTimeStep(double h);

  /// A stencil with its derivatives in h at fixed free attitudes: ∂r_k/∂h, and with the weights w
  /// of `second` (forEachStencilWithTimeStep), ∂²(wᵀr_k)/∂δ∂h over (δ_{k−1}, δ_k, δ_{k+1}) and
  /// ∂²(wᵀr_k)/∂h². Fixed nodes' columns are included, as in `jacobian`.
  struct TimeStepStencil : Stencil {
    Vector3 tau_h;                         ///< ∂r_k/∂h
    Eigen::Matrix<double, 9, 1> second_h;  ///< ∂²(wᵀr_k)/∂δ∂h
    double second_hh = 0.0;                ///< ∂²(wᵀr_k)/∂h²
  };
  /// As forEachStencil(true, …, weights) with the h-derivatives.
  double forEachStencilWithTimeStep(const std::function<void(const TimeStepStencil&)>& visit,
                                    const SecondOrderWeights& weights = nullptr) const;

  /// Φ = ε C + φ(N h) of `objective` at δ = 0 and the current h: `gradient` (unknowns() + 1
  /// entries, ∂Φ/∂h last), the Hessian's band (node unknowns; may be null, then border and
  /// corner are not formed), its border column ∂²Φ/∂δ∂h and corner ∂²Φ/∂h². With the effort
  /// objective the band and the node gradient are evaluate()'s, bit for bit.
  double evaluateWithTimeStep(const TranscriptionObjective& objective, Eigen::VectorXd* gradient,
                              BandedSymmetricMatrix* band, Eigen::VectorXd* border,
                              double* corner) const;

  /// How attitude R_j moves with h at fixed free attitudes: R_j(h) = R_j exp(d(h)^),
  /// d = first Δh + ½ second Δh² (the step that carries a boundary rate honours it at every h).
  struct BoundaryPath {
    Vector3 first = Vector3::Zero(), second = Vector3::Zero();
  };
  /// R_j's path: zero but for the fixed inner attitudes R_1, R_{N−1} of paper and variational
  /// (R_1 = R_0 F_0, F_0 from Ω(0) at h); a free attitude is held, R_0 and R_N are data.
  BoundaryPath nodePath(int j) const;

  // ---- the twist of a pointing end condition as a global unknown (reduced_problem_twist.cpp) ----
  // R_N = R_ref exp(ψ b^) (planning/pointing.hpp): ψ moves R_N by exp(Δψ b^) on the right and,
  // for paper and variational, R_{N−1} = R_N F_{N−1}ᵀ by exp(Δψ (F_{N−1} b)^) (F_{N−1}, from Ω(T),
  // is kept). Ω(T) is in the body frame and does not move. The motion is exactly linear in the
  // right-perturbation coordinates of those nodes, so the derivatives in ψ are the stencils'
  // Jacobian and Hessian contracted with it: no curvature term (unlike h's path).

  /// Whether the problem's end condition is a pointing one (ψ is an unknown).
  bool hasTwist() const { return twist_axis_.squaredNorm() > 0.0; }
  /// e_j: R_j(ψ + Δψ) = R_j exp(Δψ e_j^) at fixed free attitudes (zero but for R_N, and R_{N−1}
  /// of paper and variational); zero for all j without a pointing end condition.
  Vector3 twistMotion(int j) const;
  /// C at δ = 0 and the current ψ with `gradient` (unknowns() + 1 entries, ∂C/∂ψ last), the
  /// band of evaluate() (may be null: then border and corner are not formed), the border
  /// ∂²C/∂δ∂ψ and the corner ∂²C/∂ψ². `gradient_scale` as evaluate()'s (the node part).
  double evaluateWithTwist(Eigen::VectorXd* gradient, BandedSymmetricMatrix* band,
                           Eigen::VectorXd* border, double* corner, double* gradient_scale) const;
  /// The iterate moved by α δ (as retract) with ψ moved by α twist_step: the steps next to the
  /// twist-moved nodes follow, composed in quaternions.
  StepVectors retractWithTwist(const Eigen::VectorXd& delta, double twist_step, double alpha) const;
  /// Accepts steps from retractWithTwist(…, twist_step, 1) (R_N moved by exp(twist_step b^)).
  void setCurrentWithTwist(const StepVectors& steps, double twist_step);
  /// R_N as the current iterate has it (moved by every accepted twist step).
  const Matrix3& finalAttitude() const { return final_attitude_; }
  /// Steps and the R_N they compose to, as finalAttitude() and current() returned them (a line
  /// search's way back to its start point when the twist moved R_N).
  void setCurrentWithFinalAttitude(const StepVectors& steps, const Matrix3& final_attitude) {
    steps_ = steps;
    final_attitude_ = final_attitude;
  }

  /// Index of R_j's first unknown, or −1 if R_j is fixed.
  int variableIndex(int j) const {
    return (j >= first_free_ && j <= last_free_) ? 3 * (j - first_free_) : -1;
  }

 private:
  /// forEachStencil's loop; unless `symmetric_second`, `second` is left as the sum S whose
  /// symmetric part (S + Sᵀ)/2 forEachStencil gives, for a reader that forms one triangle.
  /// `known`: the steps' forms where they are the current iterate's (else null).
  double visitStencils(bool with_second_order, bool symmetric_second,
                       const std::function<void(const Stencil&)>& visit,
                       const SecondOrderWeights& weights, const StepForms* known = nullptr) const;
  /// The free steps' composition R_firstᵀR_{last+1} (what they must compose to), in quaternions.
  Eigen::Vector4d freeStepsComposition() const;
  /// Closes the gap between the free steps' composition and `target` smoothly (see
  /// initializeFromCoarser).
  void closeGap(const Eigen::Vector4d& target);

  /// The path of R_1 (at_start) or R_{N−1}; zero for second_order (no fixed inner attitude).
  BoundaryPath boundaryPath(bool at_start) const;
  /// retract's step update with a perturbation per node (zero for nodes that do not move).
  StepVectors movedSteps(const std::function<Vector3(int j)>& perturbation) const;

  int N_;
  DiscreteScheme scheme_;
  Matrix3 initial_attitude_, final_attitude_;
  Vector3 initial_velocity_, final_velocity_;   ///< Ω(0), Ω(T): the boundary steps at any h
  std::shared_ptr<const EffectModel> effects_;  ///< null when the plan has no external torques
  int first_free_, last_free_;                  ///< the free attitudes R_j
  Vector3 initial_momentum_, final_momentum_;   ///< J Ω(0), J Ω(T)
  Vector3 principal_span_;
  StepVectors steps_;
  Vector3 twist_axis_;  ///< b (unit) of a pointing end condition; zero for a fixed R_N
};

}  // namespace attitude_planner
