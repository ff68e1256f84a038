#include "planning/transcription/node_constraints.hpp"

#include <cmath>

#include "lie/dual.hpp"

namespace attitude_planner {

namespace {

/// ∇_ε φ(F exp ε^) at ε = 0 up to an antisymmetric term: V(F)ᵀ Ω(F), V = ∂Ω/∂ε. Differentiating
/// it once more (dual numbers in ε) gives the Hessian: the exact one is
/// ∂/∂ε [Jr(ε)ᵀ V(F exp ε)ᵀ Ω(F exp ε)] = ∂/∂ε[VᵀΩ] − ½ (VᵀΩ)^, whose last term is antisymmetric
/// and drops out of the symmetric part.
template <typename S>
so3::Vec3<S> rateGradient(const DiscreteScheme& scheme, const so3::Mat3<S>& F, S* half_squared) {
  const double h = scheme.timeStep();
  so3::Vec3<S> Omega;
  so3::Mat3<S> V;
  if (scheme.kind() == SchemeKind::Paper) {
    const so3::Vec3<S> w = so3::log<S>(F);
    Omega = w / S(h);
    V = so3::rightJacobianInverse<S>(w) / S(h);
  } else {
    const so3::Mat3<S> J_inverse = scheme.inertia().inverse().template cast<S>();
    Omega = J_inverse * scheme.momentum<S>(F);
    V = J_inverse * scheme.momentumJacobian<S>(F);
  }
  *half_squared = S(0.5) * Omega.squaredNorm();
  return V.transpose() * Omega;
}

}  // namespace

AngularRateTerms angularRateTerms(const DiscreteScheme& scheme, const Vector3& omega) {
  using D3 = Dual<3>;
  const Matrix3 F = so3::exp(omega);
  so3::Vec3<D3> epsilon;
  for (int i = 0; i < 3; ++i) epsilon(i) = D3(0.0, i);
  const so3::Mat3<D3> F_perturbed = F.cast<D3>() * so3::exp<D3>(epsilon);
  D3 half_squared;
  const so3::Vec3<D3> g_dual = rateGradient<D3>(scheme, F_perturbed, &half_squared);
  Vector3 g;
  Matrix3 M;
  for (int i = 0; i < 3; ++i) {
    g(i) = g_dual(i).v;
    M.row(i) = g_dual(i).d.transpose();
  }
  const Matrix3 H = 0.5 * (M + M.transpose());  // ∂²φ/∂ε²
  // F(a, b) = exp(−a^) F exp(b^) = F exp(ε^), ε = b − Fᵀa − ½ (Fᵀa) × b + O(3) (BCH), so
  // ∂ε/∂(a, b) = [−Fᵀ, I] and the mixed term adds gᵀ∂²ε/∂a∂b = ½ F g^ to the (a, b) block.
  AngularRateTerms out;
  out.half_squared_rate = half_squared.v;
  out.gradient.head<3>() = -F * g;
  out.gradient.tail<3>() = g;
  const Matrix3 cross = 0.5 * F * so3::hat(g);
  out.hessian.block<3, 3>(0, 0) = F * H * F.transpose();
  out.hessian.block<3, 3>(0, 3) = -F * H + cross;
  out.hessian.block<3, 3>(3, 0) = out.hessian.block<3, 3>(0, 3).transpose();
  out.hessian.block<3, 3>(3, 3) = H;
  return out;
}

PointingTerms pointingTerms(const Matrix3& R, const Vector3& b, const Vector3& s) {
  // sᵀR exp(δ^) b = vᵀ(b + δ × b + ½ δ × (δ × b)) + O(3), v = Rᵀs.
  const Vector3 v = R.transpose() * s;
  PointingTerms out;
  out.cosine = v.dot(b);
  out.gradient = b.cross(v);
  out.hessian = 0.5 * (v * b.transpose() + b * v.transpose()) - v.dot(b) * Matrix3::Identity();
  return out;
}

ElasticSlacks elasticSlacks(double c, double mu, double rho) {
  // ρ s² − (ρc + 2μ) s + μc = 0 and v = s − c; the root is formed without cancellation for
  // either sign of c (r = √(ρ²c² + 4μ²) ≥ ρ|c|).
  const double r = std::sqrt(rho * rho * c * c + 4.0 * mu * mu);
  ElasticSlacks out;
  if (c >= 0.0) {
    out.v = (2.0 * mu + 4.0 * mu * mu / (r + rho * c)) / (2.0 * rho);
    out.s = out.v + c;
  } else {
    out.s = (2.0 * mu + 4.0 * mu * mu / (r - rho * c)) / (2.0 * rho);
    out.v = out.s - c;
  }
  out.psi = rho * out.v - mu * std::log(out.s) - mu * std::log(out.v);
  return out;
}

}  // namespace attitude_planner
