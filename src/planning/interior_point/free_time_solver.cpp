// Minimum time as one interior-point problem (free_time_solver.hpp).
//
// Unknowns: the free attitudes R_j exp(δ_j^) of the reduced problem and η = h/h₀ (h₀ the start's
// time step, T₀ = N h₀), the boundary data R_0, R_N, Ω(0), Ω(T) held at every h
// (ReducedProblem::setTimeStep). Problem, with the torque constraints c_i ≥ 0 written as the
// fixed-h interior point writes them (constrained_system.cpp):
//     min f = T/T₀ + ε C(δ, h)   s.t.  c_i(δ, h) ≥ 0,   torque box 1 ∓ τ_{k,a}/a_a, norm 1 −
//     |τ_k|²/t²,
// C the scheme's effort Σ ½ w_k |τ_k|² and ε = ε₀ μ/μ₀ a regularization that vanishes with the
// barrier μ (minimum time alone is bang–bang: where a torque is strictly inside its bounds, ε
// makes the Newton system definite; at μ → 0 the answer is a KKT point of minimum time itself).
// Every constraint is a function of one torque τ_k, so of R_{k−1}, R_k, R_{k+1} and h:
// ∂τ_k/∂h comes from ReducedProblem::forEachStencilWithTimeStep (tau_h, with the fixed inner
// attitudes of paper and variational moving with h), and the Hessian of the Lagrangian
// L = f − Σ zᵢcᵢ is that stencil's `second` with the weights w_k = ε r_k − Σ zᵢ ∂cᵢ/∂r_k plus the
// Gauss–Newton terms of C and the norm bound. A feasible primal–dual barrier method: the iterates
// stay strictly inside (every iterate is a plan meeting every constraint and the discrete
// dynamics), the Newton step of the barrier problem condenses to
//     [W + Σ (zᵢ/cᵢ) gᵢgᵢᵀ] dx = −∇f + Σ (μ/cᵢ) gᵢ,   dzᵢ = μ/cᵢ − zᵢ − (zᵢ/cᵢ) gᵢᵀdx,
// over x = (δ, η): a band (the node unknowns) bordered by one column (η), solved by the Schur
// complement (linalg/bordered_band.hpp). Inertia: the band must be positive definite and the
// Schur complement positive (else a growing shift, as IPOPT's δ_w); line search Armijo on
// φ_μ = f − μ Σ ln cᵢ with the fraction to the boundary on c and z; barrier μ decreased
// monotonically (IPOPT's κ_μ, θ_μ) once the barrier problem's residual is ≤ κ_ε μ.
#include "planning/interior_point/free_time_solver.hpp"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <limits>
#include <sstream>

#include "attitude_planner/errors.hpp"
#include "planning/linalg/bordered_band.hpp"

namespace attitude_planner {

namespace {

/// The start's time step grows by this factor until every constraint holds with kStartMargin.
constexpr double kStartGrowth = 1.05;
constexpr double kStartMargin = 0.05;
constexpr int kMaxStartGrowths = 400;
/// μ₀ = this / m (m constraints): the barrier terms start at a tenth of the objective T/T₀ = 1.
constexpr double kInitialBarrier = 0.1;
/// ε₀ C₀ = this × T₀ at the start (C₀ its effort): a light regularization, gone as μ → 0.
constexpr double kInitialEffortShare = 1e-2;
/// ε never falls below this × ε₀: where the plan is strictly inside its bounds (the switches)
/// minimum time alone has no curvature, and a shifted Newton step stalls there (measured on
/// Bilimoria–Wie: stationarity stuck at 1e-6); T moves by O(ε) ~ 1e-10 T₀.
constexpr double kFinalEffortFraction = 1e-8;
/// Monotone barrier update (IPOPT κ_ε, κ_μ, θ_μ).
constexpr double kBarrierSolved = 10.0;
constexpr double kBarrierLinear = 0.2;
constexpr double kBarrierSuperlinear = 1.5;
/// Fraction to the boundary (IPOPT τ) on the constraint values and the multipliers.
constexpr double kFractionToBoundary = 0.99;
/// z stays within [μ/(κ c), κ μ/c] (IPOPT κ_Σ).
constexpr double kDualSafeguard = 1e10;
constexpr double kArmijo = 1e-4;
constexpr int kMaxHalvings = 40;
/// Inertia correction: a relative diagonal shift, from kFirstShift growing ×kShiftGrowth.
constexpr double kFirstShift = 1e-10;
constexpr double kShiftGrowth = 100.0;
constexpr double kMaxShift = 1e10;
constexpr int kHalfBandwidth = 8;
/// Above this N the stationarity tolerance grows like N² (round-off of second differences).
constexpr double kRoundOffSteps = 256;  ///< the reduced problem's Hessian band
/// Most constraints on one torque: 6 box sides and one norm bound.
constexpr int kMaxPerTorque = 7;

/// One constraint on one torque: value, gradient over (δ_{k−1}, δ_k, δ_{k+1}, η), multiplier.
struct TorqueConstraint {
  double c = 1.0, z = 0.0, dz = 0.0;
  Eigen::Matrix<double, 10, 1> g = Eigen::Matrix<double, 10, 1>::Zero();
};

class FreeTimeSolver {
 public:
  FreeTimeSolver(const PlanningProblem& problem, ReducedProblem* np)
      : problem_(problem), np_(*np), N_(np->steps()), n_(np->unknowns()) {
    for (int a = 0; a < 3; ++a) {
      if (std::isfinite(problem.max_torque(a)) && problem.max_torque(a) > 0) {
        box_axes_.push_back(a);
      }
    }
    for (const PlanningConstraint& c : problem.constraints) {
      if (c.kind == ConstraintKind::MaxTorqueNorm) norm_ = std::min(norm_, c.limit);
    }
    per_torque_ = 2 * static_cast<int>(box_axes_.size()) + (std::isfinite(norm_) ? 1 : 0);
    first_k_ = np_.firstFreeNode() - 1;
    last_k_ = np_.lastFreeNode() + 1;
    at_.resize(last_k_ - first_k_ + 1);
  }

  /// Raises h until every constraint holds with kStartMargin; false if it never does.
  bool startInside() {
    for (int i = 0; i < kMaxStartGrowths; ++i) {
      if (smallestValue(np_.current()) >= kStartMargin) {
        h0_ = np_.timeStep();
        return true;
      }
      np_.setTimeStep(np_.timeStep() * kStartGrowth);
    }
    return false;
  }

  FreeTimeOutcome run(double tolerance, int max_iterations, const SolverOptions* options);

 private:
  int constraintCount() const { return per_torque_ * (last_k_ - first_k_ + 1); }
  double torqueScale(int k) const { return std::sqrt(np_.scheme().torqueWeight(k, N_)); }

  /// The constraint values of torque τ (not its residual r = √w τ) into `out`.
  void values(const Vector3& tau, std::array<TorqueConstraint, kMaxPerTorque>* out) const {
    int i = 0;
    for (const int a : box_axes_) {
      (*out)[i++].c = 1.0 - tau(a) / problem_.max_torque(a);
      (*out)[i++].c = 1.0 + tau(a) / problem_.max_torque(a);
    }
    if (std::isfinite(norm_)) (*out)[i++].c = 1.0 - tau.squaredNorm() / (norm_ * norm_);
  }

  double smallestValue(const ReducedProblem::StepVectors& steps) const {
    const std::vector<Vector3> tau = np_.torques(steps);
    double smallest = std::numeric_limits<double>::infinity();
    std::array<TorqueConstraint, kMaxPerTorque> row;
    for (int k = first_k_; k <= last_k_; ++k) {
      values(tau[k], &row);
      for (int i = 0; i < per_torque_; ++i) smallest = std::min(smallest, row[i].c);
    }
    return smallest;
  }

  /// φ_μ at the current iterate (+∞ unless every constraint is ≥ fraction · its old value).
  double merit(double mu, double epsilon, bool check_boundary) const {
    const std::vector<Vector3> tau = np_.torques(np_.current());
    double phi = N_ * np_.timeStep() / T0() + epsilon * np_.scheme().cost(tau);
    std::array<TorqueConstraint, kMaxPerTorque> row;
    for (int k = first_k_; k <= last_k_; ++k) {
      values(tau[k], &row);
      for (int i = 0; i < per_torque_; ++i) {
        const double old = at_[k - first_k_][i].c;
        if (!(row[i].c > 0) || (check_boundary && row[i].c < (1 - kFractionToBoundary) * old)) {
          return std::numeric_limits<double>::infinity();
        }
        phi -= mu * std::log(row[i].c);
      }
    }
    return phi;
  }

  double T0() const { return N_ * h0_; }
  void assemble(double mu, double epsilon);
  bool solveStep(Eigen::VectorXd* d);
  bool lineSearch(const Eigen::VectorXd& d, double mu, double epsilon, double* alpha);
  void moveTo(double h, const ReducedProblem::StepVectors& steps, const Eigen::VectorXd* d,
              double alpha);
  double localDot(int k, const Eigen::Matrix<double, 10, 1>& g, const Eigen::VectorXd& d) const;
  void dualStep(const Eigen::VectorXd& d, double mu);
  void safeguardDuals(double mu);
  double barrierResidual(double mu) const;
  void initializeDuals(double mu);
  FreeTimeOutcome outcome(Termination t, const std::string& why, int iterations,
                          double epsilon) const;

  const PlanningProblem& problem_;
  ReducedProblem& np_;
  int N_, n_;
  std::vector<int> box_axes_;
  double norm_ = std::numeric_limits<double>::infinity();
  int per_torque_ = 0;
  int first_k_ = 0, last_k_ = 0;
  double h0_ = 0.0;
  std::vector<std::array<TorqueConstraint, kMaxPerTorque>> at_;  ///< at_[k − first_k_]
  // The assembled system at the current iterate.
  BandedSymmetric<double> band_{1, kHalfBandwidth};
  Eigen::VectorXd border_, rhs_, lagrangian_gradient_;
  double corner_ = 0.0;
  double last_shift_ = 0.0;  ///< the last iteration's shift (0: none)
};

void FreeTimeSolver::assemble(double mu, double epsilon) {
  band_ = BandedSymmetric<double>(n_, kHalfBandwidth);
  border_.setZero(n_);
  rhs_.setZero(n_ + 1);
  lagrangian_gradient_.setZero(n_ + 1);
  corner_ = 0.0;
  const double t2 = norm_ * norm_;
  const auto weights = [&](int k, const Vector3& r) {
    // w = ε r − Σ zᵢ ∂cᵢ/∂r: the Lagrangian's second-order weights of the residual r = √w τ.
    const double s = torqueScale(k);
    const auto& row = at_[k - first_k_];
    Vector3 w = epsilon * r;
    int i = 0;
    for (const int a : box_axes_) {
      w(a) += (row[i].z - row[i + 1].z) / (problem_.max_torque(a) * s);
      i += 2;
    }
    if (std::isfinite(norm_)) w += 2.0 * row[i].z / (s * s * t2) * r;
    return w;
  };
  const double dT = N_ * h0_ / T0();  // ∂(T/T₀)/∂η = 1
  np_.forEachStencilWithTimeStep(
      [&](const ReducedProblem::TimeStepStencil& st) {
        const double s = torqueScale(st.k);
        Eigen::Matrix<double, 3, 10> G;
        G.leftCols<9>() = st.jacobian;
        G.col(9) = st.tau_h * h0_;
        auto& row = at_[st.k - first_k_];
        values(st.tau / s, &row);
        Eigen::Matrix<double, 10, 10> H = Eigen::Matrix<double, 10, 10>::Zero();
        H.topLeftCorner<9, 9>() = st.second;
        H.block<9, 1>(0, 9) = st.second_h * h0_;
        H.block<1, 9>(9, 0) = (st.second_h * h0_).transpose();
        H(9, 9) = st.second_hh * h0_ * h0_;
        double gauss_newton = epsilon;
        int i = 0;
        for (const int a : box_axes_) {
          row[i].g = -G.row(a).transpose() / (problem_.max_torque(a) * s);
          row[i + 1].g = -row[i].g;
          i += 2;
        }
        if (std::isfinite(norm_)) {
          row[i].g = -2.0 / (s * s * t2) * (G.transpose() * st.tau);
          gauss_newton += 2.0 * row[i].z / (s * s * t2);
        }
        H += gauss_newton * G.transpose() * G;
        Eigen::Matrix<double, 10, 1> grad_f = epsilon * G.transpose() * st.tau;
        Eigen::Matrix<double, 10, 1> rhs = -grad_f, lagrangian = grad_f;
        for (int j = 0; j < per_torque_; ++j) {
          H += (row[j].z / row[j].c) * row[j].g * row[j].g.transpose();
          rhs += (mu / row[j].c) * row[j].g;
          lagrangian -= row[j].z * row[j].g;
        }
        for (int node = 0; node < 3; ++node) {
          const int v = np_.variableIndex(st.k - 1 + node);
          if (v < 0) continue;
          rhs_.segment<3>(v) += rhs.segment<3>(3 * node);
          lagrangian_gradient_.segment<3>(v) += lagrangian.segment<3>(3 * node);
          border_.segment<3>(v) += H.block<3, 1>(3 * node, 9);
        }
        rhs_(n_) += rhs(9);
        lagrangian_gradient_(n_) += lagrangian(9);
        corner_ += H(9, 9);
        const int first_slot = std::max(0, np_.firstFreeNode() - (st.k - 1));
        const int last_slot = std::min(2, np_.lastFreeNode() - (st.k - 1));
        if (first_slot <= last_slot) {
          band_.addSymmetricBlock<9>(3 * (st.k - 1 - np_.firstFreeNode()),
                                     Eigen::Matrix<double, 9, 9>(H.topLeftCorner<9, 9>()),
                                     3 * first_slot, 3 * (last_slot + 1));
        }
      },
      weights);
  rhs_(n_) -= dT;
  lagrangian_gradient_(n_) += dT;
}

/// The Newton step of the barrier problem (bordered band), with a shift δ·I (δ relative to the
/// mean diagonal: a row-relative shift would scale with the barrier terms of active bounds and
/// stall the step) until the band is positive definite, the Schur complement positive and the
/// step a descent direction of φ_μ. As IPOPT's δ_w: the next iteration starts from a third of
/// the last shift that worked.
bool FreeTimeSolver::solveStep(Eigen::VectorXd* d) {
  double scale = std::abs(corner_);
  for (int i = 0; i < n_; ++i) scale += std::abs(band_(i, i));
  scale /= n_ + 1;
  const double resumed = last_shift_ > 0 ? std::max(kFirstShift, last_shift_ / 3) : kFirstShift;
  for (double shift = 0.0; shift <= kMaxShift;
       shift = shift == 0.0 ? resumed : shift * (last_shift_ > 0 ? 8 : kShiftGrowth)) {
    BandedSymmetric<double> A = band_;
    if (shift > 0) A.addToDiagonal(shift * scale);
    Eigen::MatrixXd D(1, 1);
    D(0, 0) = corner_ + shift * scale;
    BorderedBanded factor;
    if (!factor.factor(A, Eigen::MatrixXd(border_), D)) continue;
    if (factor.inertia().positive != 1) continue;
    *d = rhs_;
    factor.solve(d);
    if (d->allFinite() && d->dot(rhs_) > 0) {
      last_shift_ = shift;
      return true;
    }
  }
  return false;
}

void FreeTimeSolver::moveTo(double h, const ReducedProblem::StepVectors& steps,
                            const Eigen::VectorXd* d, double alpha) {
  // Back to the accepted iterate (its boundary steps at its h), then h, then the attitudes:
  // setTimeStep keeps the free attitudes, which the δ-step then moves.
  np_.setCurrent(steps);
  if (!d) return;
  np_.setTimeStep(h + alpha * h0_ * (*d)(n_));
  np_.setCurrent(np_.retract(d->head(n_), alpha));
}

bool FreeTimeSolver::lineSearch(const Eigen::VectorXd& d, double mu, double epsilon,
                                double* alpha) {
  const double h = np_.timeStep();
  const ReducedProblem::StepVectors steps = np_.current();
  const double phi0 = merit(mu, epsilon, false);
  const double slope = -d.dot(rhs_);  // ∇φ_μᵀ d < 0
  double a = 1.0;
  for (int i = 0; i < kMaxHalvings; ++i, a *= 0.5) {
    if (h + a * h0_ * d(n_) <= 0) continue;
    double phi = std::numeric_limits<double>::infinity();
    try {
      moveTo(h, steps, &d, a);
      phi = merit(mu, epsilon, true);
    } catch (const std::exception&) {  // no boundary step at that h (StepTooLarge)
    }
    if (phi <= phi0 + kArmijo * a * slope) {
      *alpha = a;
      return true;
    }
    np_.setTimeStep(h);
  }
  np_.setTimeStep(h);
  moveTo(h, steps, nullptr, 0.0);
  return false;
}

double FreeTimeSolver::localDot(int k, const Eigen::Matrix<double, 10, 1>& g,
                                const Eigen::VectorXd& d) const {
  double sum = g(9) * d(n_);
  for (int node = 0; node < 3; ++node) {
    const int v = np_.variableIndex(k - 1 + node);
    if (v >= 0) sum += g.segment<3>(3 * node).dot(d.segment<3>(v));
  }
  return sum;
}

/// dz = μ/c − z − (z/c) gᵀd at the assembled point, and the largest dual step by the fraction
/// to the boundary; applied to z.
void FreeTimeSolver::dualStep(const Eigen::VectorXd& d, double mu) {
  double alpha = 1.0;
  for (int k = first_k_; k <= last_k_; ++k) {
    for (int i = 0; i < per_torque_; ++i) {
      TorqueConstraint& tc = at_[k - first_k_][i];
      tc.dz = mu / tc.c - tc.z - tc.z / tc.c * localDot(k, tc.g, d);
      if (tc.dz < 0) alpha = std::min(alpha, -kFractionToBoundary * tc.z / tc.dz);
    }
  }
  for (auto& row : at_) {
    for (int i = 0; i < per_torque_; ++i) row[i].z += alpha * row[i].dz;
  }
}

/// z within [μ/(κ c), κ μ/c] at the current values c.
void FreeTimeSolver::safeguardDuals(double mu) {
  const std::vector<Vector3> tau = np_.torques(np_.current());
  std::array<TorqueConstraint, kMaxPerTorque> row;
  for (int k = first_k_; k <= last_k_; ++k) {
    values(tau[k], &row);
    for (int i = 0; i < per_torque_; ++i) {
      TorqueConstraint& tc = at_[k - first_k_][i];
      tc.c = row[i].c;
      tc.z = std::clamp(tc.z, mu / (kDualSafeguard * tc.c), kDualSafeguard * mu / tc.c);
    }
  }
}

void FreeTimeSolver::initializeDuals(double mu) {
  const std::vector<Vector3> tau = np_.torques(np_.current());
  std::array<TorqueConstraint, kMaxPerTorque> row;
  for (int k = first_k_; k <= last_k_; ++k) {
    values(tau[k], &row);
    for (int i = 0; i < per_torque_; ++i) {
      at_[k - first_k_][i].c = row[i].c;
      at_[k - first_k_][i].z = mu / row[i].c;
    }
  }
}

/// The barrier problem's KKT residual: max(‖∇L‖∞, max |zc − μ|) at the assembled point.
double FreeTimeSolver::barrierResidual(double mu) const {
  double worst = lagrangian_gradient_.lpNorm<Eigen::Infinity>();
  for (const auto& row : at_) {
    for (int i = 0; i < per_torque_; ++i)
      worst = std::max(worst, std::abs(row[i].z * row[i].c - mu));
  }
  return worst;
}

FreeTimeOutcome FreeTimeSolver::run(double tolerance, int max_iterations,
                                    const SolverOptions* options) {
  const auto started = std::chrono::steady_clock::now();
  const int m = constraintCount();
  const double mu0 = kInitialBarrier / m;
  const double mu_final = 0.1 * tolerance / m;  // the duality gap Σ zc ≈ m μ below tolerance
  const double C0 = np_.cost(np_.current());
  const double epsilon0 = C0 > 0 ? kInitialEffortShare / C0 : 0.0;
  // Torques are second differences of the attitudes: their round-off, and so the stationarity's
  // floor, grows like N² (measured: 2e-10 at N = 512, above 1e-9 at 1024).
  const double stationarity_tolerance =
      tolerance * std::max(1.0, std::pow(static_cast<double>(N_) / kRoundOffSteps, 2));
  double mu = mu0;
  initializeDuals(mu);
  int iterations = 0;
  for (;; ++iterations) {
    const double epsilon = epsilon0 * std::max(mu / mu0, kFinalEffortFraction);
    assemble(mu, epsilon);
    double gap = 0.0;
    for (const auto& row : at_)
      for (int i = 0; i < per_torque_; ++i) gap += row[i].z * row[i].c;
    const double stationarity = lagrangian_gradient_.lpNorm<Eigen::Infinity>();
    if (mu <= mu_final && stationarity <= stationarity_tolerance && gap <= tolerance) {
      return outcome(Termination::Converged, "converged", iterations, epsilon);
    }
    if (mu > mu_final && barrierResidual(mu) <= kBarrierSolved * mu) {
      mu = std::max(mu_final, std::min(kBarrierLinear * mu, std::pow(mu, kBarrierSuperlinear)));
      continue;  // the same iterate for the next barrier problem (not an iteration)
    }
    if (options && options->cancel_requested && options->cancel_requested->load()) {
      return outcome(Termination::Cancelled, "cancelled", iterations, epsilon);
    }
    if (options && budgetSpent(withRemainingBudget(*options, started))) {
      return outcome(Termination::TimedOut, "out of time", iterations, epsilon);
    }
    if (iterations >= max_iterations) {
      return outcome(Termination::NotConverged, "iteration limit", iterations, epsilon);
    }
    Eigen::VectorXd d;
    double alpha = 0.0;
    if (!solveStep(&d) || !lineSearch(d, mu, epsilon, &alpha)) {
      if (stationarity <= 100 * stationarity_tolerance && gap <= 100 * tolerance) {
        return outcome(Termination::Converged, "converged to the round-off floor", iterations,
                       epsilon);
      }
      return outcome(Termination::NotConverged, "no descent step (line search failed)", iterations,
                     epsilon);
    }
    dualStep(d, mu);
    safeguardDuals(mu);
  }
}

FreeTimeOutcome FreeTimeSolver::outcome(Termination t, const std::string& why, int iterations,
                                        double epsilon) const {
  FreeTimeOutcome out;
  out.termination = t;
  out.steps = np_.current();
  out.time_step = np_.timeStep();
  out.start_time_step = h0_;
  out.duration = N_ * out.time_step;
  out.iterations = iterations;
  out.effort_weight = epsilon;
  // Residuals of the Lagrangian T/T₀ + εC − Σ z c (ε → 0 with μ: minimum time at the end).
  out.stationarity = lagrangian_gradient_.lpNorm<Eigen::Infinity>();
  out.time_row = std::abs(lagrangian_gradient_(n_));
  out.smallest_value = std::numeric_limits<double>::infinity();
  out.torque_multipliers.assign(N_ + 1, Vector3::Zero());
  for (int k = first_k_; k <= last_k_; ++k) {
    const auto& row = at_[k - first_k_];
    for (int i = 0; i < per_torque_; ++i) {
      out.complementarity += row[i].z * row[i].c;
      out.smallest_value = std::min(out.smallest_value, row[i].c);
    }
    for (std::size_t j = 0; j < box_axes_.size(); ++j) {
      out.torque_multipliers[k](box_axes_[j]) = row[2 * j].z - row[2 * j + 1].z;
    }
  }
  out.maneuver = np_.maneuver(out.steps);
  std::ostringstream message;
  message << why << " after " << iterations << " iterations: T = " << out.duration
          << " s, stationarity " << out.stationarity << " (h row " << out.time_row
          << "), complementarity " << out.complementarity << ", min c " << out.smallest_value;
  out.message = message.str();
  return out;
}

}  // namespace

std::string freeTimeUnsupported(const PlanningProblem& problem) {
  if (problem.scheme == SchemeKind::FourthOrder) {
    return "scheme: fourth_order (a Richardson pair of second_order plans, no one transcription)";
  }
  if (problem.effects && !problem.effects->empty()) return "effects (time-dependent torques)";
  for (const PlanningConstraint& c : problem.constraints) {
    if (c.kind == ConstraintKind::MaxAngularRate) return "constraints: max_angular_rate";
    if (c.isCone()) return "constraints: keep_out / keep_in cones";
  }
  return "";
}

FreeTimeOutcome solveFreeTime(const PlanningProblem& problem, const std::vector<Matrix3>& attitudes,
                              double start_duration, double tolerance, int max_iterations,
                              const SolverOptions* options) {
  PlanningProblem at = problem;
  at.duration = start_duration;
  FreeTimeOutcome failed;
  failed.termination = Termination::NotConverged;
  try {
    ReducedProblem np(at);
    np.setInteriorFromAttitudes(attitudes);
    FreeTimeSolver solver(problem, &np);
    if (!solver.startInside()) {
      failed.message = "no strictly feasible start: the constraints still fail at " +
                       std::to_string(std::pow(kStartGrowth, kMaxStartGrowths)) +
                       " times the start's duration";
      return failed;
    }
    return solver.run(tolerance, max_iterations, options);
  } catch (const StepTooLarge& e) {
    failed.message = std::string("the boundary rates admit no step: ") + e.what();
    return failed;
  }
}

}  // namespace attitude_planner
