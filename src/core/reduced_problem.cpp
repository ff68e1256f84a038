#include "attitude_planner/reduced_problem.hpp"

#include <optional>

#include "attitude_planner/dual.hpp"
#include "attitude_planner/errors.hpp"

namespace attitude_planner {

namespace {

using Dual3 = Dual<3>;

/// What one step F_j contributes to the torques next to it, and to their Jacobians
/// (right perturbation F exp(ε^); D = dμ/dε, G = Fᵀμ, dG = dG/dε = (Fᵀμ)^ + FᵀD):
///   τ_k = (μ_k − G_{k−1})/h
///   ∂τ_k/∂(δ_{k−1}, δ_k, δ_{k+1}) = [dG_{k−1}F_{k−1}ᵀ, −(D_k F_kᵀ + dG_{k−1}), D_k] / h,
/// from F_{k−1} → F_{k−1} exp(δ_k − F_{k−1}ᵀ δ_{k−1}) and F_k → F_k exp(δ_{k+1} − F_kᵀ δ_k).
template <typename S>
struct StepTerms {
  so3::Vec3<S> mu, G;
  so3::Mat3<S> D, dG, DFt, dGFt;

  StepTerms(const DiscreteScheme& scheme, const so3::Mat3<S>& F) {
    mu = scheme.momentum<S>(F);
    G = F.transpose() * mu;
    D = scheme.momentumJacobian<S>(F);
    dG = so3::hat<S>(G) + F.transpose() * D;
    DFt = D * F.transpose();
    dGFt = dG * F.transpose();
  }
};

/// F exp(ε^) to first order in a dual ε (value 0, unit derivatives): F + Σ_e ε_e F ê_e^.
so3::Mat3<Dual3> perturbed(const Matrix3& F) {
  so3::Mat3<Dual3> Fd;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) Fd(r, c) = Dual3(F(r, c));
  }
  for (int e = 0; e < 3; ++e) {
    const Matrix3 dF = F * so3::hat(Vector3(Vector3::Unit(e)));
    for (int r = 0; r < 3; ++r) {
      for (int c = 0; c < 3; ++c) Fd(r, c).d(e) = dF(r, c);
    }
  }
  return Fd;
}

/// T(m, e) = Σ_i τ_i ∂X(i, m)/∂ε_e: the τ-weighted derivative of a Jacobian block.
Matrix3 contract(const so3::Mat3<Dual3>& X, const Vector3& tau) {
  Matrix3 T = Matrix3::Zero();
  for (int i = 0; i < 3; ++i) {
    for (int m = 0; m < 3; ++m) T.row(m) += tau(i) * X(i, m).d.transpose();
  }
  return T;
}

}  // namespace

ReducedProblem::ReducedProblem(const PlanningProblem& problem)
    : N_(problem.steps),
      scheme_(problem.scheme, problem.inertia, problem.duration / problem.steps) {
  R_.assign(N_ + 1, Matrix3::Identity());
  R_[0] = problem.initial_attitude;
  R_[1] = problem.initial_attitude * scheme_.stepFromVelocity(problem.initial_velocity);
  R_[N_] = problem.final_attitude;
  R_[N_ - 1] =
      problem.final_attitude * scheme_.stepFromVelocity(problem.final_velocity).transpose();
  initializeOnGeodesic();
}

void ReducedProblem::setInterior(const std::vector<Matrix3>& attitudes) {
  if (static_cast<int>(attitudes.size()) != N_ + 1) {
    throw InvalidInput("warm start: has " + std::to_string(attitudes.size() - 1) +
                       " steps, the problem " + std::to_string(N_));
  }
  for (int j = 2; j <= N_ - 2; ++j) R_[j] = attitudes[j];
}

void ReducedProblem::initializeOnGeodesic() {
  const Vector3 span = so3::log(Matrix3(R_[1].transpose() * R_[N_ - 1]));
  for (int j = 2; j <= N_ - 2; ++j) {
    R_[j] = R_[1] * so3::exp(Vector3(span * double(j - 1) / double(N_ - 2)));
  }
}

std::vector<Vector3> ReducedProblem::torques(const std::vector<Matrix3>& R) const {
  std::vector<Vector3> tau(N_ + 1, Vector3::Zero());
  const double h = scheme_.timeStep();
  Matrix3 F = R[0].transpose() * R[1];
  Vector3 carried = F.transpose() * scheme_.momentum<double>(F);  // G_{k−1}
  for (int k = 1; k < N_; ++k) {
    F = R[k].transpose() * R[k + 1];
    const Vector3 mu = scheme_.momentum<double>(F);
    tau[k] = (mu - carried) / h;
    carried = F.transpose() * mu;
  }
  return tau;
}

double ReducedProblem::cost(const std::vector<Matrix3>& R) const {
  double c = 0;
  for (const Vector3& t : torques(R)) c += 0.5 * t.squaredNorm();
  return c;
}

std::vector<Matrix3> ReducedProblem::retract(const Eigen::VectorXd& delta, double alpha) const {
  std::vector<Matrix3> R = R_;
  for (int j = 2; j <= N_ - 2; ++j) {
    R[j] = R_[j] * so3::exp(Vector3(alpha * delta.segment<3>(variableIndex(j))));
  }
  return R;
}

double ReducedProblem::evaluate(Eigen::VectorXd* gradient, BandedSymmetricMatrix* hessian,
                                double* gradient_scale) const {
  const double h = scheme_.timeStep();
  gradient->setZero(unknowns());
  if (hessian) hessian->setZero();
  double cost = 0.0, jacobian_scale = 0.0, torque_scale = 0.0;
  // Rolling window over steps: `prev` holds F_{k−1}'s terms, `next` F_k's (each F once).
  const auto step = [&](int j) { return Matrix3(R_[j].transpose() * R_[j + 1]); };
  const auto terms_of = [&](int j) { return StepTerms<Dual3>(scheme_, perturbed(step(j))); };
  std::optional<StepTerms<Dual3>> prev_d;  // derivatives are formed only for the Hessian
  if (hessian) prev_d.emplace(terms_of(0));
  StepTerms<double> prev(scheme_, step(0));
  for (int k = 1; k < N_; ++k) {
    const Matrix3 F_prev = R_[k - 1].transpose() * R_[k];
    const Matrix3 F = R_[k].transpose() * R_[k + 1];
    StepTerms<double> next(scheme_, F);
    const Vector3 tau = (next.mu - prev.G) / h;
    Eigen::Matrix<double, 3, 9> jac;
    jac.block<3, 3>(0, 0) = prev.dGFt / h;
    jac.block<3, 3>(0, 3) = -(next.DFt + prev.dG) / h;
    jac.block<3, 3>(0, 6) = next.D / h;
    const Eigen::Matrix<double, 9, 1> g = jac.transpose() * tau;
    cost += 0.5 * tau.squaredNorm();
    jacobian_scale = std::max(jacobian_scale, jac.cwiseAbs().maxCoeff());
    torque_scale = std::max(torque_scale, tau.cwiseAbs().maxCoeff());
    for (int s = 0; s < 3; ++s) {
      const int v = variableIndex(k - 1 + s);
      if (v >= 0) gradient->segment<3>(v) += g.segment<3>(3 * s);
    }
    if (!hessian) {
      prev = next;
      continue;
    }
    StepTerms<Dual3> next_d = terms_of(k);
    // second(m, l) = Σ_i τ_i ∂jac(i, m)/∂δ_l by the chain rule through ε_{k−1}, ε_k.
    Eigen::Matrix<double, 9, 9> second = Eigen::Matrix<double, 9, 9>::Zero();
    const Matrix3 T_dGFt_prev = contract(prev_d->dGFt, tau) / h;  // block a, via ε_{k−1}
    const Matrix3 T_dG_prev = -contract(prev_d->dG, tau) / h;     // block b, via ε_{k−1}
    const Matrix3 T_DFt = -contract(next_d.DFt, tau) / h;         // block b, via ε_k
    const Matrix3 T_D = contract(next_d.D, tau) / h;              // block c, via ε_k
    second.block<3, 3>(0, 0) = -T_dGFt_prev * F_prev.transpose();
    second.block<3, 3>(0, 3) = T_dGFt_prev;
    second.block<3, 3>(3, 0) = -T_dG_prev * F_prev.transpose();
    second.block<3, 3>(3, 3) = T_dG_prev - T_DFt * F.transpose();
    second.block<3, 3>(3, 6) = T_DFt;
    second.block<3, 3>(6, 3) = -T_D * F.transpose();
    second.block<3, 3>(6, 6) = T_D;
    // The antisymmetric part of `second` is cancelled exactly by the retraction's derivative
    // (dJr(δ)/dδ = −½(·)^ contracted with the gradient), so the exact Hessian is:
    const Eigen::Matrix<double, 9, 9> block =
        jac.transpose().lazyProduct(jac) + 0.5 * (second + second.transpose());
    for (int s = 0; s < 3; ++s) {
      const int vs = variableIndex(k - 1 + s);
      if (vs < 0) continue;
      for (int t = 0; t <= s; ++t) {
        const int vt = variableIndex(k - 1 + t);
        if (vt < 0) continue;
        for (int i = 0; i < 3; ++i) {
          for (int j = 0; j < (s == t ? i + 1 : 3); ++j) {
            hessian->add(vs + i, vt + j, block(3 * s + i, 3 * t + j));
          }
        }
      }
    }
    prev_d.emplace(next_d);
    prev = next;
  }
  *gradient_scale = jacobian_scale * std::max(torque_scale, 1e-300);
  return cost;
}

}  // namespace attitude_planner
