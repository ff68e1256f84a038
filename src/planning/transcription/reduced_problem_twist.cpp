// ReducedProblem with the twist ψ of a pointing end condition as a global unknown (declarations
// and the model in reduced_problem.hpp). The twist moves the fixed attitudes by
//
//     R_N → R_N exp(Δψ b^),   R_{N−1} = R_N F_{N−1}ᵀ → R_{N−1} exp(Δψ (F_{N−1} b)^)
//
// (the second for paper and variational, whose last step F_{N−1} carries Ω(T) and is kept: it is
// exp(−Δψ (Fb)^) F exp(Δψ b^) = F exactly). Both are straight lines x(ψ) = ψ e in the nodes'
// right-perturbation coordinates, so with H the (symmetric) Hessian of C in those coordinates
// and g its gradient, including the fixed nodes' columns as the stencils carry them,
//     ∂C/∂ψ = gᵀe,  ∂²C/∂δ∂ψ = (H e)_free,  ∂²C/∂ψ² = eᵀ H e,
// exactly (test_pointing.cpp checks all three against central differences for every scheme).
#include <algorithm>

#include "planning/transcription/reduced_problem.hpp"

namespace attitude_planner {

Vector3 ReducedProblem::twistMotion(int j) const {
  if (!hasTwist()) return Vector3::Zero();
  if (j == N_) return twist_axis_;
  if (j == N_ - 1 && !scheme_.hasEndTorques()) return so3::exp(steps_[N_ - 1]) * twist_axis_;
  return Vector3::Zero();
}

double ReducedProblem::evaluateWithTwist(Eigen::VectorXd* gradient, BandedSymmetricMatrix* band,
                                         Eigen::VectorXd* border, double* corner,
                                         double* gradient_scale) const {
  const int n = unknowns();
  gradient->setZero(n + 1);
  if (band) {
    band->setZero();
    border->setZero(n);
    *corner = 0.0;
  }
  double jacobian_scale = 0.0, torque_scale = 0.0;
  const double cost = forEachStencil(band != nullptr, [&](const Stencil& st) {
    jacobian_scale = std::max(jacobian_scale, st.jacobian.cwiseAbs().maxCoeff());
    torque_scale = std::max(torque_scale, st.tau.cwiseAbs().maxCoeff());
    Eigen::Matrix<double, 9, 1> e;  // the twist's motion of the stencil's nodes
    for (int s = 0; s < 3; ++s) e.segment<3>(3 * s) = twistMotion(st.k - 1 + s);
    const Eigen::Matrix<double, 9, 1> g = st.jacobian.transpose() * st.tau;
    (*gradient)(n) += g.dot(e);
    Eigen::Matrix<double, 9, 9> block;
    Eigen::Matrix<double, 9, 1> block_e;
    if (band) {
      block = st.jacobian.transpose().lazyProduct(st.jacobian) + st.second;
      block_e = block * e;
      *corner += e.dot(block_e);
    }
    for (int s = 0; s < 3; ++s) {
      const int v = variableIndex(st.k - 1 + s);
      if (v < 0) continue;
      gradient->segment<3>(v) += g.segment<3>(3 * s);
      if (band) border->segment<3>(v) += block_e.segment<3>(3 * s);
    }
    if (!band) return;
    const int first_slot = std::max(0, first_free_ - (st.k - 1));
    const int last_slot = std::min(2, last_free_ - (st.k - 1));
    band->addSymmetricBlock<9>(3 * (st.k - 1 - first_free_), block, 3 * first_slot,
                               3 * (last_slot + 1));
  });
  *gradient_scale = jacobian_scale * std::max(torque_scale, 1e-300);
  return cost;
}

ReducedProblem::StepVectors ReducedProblem::retractWithTwist(const Eigen::VectorXd& delta,
                                                             double twist_step,
                                                             double alpha) const {
  return movedSteps([&](int j) {
    const int v = variableIndex(j);
    if (v >= 0) return Vector3(alpha * delta.segment<3>(v));
    return Vector3(alpha * twist_step * twistMotion(j));
  });
}

void ReducedProblem::setCurrentWithTwist(const StepVectors& steps, double twist_step) {
  steps_ = steps;
  final_attitude_ = final_attitude_ * so3::exp(Vector3(twist_step * twist_axis_));
}

}  // namespace attitude_planner
