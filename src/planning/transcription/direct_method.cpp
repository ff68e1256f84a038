#include "planning/transcription/direct_method.hpp"

#include <Eigen/Cholesky>
#include <Eigen/LU>

#include "attitude_planner/dynamics/simulation.hpp"
#include "attitude_planner/errors.hpp"

namespace attitude_planner {

std::vector<Vector3> torqueSequenceFromUnknowns(const Eigen::VectorXd& x) {
  const int interior = static_cast<int>(x.size()) / 3;  // N − 1
  std::vector<Vector3> torque(interior + 2, Vector3::Zero());
  for (int k = 1; k <= interior; ++k) torque[k] = x.segment<3>(3 * (k - 1));
  return torque;
}

Eigen::VectorXd unknownsFromTorqueSequence(const std::vector<Vector3>& torque) {
  const int interior = static_cast<int>(torque.size()) - 2;
  Eigen::VectorXd x(3 * std::max(interior, 0));
  for (int k = 1; k <= interior; ++k) x.segment<3>(3 * (k - 1)) = torque[k];
  return x;
}

Matrix3 carriedMomentumJacobian(const DiscreteScheme& scheme, const Matrix3& F) {
  // G(F exp ε^) = exp(−ε^) Fᵀ μ(F exp ε^) = Fᵀμ − ε × Fᵀμ + Fᵀ dμ ε + O(ε²)
  const Vector3 carried = F.transpose() * scheme.momentum<double>(F);
  return so3::hat(carried) + F.transpose() * scheme.momentumJacobian<double>(F);
}

TerminalConstraints evaluateTerminalConstraints(const PlanningProblem& problem,
                                                const Eigen::VectorXd& x, bool with_jacobian) {
  const int N = problem.steps;
  if (x.size() != 3 * (N - 1)) {
    throw InvalidInput("direct method: expected 3(N-1) = " + std::to_string(3 * (N - 1)) +
                       " unknowns, got " + std::to_string(x.size()));
  }
  const double h = problem.duration / N;
  const DiscreteScheme scheme(problem.scheme, problem.inertia, h);
  SimulationInput input;
  input.initial_attitude = problem.initial_attitude;
  input.initial_velocity = problem.initial_velocity;
  input.torque = torqueSequenceFromUnknowns(x);

  TerminalConstraints out;
  out.maneuver = simulate(scheme, input);
  const std::vector<Matrix3>& R = out.maneuver.attitude;
  const Vector3 attitude_miss = so3::log(Matrix3(problem.final_attitude.transpose() * R[N]));
  out.value.head<3>() = attitude_miss;
  out.value.tail<3>() = out.maneuver.angular_velocity[N - 1] - problem.final_velocity;
  if (!with_jacobian) return out;

  // F_k = R_kᵀ R_{k+1}: the relative rotations simulate() used (to round-off).
  std::vector<Matrix3> F(N);
  for (int k = 0; k < N; ++k) F[k] = R[k].transpose() * R[k + 1];

  // Terminal sensitivities: attitude row block acts on δθ_N, velocity row block on δF_{N−1}.
  const Matrix3 Y = so3::rightJacobianInverse(attitude_miss);
  Matrix3 V;
  if (problem.scheme == SchemeKind::Paper) {
    V = so3::rightJacobianInverse(so3::log(F[N - 1])) / h;  // Ω = log(F)/h
  } else {
    V = problem.inertia.inverse() * scheme.momentumJacobian<double>(F[N - 1]);  // Ω = J⁻¹μ(F)
  }

  // Adjoint sweep. δθ_N = Σ_j R_Nᵀ R_{j+1} δF_j, and δF_{k+1} = A_{k+1} δF_k + B_{k+1} δτ_{k+1}
  // with A_k = dμ(F_k)⁻¹ dG(F_{k−1}), B_k = h dμ(F_k)⁻¹. Λ_k = dc/dδF_k (6×3), total.
  out.jacobian.resize(kTerminalConstraints, 3 * (N - 1));
  using Block = Eigen::Matrix<double, kTerminalConstraints, 3>;
  Block lambda;
  Matrix3 dmu_inverse = scheme.momentumJacobian<double>(F[N - 1]).inverse();
  lambda.topRows<3>() = Y;  // R_Nᵀ R_N = I
  lambda.bottomRows<3>() = V;
  for (int k = N - 1; k >= 1; --k) {
    const Block lambda_dinv = lambda * dmu_inverse;  // Λ_k dμ(F_k)⁻¹
    out.jacobian.block<kTerminalConstraints, 3>(0, 3 * (k - 1)) = h * lambda_dinv;
    if (k == 1) break;
    const Block propagated = lambda_dinv * carriedMomentumJacobian(scheme, F[k - 1]);
    dmu_inverse = scheme.momentumJacobian<double>(F[k - 1]).inverse();
    lambda.topRows<3>() = Y * (R[N].transpose() * R[k]);
    lambda.bottomRows<3>().setZero();
    lambda += propagated;
  }
  return out;
}

Eigen::VectorXd stationarityResidual(const Eigen::VectorXd& x, const Eigen::MatrixXd& C) {
  const Eigen::MatrixXd CCt = C * C.transpose();
  const Eigen::VectorXd multipliers = CCt.ldlt().solve(C * x);
  return x - C.transpose() * multipliers;
}

}  // namespace attitude_planner
