// Continuous-time reference: Pontryagin extremal flow + multiple shooting
// (continuous_reference.hpp).
#include "attitude_planner/analysis/continuous_reference.hpp"

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <sstream>

#include "analysis/extrapolation_integrator.hpp"
#include "attitude_planner/errors.hpp"
#include "lie/dual.hpp"
#include "planning/problem/message_notes.hpp"

namespace attitude_planner {
namespace {

using Quaternion4 = Eigen::Vector4d;  // (w, x, y, z)

/// Extremal state (q, Ω, π, ν, c): unit quaternion of R, body velocity, costates, running cost.
template <typename S>
using Flow = Eigen::Matrix<S, 14, 1>;

/// The extremal vector field (header comment; τ = −ν).
template <typename S>
Flow<S> extremalField(const Matrix3& J_d, const Matrix3& J_inverse_d, const Flow<S>& x) {
  const so3::Mat3<S> J = J_d.cast<S>();
  const so3::Mat3<S> J_inverse = J_inverse_d.cast<S>();
  const Eigen::Matrix<S, 4, 1> q = x.template head<4>();
  const so3::Vec3<S> Omega = x.template segment<3>(4);
  const so3::Vec3<S> pi = x.template segment<3>(7);
  const so3::Vec3<S> nu = x.template segment<3>(10);
  const so3::Vec3<S> M = J * Omega;  // body angular momentum
  Eigen::Matrix<S, 4, 1> omega_q;
  omega_q << S(0), Omega(0), Omega(1), Omega(2);
  Flow<S> dx;
  dx.template head<4>() = S(0.5) * so3::quaternionProduct<S>(q, omega_q);  // q̇ = ½ q ⊗ (0, Ω)
  dx.template segment<3>(4) = J_inverse * (M.cross(Omega) - nu);           // Euler, τ = −ν
  dx.template segment<3>(7) = pi.cross(Omega);                             // π̇ = π × Ω
  dx.template segment<3>(10) = J_inverse * (M.cross(nu) - J * Omega.cross(nu) - pi);
  dx(13) = S(0.5) * nu.squaredNorm();
  return dx;
}

/// Integrates the extremal flow over `duration` in `steps` GBS macro steps; |q| renormalized.
template <typename S>
Flow<S> integrateFlow(const Matrix3& J, const Matrix3& J_inverse, Flow<S> x, double duration,
                      int steps) {
  const auto f = [&](const Flow<S>& y) { return extremalField<S>(J, J_inverse, y); };
  const double H = duration / steps;
  for (int i = 0; i < steps; ++i) {
    x = extrapolationStep(f, x, H);
    const S norm = x.template head<4>().norm();
    x.template head<4>() /= norm;
  }
  return x;
}

Flow<double> flowOfState(const ContinuousState& s) {
  Flow<double> x;
  x.head<4>() = so3::quaternionCoefficients<double>(s.attitude);
  x.segment<3>(4) = s.angular_velocity;
  x.segment<3>(7) = s.costate_attitude;
  x.segment<3>(10) = s.costate_velocity;
  x(13) = s.cost;
  return x;
}

ContinuousState stateOfFlow(const Flow<double>& x, double t) {
  ContinuousState s;
  s.t = t;
  s.attitude = so3::matrixFromQuaternion<double>(x.head<4>());
  s.angular_velocity = x.segment<3>(4);
  s.costate_attitude = x.segment<3>(7);
  s.costate_velocity = x.segment<3>(10);
  s.cost = x(13);
  return s;
}

/// Rotation vector of conj(a) ⊗ b, i.e. log(R_aᵀ R_b); scale-invariant in b.
template <typename S>
so3::Vec3<S> relativeRotation(const Quaternion4& a, const Eigen::Matrix<S, 4, 1>& b) {
  Eigen::Matrix<S, 4, 1> a_conjugate;
  a_conjugate << S(a(0)), S(-a(1)), S(-a(2)), S(-a(3));
  return so3::logOfQuaternion<S>(so3::quaternionProduct<S>(a_conjugate, b));
}

double hamiltonian(const Matrix3& J, const ContinuousState& s) {
  const Vector3& W = s.angular_velocity;
  const Vector3& nu = s.costate_velocity;
  return -0.5 * nu.squaredNorm() + s.costate_attitude.dot(W) + nu.dot((J * W).cross(W));
}

/// Node states of the shooting grid guessed from a discrete plan (header: τ ≈ −ν, π from the
/// ν equation with ν̇ by differences). Discrete Ω_k is the velocity over step k, so a node gets
/// the mean of its two steps; τ_0 = τ_N = 0 are boundary artefacts, extrapolated instead.
std::vector<ContinuousState> guessNodes(const PlanningProblem& problem, const Maneuver& plan,
                                        int segments) {
  const int N = plan.steps();
  const double h = problem.duration / N;
  const auto torque = [&](int k) -> Vector3 {
    if (k <= 0) return 2.0 * plan.torque[1] - plan.torque[2];
    if (k >= N) return 2.0 * plan.torque[N - 1] - plan.torque[N - 2];
    return plan.torque[k];
  };
  const Matrix3& J = problem.inertia;
  std::vector<ContinuousState> nodes;
  for (int m = 0; m < segments; ++m) {
    const double t = problem.duration * m / segments;
    const int k = std::min(N - 1, static_cast<int>(std::lround(t / h)));
    ContinuousState s;
    s.t = t;
    s.attitude = plan.attitude[k];
    s.angular_velocity = k == 0 ? problem.initial_velocity
                                : 0.5 * (plan.angular_velocity[k - 1] + plan.angular_velocity[k]);
    const Vector3 nu = -torque(k);
    const Vector3 nu_dot = -(torque(k + 1) - torque(k - 1)) / (2.0 * h);
    const Vector3& W = s.angular_velocity;
    s.costate_velocity = nu;
    s.costate_attitude = -J * nu_dot - J * W.cross(nu) + (J * W).cross(nu);
    nodes.push_back(s);
  }
  nodes[0].attitude = problem.initial_attitude;
  return nodes;
}

constexpr int kStateDim = 12;  // perturbation of a node: δR (right), δΩ, δπ, δν

}  // namespace

ContinuousState propagateExtremal(const Matrix3& inertia, const ContinuousState& start,
                                  double duration, int macro_steps) {
  if (duration == 0.0 || macro_steps < 1) return start;
  const Flow<double> x =
      integrateFlow<double>(inertia, inertia.inverse(), flowOfState(start), duration, macro_steps);
  return stateOfFlow(x, start.t + duration);
}

void propagateRigidBody(const Matrix3& inertia, const Vector3& torque, double duration,
                        int macro_steps, Matrix3* attitude, Vector3* angular_velocity) {
  propagateRigidBody(inertia, torque, torque, duration, macro_steps, attitude, angular_velocity);
}

void propagateRigidBody(const Matrix3& inertia, const Vector3& torque_start,
                        const Vector3& torque_end, double duration, int macro_steps,
                        Matrix3* attitude, Vector3* angular_velocity) {
  const Vector3 slope =
      duration > 0 ? Vector3((torque_end - torque_start) / duration) : Vector3::Zero().eval();
  propagateRigidBody(inertia, {torque_start, slope, Vector3::Zero(), Vector3::Zero()}, duration,
                     macro_steps, attitude, angular_velocity);
}

void propagateRigidBody(const Matrix3& inertia, const std::array<Vector3, 4>& c, double duration,
                        int macro_steps, Matrix3* attitude, Vector3* angular_velocity) {
  using State = Eigen::Matrix<double, 8, 1>;  // (q, Ω, s): time makes the torque autonomous
  const Matrix3 J_inverse = inertia.inverse();
  const auto f = [&](const State& x) {
    const Vector3 W = x.segment<3>(4);
    const double s = x(7);
    State dx;
    dx.head<4>() =
        0.5 * so3::quaternionProduct<double>(x.head<4>(), Quaternion4(0, W(0), W(1), W(2)));
    const Vector3 tau = c[0] + s * (c[1] + s * (c[2] + s * c[3]));
    dx.segment<3>(4) = J_inverse * ((inertia * W).cross(W) + tau);
    dx(7) = 1.0;
    return dx;
  };
  State x;
  x.head<4>() = so3::quaternionCoefficients<double>(*attitude);
  x.segment<3>(4) = *angular_velocity;
  x(7) = 0.0;
  const double H = duration / macro_steps;
  for (int i = 0; i < macro_steps; ++i) {
    x = extrapolationStep(f, x, H);
    x.head<4>().normalize();
  }
  *attitude = so3::matrixFromQuaternion<double>(x.head<4>());
  *angular_velocity = x.segment<3>(4);
}

namespace {

/// Multiple shooting on the extremal flow: M segments of `span` seconds, each integrated in
/// `steps` macro steps. Unknowns: (π_0, ν_0) and the inner nodes' (δR, δΩ, δπ, δν).
struct Shooting {
  Shooting(const PlanningProblem& problem, int M, int steps)
      : problem(problem),
        J(problem.inertia),
        J_inverse(problem.inertia.inverse()),
        M(M),
        steps(steps),
        span(problem.duration / M),
        q_final(so3::quaternionCoefficients<double>(problem.final_attitude)),
        n(6 + kStateDim * (M - 1)) {}

  /// Defects (and, given `jacobian`, their Jacobian) at the nodes.
  void evaluate(const std::vector<ContinuousState>& nodes, Eigen::VectorXd* defect,
                Eigen::MatrixXd* jacobian) const {
    defect->setZero(n);
    if (jacobian) jacobian->setZero(n, n);
    for (int m = 0; m < M; ++m) {
      if (jacobian) {
        segmentWithJacobian(nodes, m, defect, jacobian);
      } else {
        segmentDefect(nodes, m, defect);
      }
    }
  }

  /// The nodes moved by alpha·step (attitudes on the group).
  std::vector<ContinuousState> apply(const std::vector<ContinuousState>& from,
                                     const Eigen::VectorXd& step, double alpha) const {
    std::vector<ContinuousState> to = from;
    to[0].costate_attitude += alpha * step.segment<3>(0);
    to[0].costate_velocity += alpha * step.segment<3>(3);
    for (int m = 1; m < M; ++m) {
      const Eigen::Matrix<double, kStateDim, 1> s =
          alpha * step.segment<kStateDim>(6 + 12 * (m - 1));
      to[m].attitude = from[m].attitude * so3::exp(Vector3(s.segment<3>(0)));
      to[m].angular_velocity += s.segment<3>(3);
      to[m].costate_attitude += s.segment<3>(6);
      to[m].costate_velocity += s.segment<3>(9);
    }
    return to;
  }

  const PlanningProblem& problem;
  const Matrix3& J;
  const Matrix3 J_inverse;
  const int M;
  const int steps;
  const double span;
  const Quaternion4 q_final;
  const int n;

 private:
  using D = Dual<kStateDim>;

  Quaternion4 target(const std::vector<ContinuousState>& nodes, int m) const {
    return m == M - 1 ? q_final
                      : Quaternion4(so3::quaternionCoefficients<double>(nodes[m + 1].attitude));
  }

  void segmentDefect(const std::vector<ContinuousState>& nodes, int m,
                     Eigen::VectorXd* defect) const {
    const int row = kStateDim * m;
    const Flow<double> x1 = integrateFlow<double>(J, J_inverse, flowOfState(nodes[m]), span, steps);
    defect->segment<3>(row) = relativeRotation<double>(target(nodes, m), x1.head<4>());
    if (m == M - 1) {
      defect->segment<3>(row + 3) = x1.segment<3>(4) - problem.final_velocity;
    } else {
      defect->segment<9>(row + 3) = x1.segment<9>(4) - flowOfState(nodes[m + 1]).segment<9>(4);
    }
  }

  void segmentWithJacobian(const std::vector<ContinuousState>& nodes, int m,
                           Eigen::VectorXd* defect, Eigen::MatrixXd* jacobian) const {
    const Flow<double> x0 = flowOfState(nodes[m]);
    const int row = kStateDim * m;
    const bool last = m == M - 1;
    // Seed the start perturbation: R exp(ε_R^) (quaternion q ⊗ q(ε_R)), Ω + ε_Ω, π + ε_π, ν +
    // ε_ν.
    Flow<D> y;
    so3::Vec3<D> eps_R;
    for (int i = 0; i < 3; ++i) eps_R(i) = D(0.0, i);
    y.head<4>() = so3::quaternionProduct<D>(x0.head<4>().cast<D>(),
                                            so3::quaternionOfRotationVector<D>(eps_R));
    for (int i = 0; i < 9; ++i) y(4 + i) = D(x0(4 + i), 3 + i);
    y(13) = D(x0(13));
    const Flow<D> y1 = integrateFlow<D>(J, J_inverse, y, span, steps);
    Eigen::Matrix<double, kStateDim, kStateDim> block;  // ∂(defect rows)/∂ε
    const so3::Vec3<D> dR =
        relativeRotation<D>(target(nodes, m), Eigen::Matrix<D, 4, 1>(y1.head<4>()));
    const int rows = last ? 6 : kStateDim;
    for (int i = 0; i < rows; ++i) {
      const D& value = i < 3 ? dR(i) : y1(4 + (i - 3));
      (*defect)(row + i) = value.v;
      for (int j = 0; j < kStateDim; ++j) block(i, j) = value.d(j);
    }
    if (last) (*defect).segment<3>(row + 3) -= problem.final_velocity;
    if (!last) (*defect).segment<9>(row + 3) -= flowOfState(nodes[m + 1]).segment<9>(4);
    // Columns of this segment's own unknowns: segment 0 only has (π_0, ν_0).
    if (m == 0) {
      jacobian->block(row, 0, rows, 6) = block.block(0, 6, rows, 6);
    } else {
      jacobian->block(row, 6 + kStateDim * (m - 1), rows, kStateDim) = block.topRows(rows);
    }
    if (!last) {
      // d_R = log(exp(−δ) R_{m+1}ᵀ R_end) = d − Jl⁻¹(d) δ,  Jl⁻¹(d) = Jr⁻¹(−d)
      const int col = 6 + kStateDim * m;
      const Vector3 d = (*defect).segment<3>(row);
      jacobian->block<3, 3>(row, col) = -so3::rightJacobianInverse(Vector3(-d));
      jacobian->block<9, 9>(row + 3, col + 3) = -Eigen::Matrix<double, 9, 9>::Identity();
    }
  }
};

/// Newton on the defects with backtracking on their norm, from `nodes` (updated in place).
/// Returns the iterations taken; `defect` holds the defects at the final nodes.
int solveDefects(const Shooting& shooting, const ReferenceOptions& options,
                 std::vector<ContinuousState>& nodes, Eigen::VectorXd& defect) {
  Eigen::MatrixXd jacobian;
  shooting.evaluate(nodes, &defect, &jacobian);
  double norm = defect.norm();
  int iterations = 0;
  while (iterations < options.max_iterations) {
    if (defect.lpNorm<Eigen::Infinity>() <= options.tolerance) break;
    const Eigen::VectorXd step = -jacobian.partialPivLu().solve(defect);
    if (!step.allFinite()) break;
    double alpha = 1.0;
    std::vector<ContinuousState> trial;
    Eigen::VectorXd trial_defect;
    bool accepted = false;
    for (int halving = 0; halving < 30; ++halving, alpha *= 0.5) {
      trial = shooting.apply(nodes, step, alpha);
      shooting.evaluate(trial, &trial_defect, nullptr);
      if (trial_defect.allFinite() && trial_defect.norm() < norm) {
        accepted = true;
        break;
      }
    }
    ++iterations;
    if (!accepted) break;  // no decrease: at the round-off floor (or lost)
    nodes = trial;
    shooting.evaluate(nodes, &defect, &jacobian);
    norm = defect.norm();
  }
  return iterations;
}

/// The first guess of the nodes' costates: options.guess, or a discrete plan at N = 256.
/// Returns null (the reason in *failure) when that plan does not converge.
const Maneuver* referenceGuess(const PlanningProblem& problem, const ReferenceOptions& options,
                               Maneuver* storage, std::string* failure) {
  const Maneuver* guess = options.guess;
  if (guess != nullptr && guess->steps() >= 4) return guess;
  PlanningProblem coarse = problem;
  coarse.steps = 256;
  coarse.scheme = SchemeKind::Paper;
  const PlanResult plan = planAtResolution(coarse);
  if (!plan.converged()) {
    *failure = "initial guess: the discrete plan did not converge: " + renderMessage(plan);
    return nullptr;
  }
  *storage = plan.maneuver;
  return storage;
}

/// The reference's nodes with the running cost (the last one at T), each interval's end
/// integrated at H and H/2 for the integration error.
struct NodeRecord {
  std::vector<ContinuousState> nodes;
  double cost = 0.0;
  double hamiltonian_drift = 0.0;
  double integration_error = 0.0;
};

NodeRecord recordNodes(const Shooting& shooting, const std::vector<ContinuousState>& nodes) {
  NodeRecord out;
  double cost = 0.0;
  double H0 = 0.0;
  for (int m = 0; m < shooting.M; ++m) {
    ContinuousState start = nodes[m];
    start.t = m * shooting.span;
    start.cost = cost;
    if (m == 0) H0 = hamiltonian(shooting.J, start);
    out.hamiltonian_drift =
        std::max(out.hamiltonian_drift, std::abs(hamiltonian(shooting.J, start) - H0));
    out.nodes.push_back(start);
    const Flow<double> x = flowOfState(start);
    const Flow<double> coarse =
        integrateFlow<double>(shooting.J, shooting.J_inverse, x, shooting.span, shooting.steps);
    const Flow<double> fine =
        integrateFlow<double>(shooting.J, shooting.J_inverse, x, shooting.span, 2 * shooting.steps);
    out.integration_error = std::max(
        {out.integration_error, (coarse.head<13>() - fine.head<13>()).lpNorm<Eigen::Infinity>(),
         std::abs(coarse(13) - fine(13))});
    cost = fine(13);
    if (m == shooting.M - 1) out.nodes.push_back(stateOfFlow(fine, shooting.problem.duration));
  }
  out.cost = cost;
  return out;
}

}  // namespace

ContinuousReference solveContinuousReference(const PlanningProblem& problem_in,
                                             const ReferenceOptions& options) {
  PlanningProblem problem = problem_in;
  problem.accuracy = AccuracyTarget{};  // the guess is a plan at a fixed N
  validateProblem(problem);
  if ((problem.effects && !problem.effects->empty()) || problem.hasTorqueBounds()) {
    throw InvalidInput(
        "continuous reference: effects and actuator limits are not supported (bare rigid body)");
  }
  if (options.segments < 1 || options.macro_steps_per_segment < 1) {
    throw InvalidInput("continuous reference: segments and macro_steps_per_segment must be >= 1");
  }
  const Shooting shooting(problem, options.segments, options.macro_steps_per_segment);
  const double T = problem.duration;

  ContinuousReference ref;
  ref.J_ = problem.inertia;
  ref.T_ = T;
  ref.max_macro_step_ = shooting.span / shooting.steps;

  Maneuver default_guess;
  const Maneuver* guess = referenceGuess(problem, options, &default_guess, &ref.message);
  if (guess == nullptr) return ref;
  std::vector<ContinuousState> nodes = guessNodes(problem, *guess, shooting.M);

  Eigen::VectorXd defect;
  ref.iterations = solveDefects(shooting, options, nodes, defect);
  ref.max_defect = defect.lpNorm<Eigen::Infinity>();

  NodeRecord record = recordNodes(shooting, nodes);
  ref.nodes_ = std::move(record.nodes);
  ref.hamiltonian_drift = record.hamiltonian_drift;
  ref.integration_error = record.integration_error;
  ref.cost = record.cost;
  const double scale = 1.0 + std::max(ref.cost / T, 1.0);
  ref.converged = defect.allFinite() && ref.max_defect <= 1e-10 * scale;
  std::ostringstream msg;
  msg << (ref.converged ? "converged" : "not converged") << ": " << ref.iterations
      << " Newton iterations, max defect " << ref.max_defect << ", integration error "
      << ref.integration_error;
  ref.message = msg.str();
  return ref;
}

ContinuousState ContinuousReference::stateAt(double t) const {
  return sample({t}).front();
}

std::vector<ContinuousState> ContinuousReference::sample(const std::vector<double>& times) const {
  std::vector<ContinuousState> out;
  out.reserve(times.size());
  if (nodes_.empty()) throw InvalidInput("continuous reference: not solved");
  const int M = static_cast<int>(nodes_.size()) - 1;
  const double span = T_ / M;
  int segment = -1;
  ContinuousState current;
  for (double t : times) {
    if (!(t >= 0.0 && t <= T_ * (1 + 1e-12))) {
      throw InvalidInput("continuous reference: time " + std::to_string(t) + " outside [0, T]");
    }
    const int m = std::min(M - 1, static_cast<int>(t / span));
    if (m != segment || t < current.t) {  // restart from the node of t's interval
      segment = m;
      current = nodes_[m];
    }
    const double dt = t - current.t;
    const int steps = dt > 0.0 ? static_cast<int>(std::ceil(dt / max_macro_step_ - 1e-9)) : 0;
    current = propagateExtremal(J_, current, dt, std::max(steps, 1));
    current.t = t;
    out.push_back(current);
  }
  return out;
}

}  // namespace attitude_planner
