// Newton's method on the first-order optimality conditions of the discrete problem (seed 000,
// Problem 3.2), O(N) time and memory per iteration.
//
// Formulation. The boundary data fix four attitudes: R_0, R_1 = R_0 F_0 (F_0 from Ω_0),
// R_{N−1} = R_N F_{N−1}ᵀ (F_{N−1} from Ω_{N−1}) and R_N. Every torque is then an explicit function
// of three consecutive attitudes (discrete_scheme.hpp):
//
//     τ_k(R_{k−1}, R_k, R_{k+1}) = (μ(F_k) − F_{k−1}ᵀ μ(F_{k−1}))/h,   F_k = R_kᵀ R_{k+1},
//
// so the constrained problem is the unconstrained minimization of C = Σ_{k=1}^{N−1} ½|τ_k|² over
// R_2..R_{N−2} (3(N−3) unknowns; the seed's 3(2N−3) unknowns τ, Ω with its 3(N−1) dynamics
// equations eliminated exactly). Its stationarity conditions ∇C = 0 are the discrete necessary
// conditions. With right perturbations R_j exp(δ_j^) the gradient is Σ_k J_kᵀ τ_k and the Hessian
// of δ ↦ C(R exp δ) is JᵀJ + sym(Σ_k Σ_i τ_{k,i} ∂J_{k,i}/∂δ): the derivative of the analytic
// Jacobian rows is taken exactly with dual numbers, and its antisymmetric part is cancelled
// exactly by the derivative of the retraction (dJr(δ)/dδ = −½ (·)^), so the symmetric part is
// the exact Hessian. τ_k couples R_{k−1..k+1}, so the Hessian is block-pentadiagonal: a banded
// Cholesky factorization costs O(N).
//
// Globalization: the cost itself is the merit function. If the Hessian is not positive definite a
// multiple of the identity is added (Levenberg); an Armijo backtracking line search along the
// retraction R_j exp(α δ_j^) follows. Convergence: the Newton decrement relative to |τ|₂ is below
// the tolerance; the step it came with is then taken, leaving the torques exact to ~round-off.
#include <Eigen/Cholesky>
#include <chrono>
#include <cmath>
#include <sstream>

#include "attitude_planner/dual.hpp"
#include "attitude_planner/errors.hpp"
#include "attitude_planner/solvers.hpp"

namespace attitude_planner {

namespace {

using Matrix39 = Eigen::Matrix<double, 3, 9>;
using Matrix99 = Eigen::Matrix<double, 9, 9>;
using Dual9 = Dual<9>;

/// τ_k and its Jacobian with respect to right perturbations (a, b, c) of (R_{k−1}, R_k, R_{k+1}).
/// Derivation: F_{k−1} → F_{k−1} exp(b − F_{k−1}ᵀ a), F_k → F_k exp(c − F_kᵀ b),
/// dμ(F)[ε] = D(F) ε, G(F) = Fᵀμ(F), dG(F) = (Fᵀμ(F))^ + Fᵀ D(F).
template <typename S>
void torqueStencil(const DiscreteScheme& scheme, const so3::Mat3<S>& R_prev, const so3::Mat3<S>& R,
                   const so3::Mat3<S>& R_next, so3::Vec3<S>* tau,
                   Eigen::Matrix<S, 3, 9>* jacobian) {
  const S h(scheme.timeStep());
  const so3::Mat3<S> F_prev = R_prev.transpose() * R;
  const so3::Mat3<S> F = R.transpose() * R_next;
  const so3::Vec3<S> mu_prev = scheme.momentum<S>(F_prev);
  const so3::Vec3<S> mu = scheme.momentum<S>(F);
  const so3::Vec3<S> carried = F_prev.transpose() * mu_prev;  // G(F_{k−1})
  *tau = (mu - carried) / h;
  if (!jacobian) return;
  const so3::Mat3<S> D_prev = scheme.momentumJacobian<S>(F_prev);
  const so3::Mat3<S> D = scheme.momentumJacobian<S>(F);
  const so3::Mat3<S> dG_prev = so3::hat<S>(carried) + F_prev.transpose() * D_prev;
  jacobian->template block<3, 3>(0, 0) = dG_prev * F_prev.transpose() / h;
  jacobian->template block<3, 3>(0, 3) = -(D * F.transpose() + dG_prev) / h;
  jacobian->template block<3, 3>(0, 6) = D / h;
}

/// Symmetric positive definite banded matrix (lower band) with an in-place Cholesky solve.
class BandedSpdMatrix {
 public:
  BandedSpdMatrix(int n, int bandwidth) : n_(n), p_(bandwidth), band_(n, bandwidth + 1) {
    band_.setZero();
  }
  void setZero() { band_.setZero(); }
  /// Adds v to A(i, j) for |i − j| ≤ bandwidth (only the lower triangle is stored).
  void add(int i, int j, double v) {
    if (i < j) std::swap(i, j);
    band_(i, i - j) += v;
  }
  void addDiagonal(double v) { band_.col(0).array() += v; }
  double diagonalMax() const { return band_.col(0).cwiseAbs().maxCoeff(); }
  /// Cholesky A = L Lᵀ in the band, then solves A x = b. Returns false if A is not SPD.
  bool factorAndSolve(Eigen::VectorXd* x) {
    Eigen::MatrixXd& L = band_;
    for (int j = 0; j < n_; ++j) {
      double d = L(j, 0);
      for (int k = std::max(0, j - p_); k < j; ++k) d -= L(j, j - k) * L(j, j - k);
      if (!(d > 0.0) || !std::isfinite(d)) return false;
      const double ljj = std::sqrt(d);
      L(j, 0) = ljj;
      for (int i = j + 1; i <= std::min(n_ - 1, j + p_); ++i) {
        double s = L(i, i - j);
        for (int k = std::max(0, i - p_); k < j; ++k) s -= L(i, i - k) * L(j, j - k);
        L(i, i - j) = s / ljj;
      }
    }
    Eigen::VectorXd& y = *x;
    for (int i = 0; i < n_; ++i) {  // L y = b
      double s = y(i);
      for (int k = std::max(0, i - p_); k < i; ++k) s -= L(i, i - k) * y(k);
      y(i) = s / L(i, 0);
    }
    for (int i = n_ - 1; i >= 0; --i) {  // Lᵀ x = y
      double s = y(i);
      for (int k = i + 1; k <= std::min(n_ - 1, i + p_); ++k) s -= L(k, k - i) * y(k);
      y(i) = s / L(i, 0);
    }
    return true;
  }

 private:
  int n_, p_;
  Eigen::MatrixXd band_;  ///< band_(i, d) = A(i, i − d)
};

/// The state of one solve: attitudes R_0..R_N, with R_2..R_{N−2} free.
class NewtonProblem {
 public:
  NewtonProblem(const PlanningProblem& problem)
      : problem_(problem),
        N_(problem.steps),
        scheme_(problem.scheme, problem.inertia, problem.duration / problem.steps) {}

  int steps() const { return N_; }
  const DiscreteScheme& scheme() const { return scheme_; }
  std::vector<Matrix3>& attitudes() { return R_; }

  /// Fixes R_0, R_1, R_{N−1}, R_N from the boundary data; the interior is the geodesic from R_1
  /// to R_{N−1} (or the warm start). Throws StepTooLarge if a boundary velocity has no step.
  void initialize(const Maneuver* warm_start) {
    R_.assign(N_ + 1, Matrix3::Identity());
    R_[0] = problem_.initial_attitude;
    R_[1] = problem_.initial_attitude * scheme_.stepFromVelocity(problem_.initial_velocity);
    R_[N_] = problem_.final_attitude;
    R_[N_ - 1] =
        problem_.final_attitude * scheme_.stepFromVelocity(problem_.final_velocity).transpose();
    if (warm_start && warm_start->steps() == N_) {
      for (int j = 2; j <= N_ - 2; ++j) R_[j] = warm_start->attitude[j];
      return;
    }
    const Vector3 span = so3::log(Matrix3(R_[1].transpose() * R_[N_ - 1]));
    for (int j = 2; j <= N_ - 2; ++j) {
      R_[j] = R_[1] * so3::exp(Vector3(span * double(j - 1) / double(N_ - 2)));
    }
  }

  /// τ_k, k = 0..N (τ_0 = τ_N = 0), for attitudes R.
  std::vector<Vector3> torques(const std::vector<Matrix3>& R) const {
    std::vector<Vector3> tau(N_ + 1, Vector3::Zero());
    for (int k = 1; k < N_; ++k) {
      torqueStencil<double>(scheme_, R[k - 1], R[k], R[k + 1], &tau[k], nullptr);
    }
    return tau;
  }

  static double cost(const std::vector<Vector3>& tau) {
    double c = 0;
    for (const Vector3& t : tau) c += 0.5 * t.squaredNorm();
    return c;
  }

  /// Gradient and exact Hessian of the cost at the current attitudes; returns the cost.
  double gradientAndHessian(Eigen::VectorXd* gradient, BandedSpdMatrix* hessian,
                            double* gradient_scale) const {
    const int n = 3 * (N_ - 3);
    gradient->setZero(n);
    hessian->setZero();
    double cost = 0.0;
    double jacobian_scale = 0.0, torque_scale = 0.0;
    for (int k = 1; k < N_; ++k) {
      // Dual evaluation: value = τ_k, J_k; derivatives = ∂J_k/∂(a, b, c)
      so3::Mat3<Dual9> Rd[3];
      for (int s = 0; s < 3; ++s) {
        so3::Vec3<Dual9> delta;
        for (int i = 0; i < 3; ++i) delta(i) = Dual9(0.0, 3 * s + i);
        Rd[s] = R_[k - 1 + s].cast<Dual9>() * so3::exp<Dual9>(delta);
      }
      so3::Vec3<Dual9> tau_d;
      Eigen::Matrix<Dual9, 3, 9> jac_d;
      torqueStencil<Dual9>(scheme_, Rd[0], Rd[1], Rd[2], &tau_d, &jac_d);
      Vector3 tau;
      Matrix39 jac;
      for (int i = 0; i < 3; ++i) {
        tau(i) = tau_d(i).v;
        for (int m = 0; m < 9; ++m) jac(i, m) = jac_d(i, m).v;
      }
      Matrix99 second = Matrix99::Zero();  // Σ_i τ_i ∂J_{i,m}/∂δ_l
      for (int i = 0; i < 3; ++i) {
        for (int m = 0; m < 9; ++m) second.row(m) += tau(i) * jac_d(i, m).d.transpose();
      }
      const Matrix99 block = jac.transpose() * jac + 0.5 * (second + second.transpose());
      const Eigen::Matrix<double, 9, 1> g = jac.transpose() * tau;
      cost += 0.5 * tau.squaredNorm();
      jacobian_scale = std::max(jacobian_scale, jac.cwiseAbs().maxCoeff());
      torque_scale = std::max(torque_scale, tau.cwiseAbs().maxCoeff());
      for (int s = 0; s < 3; ++s) {
        const int vs = variableIndex(k - 1 + s);
        if (vs < 0) continue;
        gradient->segment<3>(vs) += g.segment<3>(3 * s);
        for (int t = 0; t <= s; ++t) {
          const int vt = variableIndex(k - 1 + t);
          if (vt < 0) continue;
          for (int i = 0; i < 3; ++i) {
            for (int j = 0; j < 3; ++j) {
              if (s == t && j > i) continue;  // diagonal block: lower triangle once
              hessian->add(vs + i, vt + j, block(3 * s + i, 3 * t + j));
            }
          }
        }
      }
    }
    // Relative gradient: |∇C| compared with |J|·|τ| (units cancel), floored for τ ≈ 0.
    *gradient_scale = jacobian_scale * std::max(torque_scale, 1e-300);
    return cost;
  }

  /// Index of the first of R_j's three unknowns, or −1 if R_j is fixed.
  int variableIndex(int j) const { return (j >= 2 && j <= N_ - 2) ? 3 * (j - 2) : -1; }

  /// R_j exp(α δ_j) for the free attitudes.
  std::vector<Matrix3> retract(const Eigen::VectorXd& delta, double alpha) const {
    std::vector<Matrix3> R = R_;
    for (int j = 2; j <= N_ - 2; ++j) {
      R[j] = R_[j] * so3::exp(Vector3(alpha * delta.segment<3>(variableIndex(j))));
    }
    return R;
  }

 private:
  const PlanningProblem& problem_;
  int N_;
  DiscreteScheme scheme_;
  std::vector<Matrix3> R_;
};

}  // namespace

PlanResult solveWithNewton(const PlanningProblem& problem, const SolverOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  const auto elapsed = [&] {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  };
  PlanResult result;
  NewtonProblem np(problem);
  try {
    np.initialize(options.warm_start);
  } catch (const StepTooLarge& e) {
    result.message = std::string("boundary velocity: ") + e.what();
    return result;
  }
  const int N = np.steps();
  const int n = 3 * (N - 3);
  BandedSpdMatrix hessian(n, 8);
  Eigen::VectorXd gradient(n), delta(n);
  double gradient_scale = 0.0;
  double relative_gradient = 0.0;
  double relative_decrement = 0.0;
  bool converged = false;
  std::string reason = "iteration limit reached";
  int iteration = 0;
  for (;; ++iteration) {
    const double cost = np.gradientAndHessian(&gradient, &hessian, &gradient_scale);
    relative_gradient = gradient.size() ? gradient.cwiseAbs().maxCoeff() / gradient_scale : 0.0;
    if (!std::isfinite(cost) || !std::isfinite(relative_gradient)) {
      reason = "non-finite cost or gradient (step too large for this h? increase steps)";
      break;
    }
    if (gradient.cwiseAbs().maxCoeff() == 0.0) {  // e.g. the zero maneuver
      converged = true;
      relative_decrement = 0.0;
      reason = "converged";
      break;
    }
    if (iteration >= options.max_iterations) break;
    if (options.time_budget_s > 0 && elapsed() > options.time_budget_s) {
      reason = "time budget exceeded";
      break;
    }
    // Newton direction; Levenberg shift until the Hessian is positive definite.
    double shift = 0.0;
    bool factored = false;
    for (int attempt = 0; attempt < 40; ++attempt) {
      BandedSpdMatrix trial = hessian;
      if (shift > 0) trial.addDiagonal(shift);
      delta = -gradient;
      if (trial.factorAndSolve(&delta)) {
        factored = true;
        break;
      }
      shift = shift == 0.0 ? 1e-10 * hessian.diagonalMax() : 10.0 * shift;
    }
    if (!factored) {
      reason = "Hessian could not be made positive definite";
      break;
    }
    // Newton decrement λ = √(gᵀH⁻¹g): λ ≈ the ℓ2 error of the torques, so λ/|τ|₂ with
    // |τ|₂ = √(2C) is the relative torque accuracy — scale-free, unlike the raw gradient, whose
    // conditioning grows like N⁴.
    const double slope = gradient.dot(delta);
    relative_decrement = std::sqrt(std::max(0.0, -slope)) / std::sqrt(std::max(2.0 * cost, 1e-300));
    const bool final_step = shift == 0.0 && relative_decrement <= options.tolerance;
    // Armijo backtracking on the cost along the retraction. Once the predicted decrease is below
    // the cost's round-off the test is meaningless and the full Newton step is taken.
    double alpha = 1.0;
    bool accepted = final_step || -slope <= 1e-13 * cost;
    std::vector<Matrix3> trial_R = np.retract(delta, alpha);
    for (int back = 0; !accepted && back < 50; ++back) {
      const double trial_cost = NewtonProblem::cost(np.torques(trial_R));
      if (std::isfinite(trial_cost) && trial_cost <= cost + 1e-4 * alpha * slope) {
        accepted = true;
        break;
      }
      alpha *= 0.5;
      trial_R = np.retract(delta, alpha);
    }
    if (!accepted) {
      reason = "line search failed";
      break;
    }
    np.attitudes() = trial_R;
    IterationInfo info{iteration + 1, cost, relative_decrement, alpha};
    result.history.push_back(info);
    if (final_step) {
      // This last step took the iterate from the tolerance to ~round-off (quadratic convergence).
      converged = true;
      reason = "converged";
      ++iteration;
      break;
    }
    if (options.on_iteration && !options.on_iteration(info)) {
      reason = "cancelled";
      ++iteration;
      break;
    }
  }
  // Report the first-order residual at the final iterate, not at the one before the last step.
  if (converged && iteration > 0) {
    np.gradientAndHessian(&gradient, &hessian, &gradient_scale);
    relative_gradient = gradient.size() ? gradient.cwiseAbs().maxCoeff() / gradient_scale : 0.0;
  }
  result.iterations = iteration;
  result.max_residual = relative_gradient;
  result.newton_decrement = relative_decrement;
  try {
    evaluatePlan(problem, np.torques(np.attitudes()), &result);
  } catch (const StepTooLarge& e) {
    result.converged = false;
    result.message = std::string("replay of the planned torques failed: ") + e.what();
    return result;
  }
  result.converged = converged;
  std::ostringstream msg;
  msg << reason << " after " << iteration << " iterations (relative gradient " << relative_gradient
      << ", relative Newton decrement " << relative_decrement << ")";
  result.message = msg.str();
  return result;
}

}  // namespace attitude_planner
