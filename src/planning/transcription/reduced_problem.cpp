#include "planning/transcription/reduced_problem.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <utility>

#include "attitude_planner/errors.hpp"
#include "dynamics/principal_branch.hpp"
#include "lie/skew_products.hpp"

namespace attitude_planner {

namespace {

/// What one step F_j contributes to the torques next to it, and to their Jacobians
/// (right perturbation F exp(ε^); D = dμ/dε, G = Fᵀμ, dG = dG/dε = (Fᵀμ)^ + FᵀD):
///   τ_k = (μ_k − G_{k−1})/h
///   ∂τ_k/∂(δ_{k−1}, δ_k, δ_{k+1}) = [dG_{k−1}F_{k−1}ᵀ, −(D_k F_kᵀ + dG_{k−1}), D_k] / h,
/// from F_{k−1} → F_{k−1} exp(δ_k − F_{k−1}ᵀ δ_{k−1}) and F_k → F_k exp(δ_{k+1} − F_kᵀ δ_k).
struct StepTerms {
  Vector3 omega;  ///< ω = log F, as stored: no log map to recover it
  Matrix3 F;
  Matrix3 E;  ///< F − I (stepTorques' difference of momenta reads it)
  DiscreteScheme::StepJacobianTerms step;  ///< what D and its contractions read of F alone
  Vector3 mu, G;
  Matrix3 D, dG, DFt, dGFt;
  Matrix3 DtF;  ///< Dᵀ F (contractdG's, the same for both torques beside the step)

  /// The terms of the step ω_in, formed in place (the rolling windows below keep two StepTerms
  /// and swap pointers: no copy of their ~130 numbers a step). With `known` (forms of the steps
  /// this one is step j of) F, E and μ are read, not formed again: the same values.
  void assign(const DiscreteScheme& scheme, const Vector3& omega_in,
              const ReducedProblem::StepForms* known = nullptr, int j = 0) {
    omega = omega_in;
    if (known) {
      F = known->F[j];
      E = known->E[j];
      mu = known->mu[j];
    } else {
      so3::expWithMinusIdentity<double>(omega, &F, &E);
      mu = scheme.momentumOfStep(omega, E);
    }
    step = scheme.stepJacobianTerms(F, omega);
    G = F.transpose() * mu;
    D = scheme.momentumJacobianOfStep(step);
    dG = so3::hat<double>(G) + F.transpose() * D;
    DFt = D * F.transpose();
    dGFt = dG * F.transpose();
    DtF = D.transpose() * F;
  }

  /// τ-weighted derivatives C_X(m, e) = Σ_i τ_i ∂X(i, m)/∂ε_e of this step's Jacobian blocks
  /// X = D, D Fᵀ, dG, dG Fᵀ, all from the scheme's C_D by the product rule with
  /// ∂F/∂ε_e = F ê_e^:  C_{X Fᵀ} = F (C_X − (Xᵀτ)^),  C_dG = τ^ dG + C_D(Fτ) − DᵀF τ^ (the
  /// products with τ^ skip its zeros: skew_products.hpp).
  Matrix3 contractD(const DiscreteScheme& scheme, const Vector3& tau) const {
    return scheme.momentumJacobianContraction(step, tau);
  }
  Matrix3 contractDFt(const Matrix3& C_D, const Vector3& tau) const {
    return F * (C_D - so3::hat<double>(Vector3(D.transpose() * tau)));
  }
  Matrix3 contractdG(const DiscreteScheme& scheme, const Vector3& tau) const {
    return so3::hatTimes(tau, dG) + scheme.momentumJacobianContraction(step, Vector3(F * tau)) -
           so3::timesHat(DtF, tau);
  }
  Matrix3 contractdGFt(const Matrix3& C_dG, const Vector3& tau) const {
    return F * (C_dG - so3::hat<double>(Vector3(dG.transpose() * tau)));
  }
};

}  // namespace

ReducedProblem::ReducedProblem(const PlanningProblem& problem)
    : N_(problem.steps),
      scheme_(problem.scheme, problem.inertia, problem.duration / problem.steps),
      initial_attitude_(problem.initial_attitude),
      final_attitude_(problem.final_attitude),
      initial_velocity_(problem.initial_velocity),
      final_velocity_(problem.final_velocity),
      effects_(problem.effects && !problem.effects->empty() ? problem.effects : nullptr),
      first_free_(scheme_.hasEndTorques() ? 1 : 2),
      last_free_(scheme_.hasEndTorques() ? problem.steps - 1 : problem.steps - 2),
      initial_momentum_(problem.inertia * problem.initial_velocity),
      final_momentum_(problem.inertia * problem.final_velocity),
      twist_axis_(problem.end_condition.pointing() ? problem.end_condition.body_axis.normalized()
                                                   : Vector3::Zero()) {
  const Matrix3 F_first = scheme_.stepFromVelocity(problem.initial_velocity);
  const Matrix3 F_last = scheme_.stepFromVelocity(problem.final_velocity);
  steps_.assign(N_, Vector3::Zero());
  // paper: ω = hΩ exactly; variational: the implicit step's rotation vector
  steps_[0] = problem.scheme == SchemeKind::Paper
                  ? Vector3(scheme_.timeStep() * problem.initial_velocity)
                  : so3::log(F_first);
  steps_[N_ - 1] = problem.scheme == SchemeKind::Paper
                       ? Vector3(scheme_.timeStep() * problem.final_velocity)
                       : so3::log(F_last);
  // Geodesic from R_1 to R_{N−1} in N − 2 equal steps.
  const Matrix3 R1 = problem.initial_attitude * F_first;
  const Matrix3 R_last = problem.final_attitude * F_last.transpose();
  principal_span_ = so3::log(Matrix3(R1.transpose() * R_last));
  initializeAlong(principal_span_);
}

void ReducedProblem::initializeAlong(const Vector3& span) {
  for (int j = 1; j <= N_ - 2; ++j) steps_[j] = span / double(N_ - 2);
}

void ReducedProblem::initializeHermite(const Vector3& span, const Vector3& start_slope,
                                       const Vector3& end_slope) {
  const auto phi = [&](double s) {
    const double h10 = s * s * s - 2 * s * s + s, h01 = -2 * s * s * s + 3 * s * s,
                 h11 = s * s * s - s * s;
    return Vector3(h10 * start_slope + h01 * span + h11 * end_slope);
  };
  // Steps between consecutive samples R_1 exp(φ(s_{j−1})), R_1 exp(φ(s_j)), composed in
  // quaternions; the last sample is exactly R_1 exp(span) = R_{N−1}.
  Eigen::Vector4d q_prev = so3::quaternionOfRotationVector<double>(Vector3::Zero());
  for (int j = 1; j <= N_ - 2; ++j) {
    const Eigen::Vector4d q = so3::quaternionOfRotationVector<double>(phi(double(j) / (N_ - 2)));
    Eigen::Vector4d q_prev_inverse = q_prev;
    q_prev_inverse.tail<3>() *= -1.0;
    steps_[j] = so3::logOfQuaternion<double>(so3::quaternionProduct<double>(q_prev_inverse, q));
    q_prev = q;
  }
}

void ReducedProblem::setInteriorFromAttitudes(const std::vector<Matrix3>& attitudes) {
  if (static_cast<int>(attitudes.size()) != N_ + 1) {
    throw InvalidInput("warm start: has " + std::to_string(attitudes.size() - 1) +
                       " steps, the problem " + std::to_string(N_));
  }
  // The warm start's fixed attitudes must be this problem's: keep ours there.
  const std::vector<Matrix3> own = this->attitudes(steps_);
  std::vector<Matrix3> R = attitudes;
  for (int j = 0; j <= N_; ++j) {
    if (variableIndex(j) < 0) R[j] = own[j];
  }
  for (int j = 0; j < N_; ++j) steps_[j] = so3::log(Matrix3(R[j].transpose() * R[j + 1]));
}

namespace {

/// The rate of `coarse` (steps of a grid of coarse.size() steps) at the position of step j of N,
/// scaled to a step of that grid. `midpoints`: step k of a grid of n steps belongs to
/// T (k + ½)/n (schemes with end torques, whose every step is free); else to T k/(n − 1) (paper
/// and variational: the fixed first and last steps carry Ω(0) and Ω(T); see
/// initializeFromCoarser).
Vector3 interpolatedStep(const ReducedProblem::StepVectors& coarse, int j, int N, bool midpoints) {
  const int Nc = static_cast<int>(coarse.size());
  const auto slope = [&](int k) {
    if (k == 0) return Vector3(coarse[1] - coarse[0]);
    if (k == Nc - 1) return Vector3(coarse[Nc - 1] - coarse[Nc - 2]);
    return Vector3(0.5 * (coarse[k + 1] - coarse[k - 1]));
  };
  const double x = midpoints ? (j + 0.5) * Nc / N - 0.5 : double(j) * (Nc - 1) / (N - 1);
  // Midpoints of the first and last fine steps lie outside the coarse ones: extrapolate
  // linearly (near a rest end the rate grows linearly in t; holding the coarse end rate made
  // the fine end torque τ_0 = 2Jω_0/h² too large by h_c/h).
  if (x < 0.0) return double(Nc) / N * (coarse[0] + x * (coarse[1] - coarse[0]));
  if (x > Nc - 1) {
    return double(Nc) / N * (coarse[Nc - 1] + (x - (Nc - 1)) * (coarse[Nc - 1] - coarse[Nc - 2]));
  }
  const int i = std::min(static_cast<int>(x), Nc - 2);
  const double s = x - i;
  const double h00 = 2 * s * s * s - 3 * s * s + 1, h10 = s * s * s - 2 * s * s + s,
               h01 = -2 * s * s * s + 3 * s * s, h11 = s * s * s - s * s;
  return double(Nc) / N *
         (h00 * coarse[i] + h10 * slope(i) + h01 * coarse[i + 1] + h11 * slope(i + 1));
}

}  // namespace

void ReducedProblem::initializeFromCoarser(const StepVectors& coarse, const StepVectors* coarser) {
  const int Nc = static_cast<int>(coarse.size());
  if (Nc < 4 || Nc >= N_ ||
      (coarser && (coarser->size() < 4 || coarser->size() >= coarse.size()))) {
    throw InvalidInput("grid continuation: a coarse grid of " + std::to_string(Nc) +
                       " steps cannot start one of " + std::to_string(N_));
  }
  // Where a step belongs in time: for paper and variational the boundary data make the first
  // step's rate Ω(0) and the last one's Ω(T), and the optimal discrete solutions are smooth in k
  // between them (measured), so step k of N belongs to T k/(N − 1). (Centring steps at (k + ½)h
  // puts the fixed end steps a fraction of a coarse step off: O(1) torque jumps at the ends.)
  // With end torques every step is free and sits at its midpoint (k + ½)h. Rates ω^c_k/h_c are
  // interpolated by Catmull–Rom (C¹, slopes one-sided at the ends) and scaled by h. With a
  // second, coarser solution the two are extrapolated to this grid's h (Richardson at the
  // scheme's order p: 1, or 2 with end torques, docs/results/accuracy.md),
  // s(h) = s(h₁) − (s(h₂) − s(h₁)) (h₁ᵖ − hᵖ)/(h₂ᵖ − h₁ᵖ).
  const bool midpoints = scheme_.hasEndTorques();
  const double p = midpoints ? 2.0 : 1.0;
  const double h1 = 1.0 / Nc, h = 1.0 / N_;
  const double weight = coarser ? (std::pow(h1, p) - std::pow(h, p)) /
                                      (std::pow(1.0 / coarser->size(), p) - std::pow(h1, p))
                                : 0.0;
  // The free steps: those next to a free attitude (1..N−2, or 0..N−1 with end torques). What
  // they compose to now is what they must compose to: R_firstᵀ R_last+1 of the fixed ends.
  const int first = first_free_ - 1, last = last_free_;
  const Eigen::Vector4d target = freeStepsComposition();
  for (int j = first; j <= last; ++j) {
    const Vector3 fine = interpolatedStep(coarse, j, N_, midpoints);
    steps_[j] = coarser
                    ? Vector3(fine - weight * (interpolatedStep(*coarser, j, N_, midpoints) - fine))
                    : fine;
  }
  closeGap(target);
}

void ReducedProblem::initializeFromSteps(const StepVectors& guess) {
  if (static_cast<int>(guess.size()) != N_) {
    throw InvalidInput("initial guess: has " + std::to_string(guess.size()) +
                       " steps, the problem " + std::to_string(N_));
  }
  const Eigen::Vector4d target = freeStepsComposition();
  for (int j = first_free_ - 1; j <= last_free_; ++j) steps_[j] = guess[j];
  closeGap(target);
}

Eigen::Vector4d ReducedProblem::freeStepsComposition() const {
  Eigen::Vector4d q = so3::quaternionOfRotationVector<double>(Vector3::Zero());
  for (int j = first_free_ - 1; j <= last_free_; ++j) {
    q = so3::quaternionProduct<double>(q, so3::quaternionOfRotationVector(steps_[j]));
  }
  return q;
}

void ReducedProblem::closeGap(const Eigen::Vector4d& target) {
  using Quaternion = Eigen::Vector4d;
  const int first = first_free_ - 1, last = last_free_;
  // The gap ψ between where the free steps end and the fixed end (body frame there), closed by
  // R_j → R_j exp(φ_j^), φ cubic in j with φ = 0 at the first fixed node and ψ at the last,
  // zero end slopes: F_j → exp(−φ_j^) F_j exp(φ_{j+1}^) telescopes to the target. In
  // quaternions throughout.
  Quaternion reached = freeStepsComposition();
  reached.tail<3>() *= -1.0;  // its inverse
  const Vector3 gap = so3::logOfQuaternion<double>(so3::quaternionProduct<double>(reached, target));
  const auto phi = [&](int j) {
    const double u = double(j - first) / (last + 1 - first);
    return Vector3((3 * u * u - 2 * u * u * u) * gap);
  };
  for (int j = first; j <= last; ++j) {
    const Quaternion q = so3::quaternionProduct<double>(
        so3::quaternionProduct<double>(so3::quaternionOfRotationVector<double>(-phi(j)),
                                       so3::quaternionOfRotationVector<double>(steps_[j])),
        so3::quaternionOfRotationVector<double>(phi(j + 1)));
    steps_[j] = so3::logOfQuaternion<double>(q);
  }
}

std::vector<Matrix3> ReducedProblem::attitudes(const StepVectors& steps) const {
  std::vector<Matrix3> R(N_ + 1);
  R[0] = initial_attitude_;
  for (int k = 0; k < N_; ++k) R[k + 1] = R[k] * so3::exp(steps[k]);
  return R;
}

namespace {

/// h τ_k = μ_k − F_{k−1}ᵀ μ_{k−1} = (μ_k − μ_{k−1}) − (F_{k−1} − I)ᵀ μ_{k−1} at an interior node,
/// before the effects: the large parts cancel in a difference of accurately formed momenta.
Vector3 interiorTorque(const Vector3& mu, const Vector3& mu_prev, const Matrix3& E_prev, double h) {
  return ((mu - mu_prev) - E_prev.transpose() * mu_prev) / h;
}

/// The end torques, before the effects: Π_0 = J Ω(0) = μ(F_0) − (h/2) τ_0 and
/// Π_N = J Ω(T) = F_{N−1}ᵀ μ(F_{N−1}) + (h/2) τ_N.
Vector3 firstTorque(const Vector3& mu_first, const Vector3& initial_momentum, double h) {
  return 2.0 * (mu_first - initial_momentum) / h;
}
Vector3 lastTorque(const Vector3& final_momentum, const Matrix3& F_last, const Vector3& mu_last,
                   double h) {
  return 2.0 * (final_momentum - F_last.transpose() * mu_last) / h;
}

/// τ_k, k = 0..N, of `steps` (ReducedProblem::torques), and with `attitudes` the rows
/// R_{k+1} = R_k F_k from the same pass. Each step's exp(ω^) and exp(ω^) − I come from one
/// Rodrigues evaluation (so3::expWithMinusIdentity: the values of exp and expMinusIdentity, so
/// the rows are attitudes()' and the torques are the same with or without them). With `keep`
/// each step's F, E and μ are kept there (ReducedProblem::StepForms).
std::vector<Vector3> stepTorques(const DiscreteScheme& scheme,
                                 const ReducedProblem::StepVectors& steps, int N,
                                 const Matrix3& initial_attitude, const Vector3& initial_momentum,
                                 const Vector3& final_momentum, const EffectModel* effects,
                                 std::vector<Matrix3>* attitudes,
                                 ReducedProblem::StepForms* keep = nullptr) {
  std::vector<Vector3> tau(N + 1, Vector3::Zero());
  const double h = scheme.timeStep();
  const bool track_attitude = attitudes || effects;
  const bool form_F = track_attitude || keep;
  if (keep) {
    keep->steps = steps;
    keep->time_step = h;
    keep->F.resize(N);
    keep->E.resize(N);
    keep->mu.resize(N);
  }
  // F = exp(ω^) only where the attitudes are followed or kept; E = F − I always. Returns μ.
  const auto step = [&](int k, Matrix3* F, Matrix3* E) {
    if (form_F) {
      so3::expWithMinusIdentity<double>(steps[k], F, E);
    } else {
      *E = so3::expMinusIdentity(steps[k]);
    }
    const Vector3 mu = scheme.momentumOfStep(steps[k], *E);
    if (keep) {
      keep->F[k] = *F;
      keep->E[k] = *E;
      keep->mu[k] = mu;
    }
    return mu;
  };
  Matrix3 F_prev, E_prev;  // F_{k−1}, F_{k−1} − I
  const Vector3 mu_first = step(0, &F_prev, &E_prev);
  Vector3 mu_prev = mu_first;
  Matrix3 R = initial_attitude;  // R_k, only needed with effects or attitudes
  if (attitudes) {
    attitudes->resize(N + 1);
    (*attitudes)[0] = R;
  }
  for (int k = 1; k < N; ++k) {
    Matrix3 F, E;
    const Vector3 mu = step(k, &F, &E);
    tau[k] = interiorTorque(mu, mu_prev, E_prev, h);
    if (track_attitude) R = R * F_prev;
    if (attitudes) (*attitudes)[k] = R;
    if (effects) tau[k] -= effects->torque(R, k * h);  // the control supplies the rest
    mu_prev = mu;
    E_prev = E;
    if (track_attitude) F_prev = F;
  }
  if (track_attitude) R = R * F_prev;  // R_N
  if (attitudes) (*attitudes)[N] = R;
  if (scheme.hasEndTorques()) {
    tau[0] = firstTorque(mu_first, initial_momentum, h);
    const Matrix3 F_last = track_attitude ? F_prev : so3::exp(steps[N - 1]);
    tau[N] = lastTorque(final_momentum, F_last, mu_prev, h);
    if (effects) {
      tau[0] -= effects->torque(initial_attitude, 0.0);
      tau[N] -= effects->torque(R, N * h);
    }
  }
  return tau;
}

}  // namespace

std::vector<Vector3> ReducedProblem::torques(const StepVectors& steps) const {
  return stepTorques(scheme_, steps, N_, initial_attitude_, initial_momentum_, final_momentum_,
                     effects_.get(), nullptr);
}

bool ReducedProblem::onPrincipalBranch(const StepVectors& steps) const {
  const double proven = principalBranchRadius(scheme_);  // steps shorter need no test
  return std::all_of(steps.begin(), steps.end(), [&](const Vector3& omega) {
    return omega.norm() < proven || scheme_.onPrincipalBranch(omega);
  });
}

Maneuver ReducedProblem::maneuver(const StepVectors& steps) const {
  Maneuver m;
  m.time_step = scheme_.timeStep();
  // The rows R_k from the torques' pass over the steps (one exponential per step, not two).
  m.torque = stepTorques(scheme_, steps, N_, initial_attitude_, initial_momentum_, final_momentum_,
                         effects_.get(), &m.attitude);
  m.time.resize(N_ + 1);
  m.angular_velocity.resize(N_ + 1);
  for (int k = 0; k <= N_; ++k) m.time[k] = k * m.time_step;
  if (scheme_.hasEndTorques()) {
    // Node velocities J⁻¹Π_k: Π_0, Π_N are the boundary momenta (τ_0, τ_N make them so), and
    // inside Π_k = μ_k − (h/2) a_k = ½(μ_k + F_{k−1}ᵀ μ_{k−1}) whatever the effects.
    const Matrix3 J_inverse = scheme_.inertia().inverse();
    m.angular_velocity[0] = J_inverse * initial_momentum_;
    m.angular_velocity[N_] = J_inverse * final_momentum_;
    Vector3 mu_prev = scheme_.momentumOfStep(steps[0]);
    for (int k = 1; k < N_; ++k) {
      const Vector3 mu = scheme_.momentumOfStep(steps[k]);
      m.angular_velocity[k] =
          J_inverse * (0.5 * (mu + so3::exp(steps[k - 1]).transpose() * mu_prev));
      mu_prev = mu;
    }
    return m;
  }
  for (int k = 0; k < N_; ++k) m.angular_velocity[k] = scheme_.velocityOfStep(steps[k]);
  m.angular_velocity[N_] = m.angular_velocity[N_ - 1];
  return m;
}

double ReducedProblem::cost(const StepVectors& steps) const {
  return scheme_.cost(torques(steps));
}

double ReducedProblem::cost(const StepVectors& steps, StepForms* keep) const {
  return scheme_.cost(stepTorques(scheme_, steps, N_, initial_attitude_, initial_momentum_,
                                  final_momentum_, effects_.get(), nullptr, keep));
}

ReducedProblem::StepVectors ReducedProblem::retract(const Eigen::VectorXd& delta,
                                                    double alpha) const {
  return movedSteps([&](int j) {
    const int v = variableIndex(j);
    return v < 0 ? Vector3::Zero().eval() : Vector3(alpha * delta.segment<3>(v));
  });
}

ReducedProblem::StepVectors ReducedProblem::movedSteps(
    const std::function<Vector3(int j)>& perturbation) const {
  StepVectors out = steps_;
  // exp(δ_{j+1}^) of step j is exp(−δ_{j+1}^)'s conjugate in step j + 1: formed once (the
  // quaternion of −v is that of v with its vector part negated, exactly).
  Eigen::Vector4d moved_start =
      so3::quaternionOfRotationVector<double>(perturbation(first_free_ - 1));
  for (int j = first_free_ - 1; j <= last_free_; ++j) {  // the steps next to a free attitude
    const Eigen::Vector4d moved_end = so3::quaternionOfRotationVector<double>(perturbation(j + 1));
    moved_start.tail<3>() = -moved_start.tail<3>();  // exp(−δ_j^)
    const Eigen::Vector4d q = so3::quaternionProduct<double>(
        so3::quaternionProduct<double>(moved_start,
                                       so3::quaternionOfRotationVector<double>(steps_[j])),
        moved_end);
    out[j] = so3::logOfQuaternion<double>(q);
    moved_start = moved_end;
  }
  return out;
}

namespace {

/// Jacobian (3×9 over δ_{k−1}, δ_k, δ_{k+1}) of a μ_k + b G_{k−1} (either step may be absent), and
/// with `w` the symmetric part of Σ_i w_i ∂(jacobian_i)/∂δ, by the chain rule through ε_{k−1},
/// ε_k (StepTerms). Torques are a = f/h, b = −f/h; the node momentum Π_k is a = b = ½.
/// Unless `symmetrize`, `second` is left as the sum S itself, whose symmetric part (S + Sᵀ)/2 is
/// meant: for a reader of one triangle, which forms only that triangle's entries.
void momentumCombination(const DiscreteScheme& scheme, const StepTerms* prev, const StepTerms* next,
                         double a, double b, const Vector3* w, bool symmetrize,
                         Eigen::Matrix<double, 3, 9>* jacobian,
                         Eigen::Matrix<double, 9, 9>* second) {
  // With both steps every block is written below; an end stencil leaves some at zero.
  if (!(prev && next)) jacobian->setZero();
  if (prev) {
    jacobian->block<3, 3>(0, 0) = -b * prev->dGFt;
    jacobian->block<3, 3>(0, 3) = b * prev->dG;
  }
  if (next) {
    jacobian->block<3, 3>(0, 3) -= a * next->DFt;
    jacobian->block<3, 3>(0, 6) = a * next->D;
  }
  if (!w) return;
  Eigen::Matrix<double, 9, 9>& raw = *second;
  // Both steps write every block but the two that couple δ_{k−1} with δ_{k+1} directly: only
  // those are cleared (the whole matrix at an end stencil).
  if (prev && next) {
    raw.block<3, 3>(0, 6).setZero();
    raw.block<3, 3>(6, 0).setZero();
  } else {
    raw.setZero();
  }
  // The products go straight into their blocks (noalias: no 3 × 3 temporary; the same sums).
  if (prev) {
    const Matrix3 C_dG_prev = prev->contractdG(scheme, *w);
    const Matrix3 T_dGFt_prev = -b * prev->contractdGFt(C_dG_prev, *w);  // block a, via ε_{k−1}
    const Matrix3 T_dG_prev = b * C_dG_prev;                             // block b, via ε_{k−1}
    raw.block<3, 3>(0, 0).noalias() = -T_dGFt_prev * prev->F.transpose();
    raw.block<3, 3>(0, 3) = T_dGFt_prev;
    raw.block<3, 3>(3, 0).noalias() = -T_dG_prev * prev->F.transpose();
    raw.block<3, 3>(3, 3) = T_dG_prev;
  }
  if (next) {
    const Matrix3 C_D = next->contractD(scheme, *w);
    const Matrix3 T_DFt = -a * next->contractDFt(C_D, *w);  // block b, via ε_k
    const Matrix3 T_D = a * C_D;                            // block c, via ε_k
    raw.block<3, 3>(3, 3).noalias() -= T_DFt * next->F.transpose();
    raw.block<3, 3>(3, 6) = T_DFt;
    raw.block<3, 3>(6, 3).noalias() = -T_D * next->F.transpose();
    raw.block<3, 3>(6, 6) = T_D;
  }
  // The antisymmetric part is cancelled exactly by the retraction's derivative
  // (dJr(δ)/dδ = −½(·)^ contracted with the gradient): the symmetric part is exact.
  if (!symmetrize) return;
  for (int c = 0; c < 9; ++c) {
    for (int r = c + 1; r < 9; ++r) raw(r, c) = raw(c, r) = 0.5 * (raw(r, c) + raw(c, r));
  }
}

/// The stencil's block JᵀJ + (S + Sᵀ)/2 of the Hessian (S = `second` as visitStencils leaves it
/// unsymmetrized), its lower triangle only: the band stores one triangle, so the other's 36
/// entries are not formed. All 9 × 9 (fixed bounds, unrolled); the caller cuts off fixed nodes.
Eigen::Matrix<double, 9, 9> lowerHessianBlock(const ReducedProblem::Stencil& st) {
  const Eigen::Matrix<double, 3, 9>& J = st.jacobian;
  const Eigen::Matrix<double, 9, 9>& S = st.second;
  Eigen::Matrix<double, 9, 9> block;  // the strict upper triangle is left unset
  for (int c = 0; c < 9; ++c) {
    for (int r = c; r < 9; ++r) {
      block(r, c) =
          J(0, r) * J(0, c) + J(1, r) * J(1, c) + J(2, r) * J(2, c) + 0.5 * (S(r, c) + S(c, r));
    }
  }
  return block;
}

}  // namespace

double ReducedProblem::forEachStencil(bool with_second_order,
                                      const std::function<void(const Stencil&)>& visit,
                                      const SecondOrderWeights& weights) const {
  return visitStencils(with_second_order, true, visit, weights);
}

double ReducedProblem::visitStencils(bool with_second_order, bool symmetric_second,
                                     const std::function<void(const Stencil&)>& visit,
                                     const SecondOrderWeights& weights,
                                     const StepForms* known) const {
  const double h = scheme_.timeStep();
  double cost = 0.0;
  Stencil st;
  st.second.setZero();
  // τ_k = f (μ(F_k) − F_{k−1}ᵀ μ(F_{k−1}))/h, where at an end node (end torques only) the missing
  // step's momentum is the boundary one (J Ω(0), J Ω(T)), a constant, and f = 2. The stencil
  // holds the residual r_k = √w_k τ_k of the cost Σ ½ w_k |τ_k|² = Σ ½ |r_k|².
  // τ_k as stepTorques forms it (its torque functions over the same exp, F − I and μ values), from
  // the stencil's step terms: the steps are not passed over twice. R_k with effects only.
  const auto torqueOfStencil = [&](int k, const StepTerms* prev, const StepTerms* next,
                                   const Matrix3& R_k) {
    Vector3 tau;
    if (prev && next) {
      tau = interiorTorque(next->mu, prev->mu, prev->E, h);
      if (effects_) tau -= effects_->torque(R_k, k * h);
    } else if (next) {  // k = 0
      tau = firstTorque(next->mu, initial_momentum_, h);
      if (effects_) tau -= effects_->torque(initial_attitude_, 0.0);
    } else {  // k = N, at R_N = R_{N−1} F_{N−1}
      tau = lastTorque(final_momentum_, prev->F, prev->mu, h);
      if (effects_) tau -= effects_->torque(Matrix3(R_k * prev->F), N_ * h);
    }
    return tau;
  };
  const auto visit_torque = [&](int k, const StepTerms* prev, const StepTerms* next,
                                const Matrix3& R_k) {
    const double root = std::sqrt(scheme_.torqueWeight(k, N_));
    const double factor = (prev && next ? 1.0 : 2.0) * root / h;
    st.k = k;
    st.tau = root * torqueOfStencil(k, prev, next, R_k);
    const Vector3 w = with_second_order && weights ? weights(k, st.tau) : st.tau;
    momentumCombination(scheme_, prev, next, factor, -factor, with_second_order ? &w : nullptr,
                        symmetric_second, &st.jacobian, &st.second);
    // τ_k −= τ_e(R_k, t_k): only R_k's block depends on the effects (fixed at the end nodes).
    const bool interior = prev && next;
    if (effects_ && interior)
      st.jacobian.block<3, 3>(0, 3) -= root * effects_->jacobian(R_k, k * h);
    if (effects_ && interior && with_second_order) {
      st.second.block<3, 3>(3, 3) -= root * effects_->weightedSecondDerivative(R_k, k * h, w);
    }
    cost += 0.5 * st.tau.squaredNorm();
    visit(st);
  };
  // Rolling window over steps: `prev` holds F_{k−1}'s terms, `next` F_k's (each F once).
  StepTerms window[2];
  StepTerms *prev = &window[0], *next = &window[1];
  prev->assign(scheme_, steps_[0], known, 0);
  if (scheme_.hasEndTorques()) visit_torque(0, nullptr, prev, initial_attitude_);
  Matrix3 R = initial_attitude_;  // R_k, only needed with effects
  for (int k = 1; k < N_; ++k) {
    next->assign(scheme_, steps_[k], known, k);
    if (effects_) R = R * prev->F;
    visit_torque(k, prev, next, R);
    std::swap(prev, next);
  }
  if (scheme_.hasEndTorques()) visit_torque(N_, prev, nullptr, R);
  return cost;
}

void ReducedProblem::forEachNodeMomentum(const std::function<void(const NodeMomentum&)>& visit,
                                         const SecondOrderWeights& weights) const {
  NodeMomentum node;
  node.second.setZero();
  StepTerms window[2];
  StepTerms *prev = &window[0], *next = &window[1];
  prev->assign(scheme_, steps_[0]);
  for (int k = 1; k < N_; ++k) {
    next->assign(scheme_, steps_[k]);
    node.k = k;
    node.momentum = 0.5 * (next->mu + prev->G);  // Π_k = μ(F_k) − (h/2)τ_k = G_{k−1} + (h/2)τ_k
    const Vector3 w = weights ? weights(k, node.momentum) : Vector3::Zero().eval();
    momentumCombination(scheme_, prev, next, 0.5, 0.5, weights ? &w : nullptr, true, &node.jacobian,
                        &node.second);
    visit(node);
    std::swap(prev, next);
  }
}

namespace {

/// Whether `forms` belong to `steps` at time step h, bit for bit (a −0 and a +0 step may form
/// different zeros).
bool formsOf(const ReducedProblem::StepForms& forms, const ReducedProblem::StepVectors& steps,
             double h) {
  return forms.time_step == h && forms.steps.size() == steps.size() &&
         std::memcmp(forms.steps.data(), steps.data(), steps.size() * sizeof(Vector3)) == 0;
}

}  // namespace

double ReducedProblem::evaluate(Eigen::VectorXd* gradient, BandedSymmetricMatrix* hessian,
                                double* gradient_scale) const {
  return evaluate(gradient, hessian, gradient_scale, nullptr);
}

double ReducedProblem::evaluate(Eigen::VectorXd* gradient, BandedSymmetricMatrix* hessian,
                                double* gradient_scale, const StepForms* known) const {
  if (known && !formsOf(*known, steps_, scheme_.timeStep())) known = nullptr;
  gradient->setZero(unknowns());
  if (hessian) hessian->setZero();
  double jacobian_scale = 0.0, torque_scale = 0.0;
  // lowerHessianBlock symmetrizes `second` in the lower triangle it forms
  const bool symmetric_second = false;
  const auto add_stencil = [&](const Stencil& st) {
    jacobian_scale = std::max(jacobian_scale, st.jacobian.cwiseAbs().maxCoeff());
    torque_scale = std::max(torque_scale, st.tau.cwiseAbs().maxCoeff());
    const Eigen::Matrix<double, 9, 1> g = st.jacobian.transpose() * st.tau;
    for (int s = 0; s < 3; ++s) {
      const int v = variableIndex(st.k - 1 + s);
      if (v >= 0) gradient->segment<3>(v) += g.segment<3>(3 * s);
    }
    if (!hessian) return;
    // The stencil's unknowns R_{k−1}, R_k, R_{k+1} are consecutive (R_{k−1}'s would be at
    // 3(k − 1 − first free node)); the fixed ones among them are cut off the block.
    const int first = 3 * std::max(0, first_free_ - (st.k - 1));
    const int last = 3 * (std::min(2, last_free_ - (st.k - 1)) + 1);
    hessian->addSymmetricBlock<9>(3 * (st.k - 1 - first_free_), lowerHessianBlock(st), first, last);
  };
  const double cost =
      visitStencils(hessian != nullptr, symmetric_second, add_stencil, nullptr, known);
  *gradient_scale = jacobian_scale * std::max(torque_scale, 1e-300);
  return cost;
}

}  // namespace attitude_planner
