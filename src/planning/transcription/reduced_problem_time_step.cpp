// ReducedProblem with the time step h as a global unknown (declarations and the model in
// reduced_problem.hpp). At fixed steps every scheme's momentum is μ̃(F)/h, so a torque is
//
//     r_k(δ, h) = s(h) ρ_k(δ + d(h)) + (t(h) − s(h)) β_k + ε_k(δ + d(h), h),
//     s = (h₀/h)², t = h₀/h,
//
// with ρ_k the dynamics' part of the torque at h₀ as a function of the node perturbations, d(h)
// the motion of the fixed inner attitudes R_1, R_{N−1} (paper, variational: boundaryPath), β_k
// the part of an end torque (second_order) carried by a boundary momentum, (∓2√w J Ω)/h₀, which
// scales as 1/h, and ε_k = −√w_k τ_e(R_k, k h) the external effects' part (EffectModel), which
// moves with h through R_k (where d moves it) and through its time t_k = k h. Its derivatives
// in h therefore follow from the stencil's Jacobian and curvature at h₀ and the effects' time
// derivatives.
#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <string>

#include "planning/transcription/reduced_problem.hpp"

namespace attitude_planner {

namespace {
Eigen::Vector4d inverseQuaternion(Eigen::Vector4d q) {
  q.tail<3>() *= -1.0;
  return q;
}
}  // namespace

void ReducedProblem::setTimeStep(double h) {
  if (!(std::isfinite(h) && h > 0.0)) {
    throw InvalidInput("time step: must be finite and > 0, got " + std::to_string(h));
  }
  const DiscreteScheme scheme(scheme_.kind(), scheme_.inertia(), h);
  const Matrix3 F_first = scheme.stepFromVelocity(initial_velocity_);  // throws StepTooLarge
  const Matrix3 F_last = scheme.stepFromVelocity(final_velocity_);
  principal_span_ = so3::log(
      Matrix3((initial_attitude_ * F_first).transpose() * final_attitude_ * F_last.transpose()));
  if (!scheme.hasEndTorques()) {
    // The boundary steps at the new h (as the constructor); R_2 and R_{N−2} stay, so
    // F_1 → F_0'ᵀ F_0 F_1 and F_{N−2} → F_{N−2} F_{N−1} F_{N−1}'ᵀ, in quaternions.
    const bool paper = scheme.kind() == SchemeKind::Paper;
    const Vector3 first = paper ? Vector3(h * initial_velocity_) : so3::log(F_first);
    const Vector3 last = paper ? Vector3(h * final_velocity_) : so3::log(F_last);
    const auto q = [](const Vector3& w) { return so3::quaternionOfRotationVector<double>(w); };
    const auto product = [](const Eigen::Vector4d& a, const Eigen::Vector4d& b) {
      return so3::quaternionProduct<double>(a, b);
    };
    steps_[1] = so3::logOfQuaternion<double>(
        product(inverseQuaternion(q(first)), product(q(steps_[0]), q(steps_[1]))));
    steps_[N_ - 2] = so3::logOfQuaternion<double>(
        product(q(steps_[N_ - 2]), product(q(steps_[N_ - 1]), inverseQuaternion(q(last)))));
    steps_[0] = first;
    steps_[N_ - 1] = last;
  }
  scheme_ = scheme;
}

ReducedProblem::BoundaryPath ReducedProblem::boundaryPath(bool at_start) const {
  BoundaryPath path;
  if (scheme_.hasEndTorques()) return path;
  const Vector3& omega = at_start ? steps_[0] : steps_[N_ - 1];
  const Vector3& velocity = at_start ? initial_velocity_ : final_velocity_;
  // The boundary step F(h) = F exp(δ(h)^) honours the boundary velocity at every h.
  Vector3 first, second;
  if (scheme_.kind() == SchemeKind::Paper) {
    first = velocity;  // ω = hΩ: F(h) = F exp(Δh Ω^), exactly linear
    second.setZero();
  } else {
    // μ̃(F exp δ) = h J Ω with μ̃ = h μ: D δ' = JΩ/h, and D δ'' = −(δ'ᵀ C_i δ')_i, C_i the
    // contraction of dμ/dε with the unit weight e_i (its quadratic form is μ_i's Hessian).
    const Matrix3 F = so3::exp(omega);
    const Matrix3 D = scheme_.momentumJacobianOfStep(F, omega);
    const Eigen::PartialPivLU<Matrix3> lu(D);
    first = lu.solve(Vector3(scheme_.inertia() * velocity / scheme_.timeStep()));
    Vector3 curvature;
    for (int i = 0; i < 3; ++i) {
      const Matrix3 C = scheme_.momentumJacobianContraction(F, omega, Vector3(Vector3::Unit(i)));
      curvature(i) = first.dot(C * first);
    }
    second = -lu.solve(curvature);
  }
  if (at_start) {  // R_1 = R_0 F_0: moves by exp(δ)
    path.first = first;
    path.second = second;
  } else {  // R_{N−1} = R_N F_{N−1}ᵀ moves by exp(−F_{N−1} δ)
    const Matrix3 F = so3::exp(omega);
    path.first = -F * first;
    path.second = -F * second;
  }
  return path;
}

ReducedProblem::BoundaryPath ReducedProblem::nodePath(int j) const {
  if (scheme_.hasEndTorques()) return {};
  if (j == 1) return boundaryPath(true);
  if (j == N_ - 1) return boundaryPath(false);
  return {};
}

namespace {

/// The effects' part ε_k = −√w_k τ_e(R_k, k h) of torque k and its derivatives in h through its
/// time t_k = k h at fixed R_k: ∂ε/∂h = −√w k τ̇_e, ∂²ε/∂h² = −√w k² τ̈_e, and of its Jacobian
/// block on R_k (interior torques only: the end torques' R_0, R_N are data), ∂/∂h = −√w k ∂J_e/∂t.
struct EffectPart {
  Vector3 value = Vector3::Zero(), first = Vector3::Zero(), second = Vector3::Zero();
  Matrix3 jacobian = Matrix3::Zero(), jacobian_h = Matrix3::Zero();
};

EffectPart effectPart(const EffectModel& effects, const Matrix3& R_k, int k, double h, double root,
                      bool interior) {
  const double t = k * h;
  const EffectTimeDerivatives d = effects.timeDerivatives(R_k, t);
  EffectPart part;
  part.value = -root * effects.torque(R_k, t);
  part.first = -root * k * d.torque_rate;
  part.second = -root * double(k) * k * d.torque_acceleration;
  if (interior) {
    part.jacobian = -root * effects.jacobian(R_k, t);
    part.jacobian_h = -root * k * d.jacobian_rate;
  }
  return part;
}

}  // namespace

double ReducedProblem::forEachStencilWithTimeStep(
    const std::function<void(const TimeStepStencil&)>& visit,
    const SecondOrderWeights& weights) const {
  const double h = scheme_.timeStep();
  // s = (h₀/h)², t = h₀/h at h = h₀: s' = −2/h, s'' = 6/h², t' = −1/h, t'' = 2/h².
  const double s1 = -2.0 / h, s2 = 6.0 / (h * h), t1 = -1.0 / h, t2 = 2.0 / (h * h);
  const BoundaryPath start = boundaryPath(true), end = boundaryPath(false);
  const bool end_torques = scheme_.hasEndTorques();
  const std::vector<Matrix3> R = effects_ ? attitudes(steps_) : std::vector<Matrix3>();
  TimeStepStencil ts;
  return forEachStencil(
      true,
      [&](const Stencil& st) {
        static_cast<Stencil&>(ts) = st;
        const Vector3 w = weights ? weights(st.k, st.tau) : st.tau;
        // d' and d'' on the stencil's nodes k − 1, k, k + 1.
        Eigen::Matrix<double, 9, 1> e = Eigen::Matrix<double, 9, 1>::Zero(), e2 = e;
        for (int s = 0; s < 3; ++s) {
          const int j = st.k - 1 + s;
          if (!end_torques && j == 1) {
            e.segment<3>(3 * s) += start.first;
            e2.segment<3>(3 * s) += start.second;
          }
          if (!end_torques && j == N_ - 1) {
            e.segment<3>(3 * s) += end.first;
            e2.segment<3>(3 * s) += end.second;
          }
        }
        const double root = std::sqrt(scheme_.torqueWeight(st.k, N_));
        Vector3 beta = Vector3::Zero();
        if (end_torques && (st.k == 0 || st.k == N_)) {
          beta = st.k == 0 ? Vector3(-2.0 * root * initial_momentum_ / h)
                           : Vector3(2.0 * root * final_momentum_ / h);
        }
        // The dynamics' part ρ (scaled by s(h)) apart from the effects' ε (moved by t_k = k h).
        const EffectPart effect =
            effects_ ? effectPart(*effects_, R[st.k], st.k, h, root, st.k >= 1 && st.k < N_)
                     : EffectPart();
        const Vector3 rho = st.tau - effect.value;
        Eigen::Matrix<double, 3, 9> rho_jacobian = st.jacobian;
        rho_jacobian.block<3, 3>(0, 3) -= effect.jacobian;
        Eigen::Matrix<double, 9, 1> effect_h = Eigen::Matrix<double, 9, 1>::Zero();
        effect_h.segment<3>(3) = effect.jacobian_h.transpose() * w;  // ∂²(wᵀε)/∂δ_k∂h
        const Vector3 Je = st.jacobian * e;
        const Eigen::Matrix<double, 9, 1> He = st.second * e;
        ts.tau_h = s1 * rho + Je + (t1 - s1) * beta + effect.first;
        ts.second_h = s1 * (rho_jacobian.transpose() * w) + He + effect_h;
        ts.second_hh = s2 * w.dot(rho) + 2.0 * s1 * w.dot(rho_jacobian * e) + e.dot(He) +
                       w.dot(st.jacobian * e2) + (t2 - s2) * w.dot(beta) + 2.0 * effect_h.dot(e) +
                       w.dot(effect.second);
        visit(ts);
      },
      weights);
}

double ReducedProblem::evaluateWithTimeStep(const TranscriptionObjective& objective,
                                            Eigen::VectorXd* gradient, BandedSymmetricMatrix* band,
                                            Eigen::VectorXd* border, double* corner) const {
  const int n = unknowns();
  const double epsilon = objective.effortWeight();
  gradient->setZero(n + 1);
  if (band) {
    band->setZero();
    border->setZero(n);
    *corner = 0.0;
  }
  double cost = 0.0;
  if (epsilon != 0.0) {
    cost = forEachStencilWithTimeStep([&](const TimeStepStencil& st) {
      // As evaluate(), scaled by ε (exact for ε = 1), plus the h terms.
      const Eigen::Matrix<double, 9, 1> g = st.jacobian.transpose() * st.tau;
      const Eigen::Matrix<double, 9, 1> g_h = st.jacobian.transpose() * st.tau_h + st.second_h;
      for (int s = 0; s < 3; ++s) {
        const int v = variableIndex(st.k - 1 + s);
        if (v < 0) continue;
        gradient->segment<3>(v) += epsilon * g.segment<3>(3 * s);
        if (band) border->segment<3>(v) += epsilon * g_h.segment<3>(3 * s);
      }
      (*gradient)(n) += epsilon * st.tau.dot(st.tau_h);
      if (!band) return;
      *corner += epsilon * (st.tau_h.squaredNorm() + st.second_hh);
      const Eigen::Matrix<double, 9, 9> block =
          st.jacobian.transpose().lazyProduct(st.jacobian) + st.second;
      const int first_slot = std::max(0, first_free_ - (st.k - 1));
      const int last_slot = std::min(2, last_free_ - (st.k - 1));
      band->addSymmetricBlock<9>(3 * (st.k - 1 - first_free_),
                                 Eigen::Matrix<double, 9, 9>(epsilon * block), 3 * first_slot,
                                 3 * (last_slot + 1));
    });
  }
  // φ(T), T = N h: dΦ/dh = N φ', d²Φ/dh² = N² φ''.
  double phi_first = 0.0, phi_second = 0.0;
  const double phi = objective.timeTerm(N_ * scheme_.timeStep(), &phi_first, &phi_second);
  (*gradient)(n) += N_ * phi_first;
  if (band) *corner += double(N_) * N_ * phi_second;
  return epsilon * cost + phi;
}

}  // namespace attitude_planner
