#include "attitude_planner/dynamics/simulation.hpp"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <sstream>

#include "attitude_planner/errors.hpp"

namespace attitude_planner {

Matrix3 reorthonormalize(const Matrix3& R) {
  return 0.5 * R * (3.0 * Matrix3::Identity() - R.transpose() * R);
}

namespace {

/// A maneuver on the uniform grid t_k = k h, k = 0..N, carrying `torque`, its attitudes and
/// velocities to be filled.
Maneuver nodeGrid(int N, double h, const std::vector<Vector3>& torque) {
  Maneuver m;
  m.time_step = h;
  m.time.resize(N + 1);
  m.attitude.resize(N + 1);
  m.angular_velocity.resize(N + 1);
  m.torque = torque;
  for (int k = 0; k <= N; ++k) m.time[k] = k * h;
  return m;
}

/// The integrator loop, specialized at compile time on whether anything acts besides the control
/// (so an absent effect costs nothing per step: no branch, no zero evaluation).
template <bool kWithEffects>
Maneuver integrate(const DiscreteScheme& scheme, const SimulationInput& input,
                   SimulationReport* report) {
  const int N = static_cast<int>(input.torque.size()) - 1;
  const double h = scheme.timeStep();
  Maneuver m = nodeGrid(N, h, input.torque);

  SimulationReport local;
  // What the body receives at node k: the commanded torque after actuation (recorded), plus the
  // effects at (R_k, t_k). Called once per node in increasing k (actuation noise advances).
  const auto applied_at = [&](int k) {
    Vector3 applied = input.torque[k];
    if constexpr (kWithEffects) {
      if (input.actuation) applied = input.actuation->apply(applied);
      m.torque[k] = applied;
      if (input.effects) applied += input.effects->torque(m.attitude[k], m.time[k]);
    }
    return applied;
  };
  const auto solve_step = [&](int k, const Vector3& p, const Matrix3& guess) {
    StepSolveReport step;
    const Matrix3 F_k = scheme.solveStep(p, guess, &step);
    if (!step.converged) {
      std::ostringstream msg;
      msg << "step too large, increase steps: implicit step k = " << k
          << " did not converge (|p| = " << p.norm() << " N m s, h = " << h << " s, residual "
          << step.residual << ")";
      throw StepTooLarge(msg.str());
    }
    local.max_step_iterations = std::max(local.max_step_iterations, step.iterations);
    local.max_step_residual = std::max(local.max_step_residual, step.residual);
    return F_k;
  };
  // With end torques (second_order) the node velocity is J⁻¹ Π_k, the node momentum between the
  // two half impulses: Π_k = F_{k−1}ᵀ μ(F_{k−1}) + (h/2) τ_k (discrete_scheme.hpp).
  const bool end_torques = scheme.hasEndTorques();
  const Matrix3 J_inverse = scheme.inertia().inverse();
  m.attitude[0] = input.initial_attitude;
  m.angular_velocity[0] = input.initial_velocity;
  Matrix3 F;  // F_0
  Vector3 spatial_momentum;
  if (end_torques) {
    // Π_0 = J Ω(0) = μ(F_0) − (h/2) τ_0
    const Vector3 p = scheme.inertia() * input.initial_velocity + 0.5 * h * applied_at(0);
    F = solve_step(0, p, so3::exp(Vector3(h * input.initial_velocity)));
    spatial_momentum = input.initial_attitude * p;
  } else {
    F = scheme.stepFromVelocity(input.initial_velocity);
    spatial_momentum = input.initial_attitude * scheme.momentum<double>(F);
  }
  m.attitude[1] = reorthonormalize(input.initial_attitude * F);
  // The momentum is carried in the world frame, π_k = R_k μ(F_k): identical to the body-frame
  // recursion μ(F_k) = F_{k−1}ᵀ μ(F_{k−1}) + h τ_k in exact arithmetic, but torque-free it is
  // then conserved bit for bit instead of accumulating a rounding bias every step.
  for (int k = 1; k < N; ++k) {
    const Vector3 applied = applied_at(k);
    const Vector3 p = m.attitude[k].transpose() * spatial_momentum + h * applied;
    F = solve_step(k, p, F);
    m.attitude[k + 1] = reorthonormalize(m.attitude[k] * F);
    m.angular_velocity[k] =
        end_torques ? Vector3(J_inverse * (p - 0.5 * h * applied)) : scheme.velocity(F);
    if (!applied.isZero(0.0)) spatial_momentum = m.attitude[k] * p;
  }
  if (end_torques) {
    // Π_N = F_{N−1}ᵀ μ(F_{N−1}) + (h/2) τ_N = J Ω(T)
    const Vector3 applied = applied_at(N);
    m.angular_velocity[N] =
        J_inverse * (m.attitude[N].transpose() * spatial_momentum + 0.5 * h * applied);
  } else {
    m.angular_velocity[N] = m.angular_velocity[N - 1];
  }
  if (report) *report = local;
  return m;
}

}  // namespace

Maneuver simulate(const DiscreteScheme& scheme, const SimulationInput& input,
                  SimulationReport* report) {
  const int N = static_cast<int>(input.torque.size()) - 1;
  if (N < 1) {
    throw InvalidInput("torque: need at least 2 entries (k = 0..N), got " +
                       std::to_string(input.torque.size()));
  }
  if (!scheme.hasEndTorques() &&
      (!input.torque.front().isZero(0.0) || !input.torque.back().isZero(0.0))) {
    throw InvalidInput("torque: tau_0 and tau_N must be zero with scheme " +
                       schemeName(scheme.kind()) + " (they do not enter eq. (18))");
  }
  const bool with_effects =
      (input.effects && !input.effects->empty()) || (input.actuation && !input.actuation->empty());
  return with_effects ? integrate<true>(scheme, input, report)
                      : integrate<false>(scheme, input, report);
}

std::array<Vector3, 4> cubicHoldCoefficients(const std::vector<Vector3>& torque, int k, double h) {
  const int N = static_cast<int>(torque.size()) - 1;
  if (N < 3 || k < 0 || k >= N) {
    throw InvalidInput("cubic hold: needs N >= 3 and 0 <= k < N, got N = " + std::to_string(N) +
                       ", k = " + std::to_string(k));
  }
  const int first = std::min(std::max(k - 1, 0), N - 3);  // nodes first..first+3
  // τ(t_k + σh) = Σ_j a_j σ^j through σ_i = first + i − k; then c_j = a_j / h^j.
  Eigen::Matrix4d V;
  for (int i = 0; i < 4; ++i) {
    const double sigma = first + i - k;
    for (int j = 0; j < 4; ++j) V(i, j) = std::pow(sigma, j);
  }
  const Eigen::Matrix4d L = V.inverse();  // a = L · (τ_first..τ_first+3)
  std::array<Vector3, 4> c;
  double scale = 1.0;
  for (int j = 0; j < 4; ++j) {
    c[j] = Vector3::Zero();
    for (int i = 0; i < 4; ++i) c[j] += L(j, i) * torque[first + i];
    c[j] /= scale;
    scale *= h;
  }
  return c;
}

namespace {

/// fourth_order's replay: the continuous body under the cubic hold, RKMK4 (replayPlan).
Maneuver integrateCubicHold(const Matrix3& inertia, double h, const SimulationInput& input) {
  const int N = static_cast<int>(input.torque.size()) - 1;
  Maneuver m = nodeGrid(N, h, input.torque);
  if (input.actuation && !input.actuation->empty()) {
    for (int k = 0; k <= N; ++k) m.torque[k] = input.actuation->apply(input.torque[k]);
  }
  const bool with_effects = input.effects && !input.effects->empty();
  const Matrix3 J_inverse = inertia.inverse();
  m.attitude[0] = input.initial_attitude;
  m.angular_velocity[0] = input.initial_velocity;
  for (int k = 0; k < N; ++k) {
    const std::array<Vector3, 4> c = cubicHoldCoefficients(m.torque, k, h);
    const Matrix3& R = m.attitude[k];
    const Vector3& W = m.angular_velocity[k];
    // (u̇, Ω̇) at R_k exp(u^), Ω, time t_k + s.
    const auto f = [&](const Vector3& u, const Vector3& w, double s, Vector3* du, Vector3* dw) {
      Vector3 tau = c[0] + s * (c[1] + s * (c[2] + s * c[3]));
      if (with_effects) tau += input.effects->torque(R * so3::exp(u), m.time[k] + s);
      *du = so3::rightJacobianInverse(u) * w;
      *dw = J_inverse * ((inertia * w).cross(w) + tau);
    };
    Vector3 u1, w1, u2, w2, u3, w3, u4, w4;
    f(Vector3::Zero(), W, 0.0, &u1, &w1);
    f(0.5 * h * u1, W + 0.5 * h * w1, 0.5 * h, &u2, &w2);
    f(0.5 * h * u2, W + 0.5 * h * w2, 0.5 * h, &u3, &w3);
    f(h * u3, W + h * w3, h, &u4, &w4);
    const Vector3 u = h / 6.0 * (u1 + 2.0 * u2 + 2.0 * u3 + u4);
    m.attitude[k + 1] = reorthonormalize(R * so3::exp(u));
    m.angular_velocity[k + 1] = W + h / 6.0 * (w1 + 2.0 * w2 + 2.0 * w3 + w4);
  }
  return m;
}

}  // namespace

Maneuver replayPlan(SchemeKind kind, const Matrix3& inertia, double time_step,
                    const SimulationInput& input, SimulationReport* report) {
  if (schemeIsDiscretization(kind)) {
    return simulate(DiscreteScheme(kind, inertia, time_step), input, report);
  }
  const int N = static_cast<int>(input.torque.size()) - 1;
  if (N < 3) {
    throw InvalidInput("torque: the cubic hold of scheme " + schemeName(kind) +
                       " needs at least 4 entries (k = 0..N, N >= 3), got " +
                       std::to_string(input.torque.size()));
  }
  if (report) *report = SimulationReport{};
  return integrateCubicHold(inertia, time_step, input);
}

}  // namespace attitude_planner
