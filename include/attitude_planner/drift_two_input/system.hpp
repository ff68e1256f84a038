// Remsing's drift + two-input system on SO(3) (seed 001): ġ = g(E3 + u1 E1 + u2 E2),
// cost ½∫(c1 u1² + c2 u2²) dt, and the flow of its normal extremals.
//
// Derivation (docs/design/drift_two_input.md): with the left-trivialized costate p ∈ so(3)* ≅ R³
// the maximum condition (seed 2.7, λ = −1) gives u_i = p_i/c_i and the reduced Hamiltonian H(p) =
// ½(p1²/c1 + p2²/c2) + p3. The spatial costate μ = g p is constant along an extremal (first-order
// optimality of the fixed-endpoint problem), so ṗ = d(gᵀμ)/dt = −ξ × p = p × ∇H(p) with ξ = ∇H(p) =
// (u1, u2, 1): exactly seed (3.12)–(3.17). Casimir C = |p|² and H are conserved.
//
// Units: t [s]; the controls u_i are angular rates [rad/s]; the drift E3 is a unit rate
// [rad/s] (time is scaled so); c_i [cost units·s²/rad²]; p has units of c·u.
#pragma once

#include <Eigen/Core>
#include <vector>

#include "attitude_planner/lie/so3.hpp"

namespace attitude_planner {

/// Cost weights (c1, c2) > 0 of ½∫(c1 u1² + c2 u2²) dt, seed (3.10).
struct DriftTwoInputWeights {
  double c1 = 1.0;  ///< weight of u1² [cost·s²/rad²]
  double c2 = 1.0;  ///< weight of u2² [cost·s²/rad²]
};

/// Throws InvalidInput unless c1, c2 are finite and > 0.
void validateDriftTwoInputWeights(const DriftTwoInputWeights& w);
/// The inputs every extremal integration and sampling shares: weights, duration T (the shared
/// duration rule, input_rules.hpp), output steps ≥ 1 and a finite costate p0; InvalidInput names
/// the one that is bad.
void validateDriftTwoInputExtremalInputs(const DriftTwoInputWeights& w, double T, int steps,
                                         const Vector3& p0);

namespace drift_two_input {

/// Body velocity ξ = ∇H(p) = (p1/c1, p2/c2, 1) [rad/s]: the extremal controls (Prop. 3.1) plus
/// drift.
template <typename S>
so3::Vec3<S> velocity(const so3::Vec3<S>& p, const DriftTwoInputWeights& w) {
  return so3::Vec3<S>(p.x() / w.c1, p.y() / w.c2, S(1));
}

/// Lie–Poisson vector field ṗ = p × ∇H(p), seed (3.15)–(3.17) [p units/s].
template <typename S>
so3::Vec3<S> costateRate(const so3::Vec3<S>& p, const DriftTwoInputWeights& w) {
  return p.cross(velocity<S>(p, w));
}

/// Reduced Hamiltonian H(p) = ½(p1²/c1 + p2²/c2) + p3 (Prop. 3.1) [p units].
inline double hamiltonian(const Vector3& p, const DriftTwoInputWeights& w) {
  return 0.5 * (p.x() * p.x() / w.c1 + p.y() * p.y() / w.c2) + p.z();
}

/// Casimir C(p) = |p|² of the minus Lie–Poisson structure [p units²].
inline double casimir(const Vector3& p) {
  return p.squaredNorm();
}

/// Running cost ½(c1 u1² + c2 u2²) = ½(p1²/c1 + p2²/c2) along an extremal [cost/s].
template <typename S>
S runningCost(const so3::Vec3<S>& p, const DriftTwoInputWeights& w) {
  return S(0.5) * (p.x() * p.x() / w.c1 + p.y() * p.y() / w.c2);
}

/// Inverse of a 3×3 matrix by cofactors (templated: usable with dual numbers, no pivoting).
template <typename S>
so3::Mat3<S> inverse3(const so3::Mat3<S>& A) {
  so3::Mat3<S> C;
  C(0, 0) = A(1, 1) * A(2, 2) - A(1, 2) * A(2, 1);
  C(0, 1) = A(0, 2) * A(2, 1) - A(0, 1) * A(2, 2);
  C(0, 2) = A(0, 1) * A(1, 2) - A(0, 2) * A(1, 1);
  C(1, 0) = A(1, 2) * A(2, 0) - A(1, 0) * A(2, 2);
  C(1, 1) = A(0, 0) * A(2, 2) - A(0, 2) * A(2, 0);
  C(1, 2) = A(0, 2) * A(1, 0) - A(0, 0) * A(1, 2);
  C(2, 0) = A(1, 0) * A(2, 1) - A(1, 1) * A(2, 0);
  C(2, 1) = A(0, 1) * A(2, 0) - A(0, 0) * A(2, 1);
  C(2, 2) = A(0, 0) * A(1, 1) - A(0, 1) * A(1, 0);
  const S det = A(0, 0) * C(0, 0) + A(0, 1) * C(1, 0) + A(0, 2) * C(2, 0);
  return C / det;
}

/// Value part of a scalar (double, or Dual<N>::v): Newton stops on values only.
inline double valueOf(double x) {
  return x;
}
/// Value part of a dual number.
template <typename D>
double valueOf(const D& x) {
  return x.v;
}

/// One implicit-midpoint step for p (preserves C and H, both quadratic, exactly up to the
/// Newton tolerance): Δ = h f(p + Δ/2), p⁺ = p + Δ. Returns Δ [p units]. Newton on the 3×3
/// system; after the value has converged one more iteration is taken so that dual-number
/// derivative parts are exact too. Throws StepTooLarge (in the .cpp wrapper) on failure:
/// here a non-convergence is reported through `converged`.
template <typename S>
so3::Vec3<S> midpointIncrement(const so3::Vec3<S>& p, double h, const DriftTwoInputWeights& w,
                               bool* converged) {
  // explicit predictor (Euler), then Newton on F(Δ) = Δ − h (p + Δ/2) × ξ(p + Δ/2)
  so3::Vec3<S> delta = costateRate<S>(p, w) * S(h);
  const so3::Vec3<S> inv_c(S(1.0 / w.c1), S(1.0 / w.c2), S(0));
  bool done = false;
  *converged = false;
  for (int it = 0; it < 50; ++it) {
    const so3::Vec3<S> m = p + delta * S(0.5);
    const so3::Vec3<S> xi = velocity<S>(m, w);
    const so3::Vec3<S> F = delta - S(h) * m.cross(xi);
    // ∂(m × ξ(m))/∂m = −ξ^ + m^ diag(1/c1, 1/c2, 0); ∂m/∂Δ = ½
    so3::Mat3<S> D = -so3::hat<S>(xi) + so3::hat<S>(m) * inv_c.asDiagonal().toDenseMatrix();
    so3::Mat3<S> Jf = so3::Mat3<S>::Identity() - S(0.5 * h) * D;
    const so3::Vec3<S> step = inverse3<S>(Jf) * F;
    delta -= step;
    if (done) {
      *converged = true;
      break;
    }
    double scale = 0.0, s = 0.0;
    for (int i = 0; i < 3; ++i) {
      scale = std::max(scale, std::abs(valueOf(p(i))) + std::abs(valueOf(delta(i))));
      s = std::max(s, std::abs(valueOf(step(i))));
    }
    if (s <= 1e-16 * std::max(scale, 1e-300)) done = true;  // one more pass for derivative parts
  }
  return delta;
}

/// One step of the extremal flow, seed (3.8) + (3.15)–(3.17): implicit midpoint for p, and
/// g⁺ = g exp(h ξ(p_mid)) so g stays on SO(3) (ξ evaluated at the midpoint p_mid = p + Δ/2 makes
/// the pair a symmetric, second-order method). Returns false if Newton did not converge.
template <typename S>
bool step(so3::Mat3<S>& g, so3::Vec3<S>& p, double h, const DriftTwoInputWeights& w,
          S* cost_increment = nullptr) {
  bool ok = false;
  const so3::Vec3<S> delta = midpointIncrement<S>(p, h, w, &ok);
  const so3::Vec3<S> mid = p + delta * S(0.5);
  g = g * so3::exp<S>(so3::Vec3<S>(velocity<S>(mid, w) * S(h)));
  if (cost_increment) *cost_increment = S(h) * runningCost<S>(mid, w);
  p = p + delta;
  return ok;
}

/// Composition coefficients of Yoshida's fourth-order "triple jump" of a symmetric method.
struct TripleJump {
  static constexpr double kGamma1 = 1.3512071919596576;   ///< 1/(2 − 2^{1/3})
  static constexpr double kGamma2 = -1.7024143839193153;  ///< 1 − 2 γ1
};

/// One step of size h of the chosen order (2: midpoint; 4: triple jump of midpoint, still
/// conserving C and H exactly since each sub-step does). Returns false on Newton failure.
template <typename S>
bool stepOfOrder(so3::Mat3<S>& g, so3::Vec3<S>& p, double h, const DriftTwoInputWeights& w,
                 int order, S* cost_increment = nullptr) {
  if (order != 4) return step<S>(g, p, h, w, cost_increment);
  bool ok = true;
  S total = S(0), part = S(0);
  for (double gamma : {TripleJump::kGamma1, TripleJump::kGamma2, TripleJump::kGamma1}) {
    ok = step<S>(g, p, gamma * h, w, &part) && ok;
    total = total + part;
  }
  if (cost_increment) *cost_increment = total;
  return ok;
}

}  // namespace drift_two_input

/// Sampled extremal: samples k = 0..N at t_k = k T/N.
struct DriftTwoInputTrajectory {
  std::vector<double> t;           ///< sample times [s]
  std::vector<Vector3> p;          ///< costate p(t_k) (body frame) [c·rad/s]
  std::vector<Matrix3> g;          ///< attitude g(t_k) (body → world)
  std::vector<Eigen::Vector2d> u;  ///< controls (u1, u2) = (p1/c1, p2/c2) at t_k [rad/s]
  double cost = 0.0;  ///< ½∫(c1 u1² + c2 u2²) dt by the scheme's own quadrature [cost]
};

/// Options of the extremal integrator.
struct DriftTwoInputIntegration {
  int substeps = 1;  ///< integration steps per output interval (≥ 1)
  int order = 2;     ///< 2: implicit midpoint; 4: its triple-jump composition
};

/// Integrates the extremal from (g0, p0) over [0, T] [s] with `steps` output intervals; throws
/// InvalidInput on bad arguments and StepTooLarge if an implicit step fails.
DriftTwoInputTrajectory integrateDriftTwoInputExtremal(const Matrix3& g0, const Vector3& p0,
                                                       double T, int steps,
                                                       const DriftTwoInputWeights& w,
                                                       const DriftTwoInputIntegration& opts = {});

/// Replays sampled controls open loop: integrates ġ = g(E3 + u1 E1 + u2 E2) from g0 through the
/// samples (t_k, u_k), k = 0..N (uniform or not, increasing), and returns g at every t_k
/// (g[0] = g0). The control between samples is the cubic through the 4 nearest samples (fewer if
/// N < 3); each interval takes `substeps` steps of the fourth-order Magnus method
/// g⁺ = g exp(s/2 (ξ_a + ξ_b) + √3/12 s² ξ_a × ξ_b), ξ at the two Gauss points, so g stays on
/// SO(3). Error O(Δt⁴) in the sample spacing (interpolation) plus O((Δt/substeps)⁴).
/// Throws InvalidInput on mismatched sizes, non-finite or non-increasing samples, substeps < 1.
std::vector<Matrix3> replayDriftTwoInputControls(const Matrix3& g0, const std::vector<double>& t,
                                                 const std::vector<Eigen::Vector2d>& u,
                                                 int substeps = 4);

/// The replay between its samples (the tracker streams a drift maneuver at its ~rate).
struct DriftTwoInputReplaySample {
  Matrix3 g = Matrix3::Identity();              ///< g(s), body → world
  Eigen::Vector2d u = Eigen::Vector2d::Zero();  ///< (u1, u2)(s) [rad/s], the replay's cubic
};
/// g(s) and u(s) at any s ∈ [t_0, t_N] (clamped) of the replay `g` = replayDriftTwoInputControls(
/// g0, t, u, substeps): from the sample before s, `substeps` Magnus steps of the same cubic control
/// to s; exactly g[k], u[k] at a sample. Throws InvalidInput on mismatched sizes.
DriftTwoInputReplaySample replayedDriftTwoInputAt(const std::vector<Matrix3>& g,
                                                  const std::vector<double>& t,
                                                  const std::vector<Eigen::Vector2d>& u, double s,
                                                  int substeps = 4);

}  // namespace attitude_planner
