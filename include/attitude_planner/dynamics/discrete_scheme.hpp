// Discrete forced rigid-body dynamics in one form shared by every scheme.
//
// With F_k = R_kᵀ R_{k+1} (the relative rotation of step k) every scheme here reads
//
//     R_{k+1} = R_k F_k,          h τ_k = μ(F_k) − F_{k−1}ᵀ μ(F_{k−1}),      k = 1..N−1,
//
// where μ(F) is the body angular momentum a step "carries" (expressed at its start node) and
// F_{k−1}ᵀ μ(F_{k−1}) the same momentum seen from the end node. The schemes differ only in μ:
//
//   paper        μ(F) = F J Ω,  Ω = log(F)/h                   seed 000, eq. (18):
//                J Ω_k = exp(hΩ_k)ᵀ (h τ_k + J Ω_{k−1})
//   variational  μ(F) = (F J_d − J_d Fᵀ)^∨ / h,  J_d = ½ tr(J) I − J
//                Lee–Leok–McClamroch LGVI; forced through the discrete Lagrange–d'Alembert
//                principle with the torque at the node: Π_k = F_{k−1}ᵀ Π_{k−1} + h τ_k.
//   second_order the variational μ (the LGVI's discrete Lagrangian tr((I − F) J_d)/h is
//                time-symmetric, hence of even order ≥ 2), but the ends are nodes like the others:
//                each torque impulse is split h/2 + h/2 over the two steps it touches, so the
//                node momenta are the forced discrete Legendre transforms
//                    Π_k = μ(F_k) − (h/2) τ_k = F_{k−1}ᵀ μ(F_{k−1}) + (h/2) τ_k,
//                and the boundary velocities are imposed at the instants 0 and T themselves:
//                Π_0 = J Ω(0), Π_N = J Ω(T) (τ_0, τ_N are unknowns, not zero). The cost is the
//                trapezoidal rule, weights ½ at the end nodes. Derivation:
//                docs/design/second_order.md.
//   fourth_order not a discretization: one Richardson extrapolation step of second_order (plans
//                at N and 2N combined node by node, planAtResolution; docs/design/fourth_order.md).
//                No DiscreteScheme is built for it (the constructor refuses it); its node torques
//                are replayed with a cubic hold (replayPlan, simulation.hpp) and its effort is the
//                end-corrected trapezoidal rule (schemeTorqueWeight).
//
// Torque-free, the spatial momentum R_k μ(F_k) is conserved exactly by construction.
// Derivatives are with respect to right perturbations F exp(ε^).
#pragma once

#include <string>
#include <vector>

#include "attitude_planner/errors.hpp"
#include "attitude_planner/lie/so3.hpp"
#include "attitude_planner/name_table.hpp"

namespace attitude_planner {

/// Which discretization of the rigid body.
enum class SchemeKind { Paper, Variational, SecondOrder, FourthOrder };

/// The names of the schemes (scene key `scheme`, --scheme, request field `scheme`, JSON).
inline constexpr NamedValue<SchemeKind> kSchemeNames[] = {
    {SchemeKind::Paper, "paper"},
    {SchemeKind::Variational, "variational"},
    {SchemeKind::SecondOrder, "second_order"},
    {SchemeKind::FourthOrder, "fourth_order"},
};

/// "paper", "variational", "second_order" or "fourth_order".
inline std::string schemeName(SchemeKind kind) {
  return nameIn(kSchemeNames, kind);
}
/// The scheme named `text`; throws InvalidInput naming `field`, the value and the accepted names.
inline SchemeKind parseScheme(const std::string& text, const std::string& field) {
  return parseIn(kSchemeNames, text, field);
}

/// True if the scheme's end-node torques are part of the plan and its rows k = 0..N are node
/// values (second_order, see DiscreteScheme::hasEndTorques; fourth_order, built from two
/// second_order plans).
inline bool schemeHasEndTorques(SchemeKind kind) {
  return kind == SchemeKind::SecondOrder || kind == SchemeKind::FourthOrder;
}

/// True if plans of the scheme are solutions of discrete equations of motion (a DiscreteScheme);
/// false for fourth_order, the Richardson extrapolation of two second_order plans.
inline bool schemeIsDiscretization(SchemeKind kind) {
  return kind != SchemeKind::FourthOrder;
}

/// Quadrature weight w_k of ½|τ_k|² in the scheme's cost Σ_k w_k ½|τ_k|² (the effort is h times
/// it), k = 0..N:
///   paper, variational  1 (τ_0 = τ_N = 0: a Riemann sum of the interior torques)
///   second_order        the trapezoidal rule: ½ at the end nodes, else 1
///   fourth_order        the trapezoidal rule with Gregory's end corrections (exact for cubics,
///                       order 4 for N ≥ 3): 3/8, 7/6, 23/24, 1, …, 1, 23/24, 7/6, 3/8; for small
///                       N the two ends' corrections add.
inline double schemeTorqueWeight(SchemeKind kind, int k, int steps) {
  if (!schemeHasEndTorques(kind)) return 1.0;
  double w = (k == 0 || k == steps) ? 0.5 : 1.0;
  if (kind == SchemeKind::FourthOrder) {
    constexpr double kCorrection[3] = {-1.0 / 8.0, 1.0 / 6.0, -1.0 / 24.0};
    if (k < 3) w += kCorrection[k];
    if (steps - k < 3) w += kCorrection[steps - k];
  }
  return w;
}

/// The scheme's cost Σ_k w_k ½|τ_k|² [N²·m²] of the node torques τ_0..τ_N (schemeTorqueWeight).
double schemeCost(SchemeKind kind, const std::vector<Vector3>& torque);

/// Outcome of one implicit step solve μ(F) = p.
struct StepSolveReport {
  bool converged = false;
  int iterations = 0;
  double residual = 0.0;  ///< |μ(F) − p| [N·m·s]
};

/// One discretization of the rigid body with inertia J [kg·m²] and time step h [s].
class DiscreteScheme {
 public:
  /// Throws InvalidInput for fourth_order (not a discretization: schemeIsDiscretization).
  DiscreteScheme(SchemeKind kind, const Matrix3& inertia, double time_step);

  SchemeKind kind() const { return kind_; }
  /// True if the torques at the end nodes are impulses of the scheme (second_order: Π_0 = J Ω(0)
  /// = μ(F_0) − (h/2) τ_0, Π_N = J Ω(T) = F_{N−1}ᵀ μ(F_{N−1}) + (h/2) τ_N); false if τ_0 = τ_N = 0
  /// and the boundary velocities fix the first and last steps (paper, variational).
  bool hasEndTorques() const { return schemeHasEndTorques(kind_); }
  /// Quadrature weight of ½|τ_k|² in the cost, k = 0..N: ½ at the ends with end torques
  /// (trapezoidal rule), else 1.
  double torqueWeight(int k, int steps) const { return schemeTorqueWeight(kind_, k, steps); }
  /// The scheme's cost Σ_k ½ w_k |τ_k|² [N²·m²] of the node torques τ_0..τ_N (the effort is
  /// h times it).
  double cost(const std::vector<Vector3>& torque) const;
  const Matrix3& inertia() const { return J_; }
  double timeStep() const { return h_; }

  /// μ(F): momentum carried by a step with relative rotation F [N·m·s], body frame at its start.
  template <typename S>
  so3::Vec3<S> momentum(const so3::Mat3<S>& F) const;

  /// μ(exp(ω^)) from the step's rotation vector ω: the same value as momentum(exp(ω^)), but with
  /// full relative precision for small steps (exp(ω^) − I is formed by series, never as a
  /// difference). Torques are second differences of the attitude, so this is what keeps them
  /// accurate over long horizons.
  Vector3 momentumOfStep(const Vector3& omega) const;
  /// The same from E = exp(ω^) − I already formed (so3::expMinusIdentity(ω)), where the caller
  /// needs E too (a torque needs F_{k−1} − I of the step whose momentum it carries).
  Vector3 momentumOfStep(const Vector3& omega, const Matrix3& E) const;

  /// dμ(F exp(ε^))/dε at ε = 0 (3×3).
  template <typename S>
  so3::Mat3<S> momentumJacobian(const so3::Mat3<S>& F) const;

  /// momentumJacobian(F) of the step F = exp(ω^) given as both (no log map to recover ω).
  Matrix3 momentumJacobianOfStep(const Matrix3& F, const Vector3& omega) const;

  /// Whether the step ω lies where μ is invertible on the branch through the identity:
  /// det(∂μ/∂ε) > 0, the sign it has at ω = 0 (J/h). Past the fold μ aliases a slow motion
  /// (variational and second_order: sin|ω| Ja + (1 − cos|ω|) a × Ja for ω = |ω| a, so an isotropic
  /// body folds at |ω| = π/2 and a step turning by nearly π carries almost no momentum): a plan
  /// with such a step is not reproduced from its own velocities and torques.
  bool onPrincipalBranch(const Vector3& omega) const;

  /// The τ-weighted derivative of the momentum Jacobian of the step F = exp(ω^), in closed form:
  ///   C(m, e) = Σ_i τ_i ∂D(i, m)/∂ε_e,  D = momentumJacobian(F exp(ε^)) at ε = 0,
  /// i.e. the mixed second derivative ∂²/∂ε_e∂η_m of τᵀμ(F exp(ε^) exp(η^)). The Newton solver's
  /// exact Hessian is built from it (derivation in discrete_scheme.cpp).
  Matrix3 momentumJacobianContraction(const Matrix3& F, const Vector3& omega,
                                      const Vector3& tau) const;

  /// What momentumJacobianOfStep and momentumJacobianContraction read of the step F = exp(ω^)
  /// alone, not of τ: formed once where one step's Jacobian is contracted with several τ (a
  /// Newton Hessian reaches each step from the two torques beside it). The paper scheme's terms
  /// (its log map's Jacobian); the variational μ reads F alone.
  struct StepJacobianTerms {
    Matrix3 F;
    Vector3 omega;        ///< ω = log F
    double c = 0.0;       ///< so3::rightJacobianInverseCoefficient(|ω|²) (paper)
    double dc = 0.0;      ///< its derivative in |ω|² (paper)
    Matrix3 W;            ///< ω^ (paper)
    Matrix3 Jr_inverse;   ///< Jr⁻¹(ω) (paper)
    Matrix3 JJr_inverse;  ///< J Jr⁻¹(ω) (paper)
    Vector3 Jw;           ///< J ω (paper)
  };
  StepJacobianTerms stepJacobianTerms(const Matrix3& F, const Vector3& omega) const;
  /// momentumJacobianOfStep(F, ω), the same values, from the step's terms.
  Matrix3 momentumJacobianOfStep(const StepJacobianTerms& step) const;
  /// momentumJacobianContraction(F, ω, τ), the same values, from the step's terms.
  Matrix3 momentumJacobianContraction(const StepJacobianTerms& step, const Vector3& tau) const;

  /// Body angular velocity [rad/s] reported for a step: paper log(F)/h (constant over the step),
  /// variational and second_order J⁻¹ μ(F) (nodal velocity at the step's start; second_order
  /// reports J⁻¹ Π_k at the nodes instead, simulation.hpp).
  Vector3 velocity(const Matrix3& F) const;

  /// velocity(exp(ω^)) from the step's rotation vector, with full relative precision for small
  /// steps (paper ω/h, variational and second_order J⁻¹ momentumOfStep(ω); second_order reports
  /// node velocities instead, ReducedProblem::maneuver).
  Vector3 velocityOfStep(const Vector3& omega) const;

  /// μ of the step whose reported velocity is Ω, without solving for the step: paper
  /// exp(hΩ^) J Ω, variational J Ω (its reported velocity is J⁻¹ μ); not for second_order,
  /// whose node velocities are J⁻¹Π_k (μ = Π_k + (h/2) a_k needs the node's torque).
  Vector3 momentumOfVelocity(const Vector3& omega) const;

  /// Relative rotation of a step whose reported velocity is Ω (inverse of velocity()).
  /// Throws StepTooLarge if the implicit equation has no solution it can find.
  Matrix3 stepFromVelocity(const Vector3& omega) const;

  /// Solves μ(F) = p for F by a safeguarded Newton iteration on F ← F exp(δ^), starting from
  /// `guess`. Converged when |μ(F) − p| ≤ 1e-14·(|p| + ‖J‖|log F|/h) + 1e-15‖J‖/h (the
  /// round-off floor of μ), then polished by up to two more Newton steps. Never returns NaN:
  /// `report.converged` is false if it fails (step too large for this h).
  Matrix3 solveStep(const Vector3& p, const Matrix3& guess, StepSolveReport* report) const;

 private:
  /// The paper scheme's dμ/dε at F = exp(w^).
  template <typename S>
  so3::Mat3<S> paperMomentumJacobian(const so3::Mat3<S>& F, const so3::Vec3<S>& w) const;
  /// μ(F) given w = log(F) (the paper scheme reads it; the variational one does not): the one
  /// formula of momentum(), for a caller that holds the log already.
  template <typename S>
  so3::Vec3<S> momentumWithLog(const so3::Mat3<S>& F, const so3::Vec3<S>& w) const;

  SchemeKind kind_;
  Matrix3 J_;
  Matrix3 J_inverse_;
  Matrix3 Jd_;  ///< nonstandard inertia ½ tr(J) I − J (variational)
  double h_;
};

// ---- templates ----------------------------------------------------------------------------------

template <typename S>
so3::Vec3<S> DiscreteScheme::momentum(const so3::Mat3<S>& F) const {
  if (kind_ == SchemeKind::Paper) return momentumWithLog<S>(F, so3::log<S>(F));
  return momentumWithLog<S>(F, so3::Vec3<S>::Zero());
}

template <typename S>
so3::Vec3<S> DiscreteScheme::momentumWithLog(const so3::Mat3<S>& F, const so3::Vec3<S>& w) const {
  if (kind_ == SchemeKind::Paper) {  // variational and second_order share μ
    const so3::Mat3<S> J = J_.template cast<S>();
    const so3::Vec3<S> Omega = w / S(h_);
    return F * (J * Omega);
  }
  const so3::Mat3<S> Jd = Jd_.template cast<S>();
  const so3::Mat3<S> A = F * Jd;
  return so3::Vec3<S>(A(2, 1) - A(1, 2), A(0, 2) - A(2, 0), A(1, 0) - A(0, 1)) / S(h_);
}

template <typename S>
so3::Mat3<S> DiscreteScheme::paperMomentumJacobian(const so3::Mat3<S>& F,
                                                   const so3::Vec3<S>& w) const {
  // μ = F J ω/h, ω = log F:  δμ = F (J Jr⁻¹(ω) − (Jω)^) ε / h
  const so3::Mat3<S> J = J_.template cast<S>();
  const so3::Vec3<S> Jw = J * w;
  return F * (J * so3::rightJacobianInverse<S>(w) - so3::hat<S>(Jw)) / S(h_);
}

template <typename S>
so3::Mat3<S> DiscreteScheme::momentumJacobian(const so3::Mat3<S>& F) const {
  if (kind_ == SchemeKind::Paper) return paperMomentumJacobian<S>(F, so3::log<S>(F));
  // μ = (F J_d − J_d Fᵀ)^∨/h:  δμ = (F ε^ J_d + J_d ε^ Fᵀ)^∨/h, column by column
  const so3::Mat3<S> Jd = Jd_.template cast<S>();
  so3::Mat3<S> D;
  for (int i = 0; i < 3; ++i) {
    so3::Vec3<S> e = so3::Vec3<S>::Zero();
    e(i) = S(1);
    const so3::Mat3<S> A = F * so3::hat<S>(e) * Jd;
    D.col(i) = so3::Vec3<S>(A(2, 1) - A(1, 2), A(0, 2) - A(2, 0), A(1, 0) - A(0, 1)) / S(h_);
  }
  return D;
}

}  // namespace attitude_planner
