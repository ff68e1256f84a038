// Shooting for the drift + two-input BVP (seed 001, (3.8)–(3.10)); see the header and
// docs/design/drift_two_input.md ("Planner").
#include "attitude_planner/drift_two_input/planner.hpp"

#include <Eigen/Cholesky>
#include <Eigen/LU>
#include <Eigen/QR>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <sstream>
#include <vector>

#include "attitude_planner/errors.hpp"
#include "attitude_planner/input_rules.hpp"
#include "lie/dual.hpp"

namespace attitude_planner {

namespace {

template <typename S>
using Quat = Eigen::Matrix<S, 4, 1>;  // (w, x, y, z)

// ---- Taylor-series integrator of the extremal flow ----------------------------------------
//
// The state (p, q, J) of an extremal obeys a quadratic ODE (seed (3.8), (3.15)–(3.17), Prop. 3.1):
//   ṗ = p × ξ(p),  q̇ = ½ q ⊗ (0, ξ(p)),  J̇ = ½(p1²/c1 + p2²/c2),  ξ(p) = (p1/c1, p2/c2, 1)
// (q the Hamilton quaternion of g, ġ = g ξ^). Its Taylor coefficients about any point follow from
// Cauchy products, x_{k+1} = (1/(k+1)) Σ_{j≤k} F(x_j, x_{k−j}), so a high order costs O(K²) per
// step and no Jacobian of the vector field. The step is a fixed fraction of the radius of
// convergence estimated from the last two coefficients (Jorba & Zou, Exp. Math. 14 (2005)), so
// it adapts to the costate's size and depends on the state only: the step sequence of an
// extremal is the same whatever output sampling is asked for.
constexpr int kTaylorOrder = 20;
// h = kStepFraction · ρ: the first neglected term is ≈ kStepFraction^21 ≈ 7e-17 of the state.
constexpr double kStepFraction = 0.17;
// Rate·T above which an integration is refused (≈ 3e5 steps): a costate that large is no
// candidate for a least-cost extremal, and refusing it keeps every trial point cheap.
constexpr double kMaxTurns = 5e4;

template <typename S>
struct ExtremalState {
  so3::Vec3<S> p;  // costate p(t) [c·rad/s]
  Quat<S> q;       // attitude g(t) as a quaternion (not renormalized: the flow keeps |q| = 1)
  S cost;          // ∫₀ᵗ ½(c1 u1² + c2 u2²) dt
};

template <typename S>
struct TaylorSeries {
  // Plain arrays (not Eigen vectors of S): with S = Dual<3> the Cauchy products below are the
  // whole cost of a Jacobian, and Eigen's expression templates over a custom scalar did not
  // inline (10x slower).
  S p[kTaylorOrder + 1][3];
  S q[kTaylorOrder + 1][4];
  S cost[kTaylorOrder + 1];

  // Coefficients about x: x(t + s) = Σ_k x_k s^k.
  void expand(const ExtremalState<S>& x, const DriftTwoInputWeights& w) {
    const S i1(1.0 / w.c1), i2(1.0 / w.c2);
    for (int i = 0; i < 3; ++i) p[0][i] = x.p(i);
    for (int i = 0; i < 4; ++i) q[0][i] = x.q(i);
    cost[0] = x.cost;
    // coefficients of (ξ1, ξ2) = (p1/c1, p2/c2); ξ3 ≡ 1 (the drift) enters only ξ_0, so its
    // products appear only for j = k below
    S xi[kTaylorOrder][2];
    for (int k = 0; k < kTaylorOrder; ++k) {
      xi[k][0] = p[k][0] * i1;
      xi[k][1] = p[k][1] * i2;
      const S* a = p[k];  // j = k: the terms with the drift (0, 0, 1)
      const S* qa = q[k];
      S dp0 = a[1], dp1 = -a[0], dp2(0.0);                 // p_k × e3
      S dq0(-qa[3]), dq1(qa[2]), dq2(-qa[1]), dq3(qa[0]);  // q_k ⊗ (0, e3)
      S dc(0.0);
      for (int j = 0; j <= k; ++j) {
        const S* pj = p[j];
        const S* qj = q[j];
        const S* b = xi[k - j];  // (b0, b1, 0)
        dp0 -= pj[2] * b[1];     // p_j × b
        dp1 += pj[2] * b[0];
        dp2 += pj[0] * b[1] - pj[1] * b[0];
        dq0 -= qj[1] * b[0] + qj[2] * b[1];  // q_j ⊗ (0, b)
        dq1 += qj[0] * b[0] - qj[3] * b[1];
        dq2 += qj[0] * b[1] + qj[3] * b[0];
        dq3 += qj[1] * b[1] - qj[2] * b[0];
        dc += pj[0] * b[0] + pj[1] * b[1];  // p_j · ξ_{k−j}: Cauchy product of p1²/c1 + p2²/c2
      }
      const double f = 1.0 / (k + 1);
      const S fs(f), hf(0.5 * f);
      p[k + 1][0] = dp0 * fs;
      p[k + 1][1] = dp1 * fs;
      p[k + 1][2] = dp2 * fs;
      q[k + 1][0] = dq0 * hf;
      q[k + 1][1] = dq1 * hf;
      q[k + 1][2] = dq2 * hf;
      q[k + 1][3] = dq3 * hf;
      cost[k + 1] = dc * hf;
    }
  }

  // Radius of convergence estimated from the last two coefficients of p and of q (both, so a
  // series with vanishing odd or even terms is not over-estimated); values only.
  double radius() const {
    auto norm = [](const S* v, int n) {
      double s = 0.0;
      for (int i = 0; i < n; ++i)
        s += drift_two_input::valueOf(v[i]) * drift_two_input::valueOf(v[i]);
      return std::sqrt(s);
    };
    double r = INFINITY;
    const double p0 = norm(p[0], 3), q0 = norm(q[0], 4);
    for (int k : {kTaylorOrder - 1, kTaylorOrder}) {
      const double pk = norm(p[k], 3), qk = norm(q[k], 4);
      if (p0 > 0.0 && pk > 0.0) r = std::min(r, std::pow(p0 / pk, 1.0 / k));
      if (qk > 0.0) r = std::min(r, std::pow(q0 / qk, 1.0 / k));
    }
    return r;
  }

  // Horner evaluation at offset s.
  ExtremalState<S> at(double s) const {
    const S ss(s);
    S pv[3], qv[4], cv = cost[kTaylorOrder];
    for (int i = 0; i < 3; ++i) pv[i] = p[kTaylorOrder][i];
    for (int i = 0; i < 4; ++i) qv[i] = q[kTaylorOrder][i];
    for (int k = kTaylorOrder - 1; k >= 0; --k) {
      for (int i = 0; i < 3; ++i) pv[i] = pv[i] * ss + p[k][i];
      for (int i = 0; i < 4; ++i) qv[i] = qv[i] * ss + q[k][i];
      cv = cv * ss + cost[k];
    }
    ExtremalState<S> x;
    x.p = so3::Vec3<S>(pv[0], pv[1], pv[2]);
    x.q = Quat<S>(qv[0], qv[1], qv[2], qv[3]);
    x.cost = cv;
    return x;
  }
};

// Integrates the extremal from x over [0, T]; after choosing each step calls
// visit(t, h, series) (dense output on [t, t + h]). Returns x(T); counts steps.
template <typename S, typename Visit>
ExtremalState<S> integrateTaylor(ExtremalState<S> x, double T, const DriftTwoInputWeights& w,
                                 double max_step, int* steps, Visit&& visit) {
  const Vector3 p0(drift_two_input::valueOf(x.p(0)), drift_two_input::valueOf(x.p(1)),
                   drift_two_input::valueOf(x.p(2)));
  // |p| is conserved (Casimir), so this bounds every rate along the extremal
  const double rate = drift_two_input::velocity<double>(p0, w).norm() +
                      p0.norm() * std::max(1.0 / w.c1, 1.0 / w.c2);
  if (!(rate * T <= kMaxTurns)) {
    std::ostringstream os;
    os << "costate |p(0)| = " << p0.norm() << " too large to integrate over T = " << T
       << " s (rate x T = " << rate * T << ")";
    throw StepTooLarge(os.str());
  }
  TaylorSeries<S> series;
  double t = 0.0;
  int n = 0;
  while (t < T) {
    series.expand(x, w);
    double h = kStepFraction * series.radius();
    if (max_step > 0.0) h = std::min(h, max_step);
    if (!(h > 0.0)) throw StepTooLarge("Taylor step is not positive (non-finite state?)");
    const bool last = t + h >= T;
    if (last) h = T - t;
    visit(t, h, series);
    x = series.at(h);
    t = last ? T : t + h;
    ++n;
  }
  if (steps) *steps = n;
  return x;
}

Quat<double> quaternionOf(const Matrix3& g) {
  return so3::quaternionCoefficients<double>(g);
}

Quat<double> conjugate(const Quat<double>& q) {
  return Quat<double>(q(0), -q(1), -q(2), -q(3));
}

// log(g1ᵀ g) from quaternions: q1* ⊗ q (q renormalized: its norm carries only integration error).
template <typename S>
so3::Vec3<S> terminalResidual(const Quat<S>& q, const Quat<double>& q1_conjugate) {
  const Quat<S> e = so3::quaternionProduct<S>(q1_conjugate.cast<S>(), Quat<S>(q / q.norm()));
  return so3::logOfQuaternion<S>(e);
}

// Shooting map p0 ↦ (r, cost) [and ∂r/∂p0 with Dual<3>] for fixed g0, target and weights.
struct Shooter {
  Matrix3 g0;
  double T;
  double max_step;
  Quat<double> q0;
  int last_steps = 0;

  Shooter(const Matrix3& g0_, double T_, double max_step_)
      : g0(g0_), T(T_), max_step(max_step_), q0(quaternionOf(g0_)) {}

  // r = log(targetᵀ g(T; p)); false if the costate is too large to integrate.
  bool value(const Vector3& p, const Quat<double>& target_conj, const DriftTwoInputWeights& w,
             Vector3* r, double* cost) {
    try {
      const ExtremalState<double> xT = integrateTaylor<double>(
          {p, q0, 0.0}, T, w, max_step, &last_steps, [](double, double, const auto&) {});
      *r = terminalResidual<double>(xT.q, target_conj);
      if (cost) *cost = xT.cost;
    } catch (const StepTooLarge&) {
      return false;
    }
    return r->allFinite();
  }

  bool jacobian(const Vector3& p, const Quat<double>& target_conj, const DriftTwoInputWeights& w,
                Vector3* r, Matrix3* J, double* cost) {
    using D = Dual<3>;
    const so3::Vec3<D> pd(D(p.x(), 0), D(p.y(), 1), D(p.z(), 2));
    try {
      const ExtremalState<D> xT =
          integrateTaylor<D>({pd, q0.cast<D>(), D(0.0)}, T, w, max_step, &last_steps,
                             [](double, double, const auto&) {});
      const so3::Vec3<D> rd = terminalResidual<D>(xT.q, target_conj);
      for (int i = 0; i < 3; ++i) {
        (*r)(i) = rd(i).v;
        J->row(i) = rd(i).d.transpose();
      }
      if (cost) *cost = xT.cost.v;
    } catch (const StepTooLarge&) {
      return false;
    }
    return r->allFinite() && J->allFinite();
  }
};

// Wall-clock budget of one planDriftTwoInput call (SolverOptions::time_budget_s semantics).
class Deadline {
 public:
  explicit Deadline(double budget_s) : budget_(budget_s), start_(Clock::now()) {}
  bool expired() const { return budget_ > 0.0 && elapsed() > budget_; }
  double elapsed() const { return std::chrono::duration<double>(Clock::now() - start_).count(); }

 private:
  using Clock = std::chrono::steady_clock;
  double budget_;
  Clock::time_point start_;
};

void validate(const DriftTwoInputRequest& rq) {
  validateDriftTwoInputWeights(rq.weights);
  auto fail = [](const std::string& field, double value, const std::string& why) {
    std::ostringstream os;
    os << field << " " << why << ", got " << value;
    throw InvalidInput(os.str());
  };
  requireDuration(rq.duration, "duration");
  if (rq.steps < 1) fail("steps", rq.steps, "must be >= 1");
  if (!std::isfinite(rq.max_step) || rq.max_step < 0) {
    fail("max_step", rq.max_step, "must be >= 0 (0 = adaptive only)");
  }
  if (!(rq.tolerance > 0)) fail("tolerance", rq.tolerance, "must be > 0");
  if (rq.max_iterations < 1) fail("max_iterations", rq.max_iterations, "must be >= 1");
  if (rq.shooting_intervals < 1 || rq.shooting_intervals > rq.steps) {
    fail("shooting_intervals", rq.shooting_intervals, "must be in [1, steps]");
  }
  if (rq.max_continuation_stages < 1) {
    fail("max_continuation_stages", rq.max_continuation_stages, "must be >= 1");
  }
  if (!std::isfinite(rq.time_budget_s) || rq.time_budget_s < 0) {
    fail("time_budget", rq.time_budget_s, "must be a finite number >= 0 s (0 = none)");
  }
  for (const auto& [name, R] :
       {std::pair<const char*, const Matrix3*>{"g0", &rq.g0}, {"g1", &rq.g1}}) {
    if (!R->allFinite() || so3::orthogonalityError(*R) > 1e-9) {
      fail(name, so3::orthogonalityError(*R), "must be a rotation matrix (orthogonality error)");
    }
  }
  if (rq.initial_costate && !rq.initial_costate->allFinite()) {
    throw InvalidInput("initial_costate must be finite");
  }
}

// ---- Levenberg–Marquardt on r(p) = 0 ---------------------------------------------------------
//
// Newton's step when it is accepted (λ → 0 near a root: quadratic convergence), a damped step
// towards the gradient of ½|r|² when not (Nielsen's λ update). Each trial step is also capped
// relative to |p|, so an iterate does not jump to a far-away (and typically much costlier)
// extremal: the start decides which extremal is found.
struct Solve {
  bool ok = false;
  Vector3 p = Vector3::Zero();
  double error = INFINITY;
  double cost = INFINITY;
  int iterations = 0;
};

constexpr double kMaxRelativeStep = 0.5;  // |Δp| ≤ 0.5 max(|p|, p_scale) per iteration

Solve levenbergMarquardt(Shooter& sh, const Quat<double>& target_conj,
                         const DriftTwoInputWeights& w, const Vector3& start, double tol,
                         int max_iterations, double p_scale, const Deadline& deadline) {
  Solve s;
  s.p = start;
  Vector3 r;
  Matrix3 J;
  if (!sh.jacobian(s.p, target_conj, w, &r, &J, &s.cost)) return s;
  s.error = r.norm();
  double lambda = -1.0, nu = 2.0;  // λ < 0: not yet set (first step is Newton's if regular)
  while (s.error > tol && s.iterations < max_iterations && !deadline.expired()) {
    ++s.iterations;
    const Matrix3 A = J.transpose() * J;
    const Vector3 g = J.transpose() * r;
    Vector3 dp;
    if (lambda < 0.0) {
      Eigen::FullPivLU<Matrix3> lu(J);
      if (lu.isInvertible()) {
        dp = -lu.solve(r);
      } else {
        lambda = 1e-3 * A.diagonal().maxCoeff();
        dp = -(A + lambda * Matrix3::Identity()).ldlt().solve(g);
      }
    } else {
      const Matrix3 D = A.diagonal().cwiseMax(1e-12 * A.diagonal().maxCoeff()).asDiagonal();
      dp = -(A + lambda * D).ldlt().solve(g);
    }
    const double cap = kMaxRelativeStep * std::max(s.p.norm(), p_scale);
    if (dp.norm() > cap) dp *= cap / dp.norm();
    if (!dp.allFinite()) break;
    const Vector3 trial = s.p + dp;
    Vector3 rt;
    double ct = 0.0;
    const bool evaluated = sh.value(trial, target_conj, w, &rt, &ct);
    const double predicted = s.error * s.error - (r + J * dp).squaredNorm();
    const double actual = evaluated ? s.error * s.error - rt.squaredNorm() : -INFINITY;
    const double rho = predicted > 0.0 ? actual / predicted : -1.0;
    // accept a gain; at round-off level any non-increase (the last digits are noise)
    if (evaluated && (rho > 1e-4 || (rt.norm() <= 1e-13 && rt.norm() <= s.error))) {
      if (!sh.jacobian(trial, target_conj, w, &r, &J, &s.cost)) break;
      s.p = trial;
      s.error = r.norm();
      if (lambda >= 0.0) {
        lambda *= std::max(1.0 / 3.0, 1.0 - std::pow(2.0 * rho - 1.0, 3));
        if (lambda < 1e-14 * A.diagonal().maxCoeff()) lambda = -1.0;  // back to plain Newton
      }
      nu = 2.0;
    } else {
      // a rejected step at round-off size: |r| is at its floor (above tol: ill-conditioned)
      if (dp.norm() <= 1e-13 * std::max(s.p.norm(), p_scale)) break;
      if (lambda < 0.0) lambda = 1e-3 * A.diagonal().maxCoeff();
      lambda *= nu;
      nu *= 2.0;
      if (nu > 1e12) break;  // no descent: a local minimum of |r| that is not a root
    }
  }
  s.ok = s.error <= tol;
  return s;
}

// ---- Starts: the extremals of the symmetric problem c1 = c2 = c ------------------------------
//
// For c1 = c2 = c, (3.15)–(3.16) rotate (p1, p2) at the constant rate ν = p3/c − 1 with p3
// constant (Prop. 4.2, corrected), so ξ(t) = exp(νt E3) ξ(0) and
//   g(t) = g0 exp(t ξ̂(0) + νt E3) exp(−νt E3) = g0 exp(t p̂0/c) exp(−νt E3)
// (differentiate: ġ = g exp(νt E3)ξ(0)^). g(T) = g1 is then exp(T p̂0/c) = G exp((p3/c − 1)T E3)
// with G = g0ᵀ g1: p0 = (c/T) v for a rotation vector v of the right side, every branch
// v_k = (θ + 2πk) n of its logarithm, subject to the scalar condition f_k(p3) = (c/T) v_k·e3 − p3
// = 0. Scanning p3 and bisecting sign changes of f_k lists the symmetric extremals (cost
// T(p1² + p2²)/(2c)); each is a start for the requested weights.
struct SymmetricExtremal {
  Vector3 p0;
  double cost;
};

std::vector<SymmetricExtremal> symmetricExtremals(const Matrix3& G, double T, double c,
                                                  int max_winding) {
  auto branch = [&](double p3, int k) -> Vector3 {
    const Vector3 v = so3::log(Matrix3(G * so3::exp(Vector3(0.0, 0.0, (p3 / c - 1.0) * T))));
    const double theta = v.norm();
    if (theta < 1e-300) return Vector3(0.0, 0.0, 2.0 * M_PI * k);  // identity: any axis; take e3
    return (c / T) * v * ((theta + 2.0 * M_PI * k) / theta);
  };
  auto f = [&](double p3, int k) { return branch(p3, k).z() - p3; };
  std::vector<SymmetricExtremal> out;
  for (int k = -max_winding; k <= max_winding; ++k) {
    // a root has |p3| ≤ (c/T)|v_k| ≤ (c/T)(2|k| + 1)π; M(p3) turns by 0.05 rad per grid point
    const double reach = (c / T) * M_PI * (2 * std::abs(k) + 1) * 1.01;
    const int n = static_cast<int>(std::ceil(2.0 * reach / (0.05 * c / T)));
    double a = -reach, fa = f(a, k);
    for (int i = 1; i <= n; ++i) {
      const double b = -reach + 2.0 * reach * i / n, fb = f(b, k);
      if ((fa < 0.0) != (fb < 0.0)) {
        double lo = a, hi = b, flo = fa;
        for (int it = 0; it < 80 && hi - lo > 1e-15 * (1.0 + std::abs(lo)); ++it) {
          const double mid = 0.5 * (lo + hi), fm = f(mid, k);
          if ((fm < 0.0) == (flo < 0.0)) {
            lo = mid;
            flo = fm;
          } else {
            hi = mid;
          }
        }
        const double root = 0.5 * (lo + hi);
        // a jump of the branch (θ through π) also changes sign: keep true roots only
        if (std::abs(f(root, k)) <= 1e-9 * (1.0 + reach)) {
          Vector3 p0 = branch(root, k);
          p0.z() = root;
          out.push_back({p0, 0.5 * T * (p0.x() * p0.x() + p0.y() * p0.y()) / c});
        }
      }
      a = b;
      fa = fb;
    }
  }
  std::sort(out.begin(), out.end(),
            [](const SymmetricExtremal& x, const SymmetricExtremal& y) { return x.cost < y.cost; });
  return out;
}

// How many symmetric extremals (cheapest first) become starts, and how many windings of the
// logarithm are listed (|k| ≤ 2 covers rotation vectors up to 5π).
constexpr int kMaxStarts = 8;
constexpr int kMaxWinding = 2;

// ---- Multiple shooting ----------------------------------------------------------------------
//
// Dense output not wanted: integrateTaylor's visitor that does nothing.
struct NoSamples {
  template <typename Series>
  void operator()(double, double, const Series&) const {}
};
constexpr NoSamples kNoSamples{};

// The nodes of multiple shooting and their equations: (G_j, P_j) at t_j = j τ, G_0 = g0 fixed.
class MultipleShooting {
 public:
  MultipleShooting(const DriftTwoInputRequest& rq, const Quat<double>& target_conj, int M)
      : rq_(rq), target_conj_(target_conj), M_(M), tau_(rq.duration / M), n_(6 * (M - 1) + 3) {}

  // Nodes on the single-shooting trajectory from p; false when it cannot be integrated.
  bool initialNodes(const Vector3& p, std::vector<Quat<double>>& G, std::vector<Vector3>& P) const {
    G.resize(M_);
    P.resize(M_);
    try {
      ExtremalState<double> x{p, quaternionOf(rq_.g0), 0.0};
      for (int j = 0; j < M_; ++j) {
        G[j] = x.q / x.q.norm();
        P[j] = x.p;
        x = integrateTaylor<double>(x, tau_, rq_.weights, rq_.max_step, nullptr, kNoSamples);
      }
    } catch (const StepTooLarge&) {
      return false;
    }
    G[0] = quaternionOf(rq_.g0);
    return true;
  }

  // Residuals F (and, given J, their Jacobian); false when an interval cannot be integrated.
  bool evaluate(const std::vector<Quat<double>>& Gs, const std::vector<Vector3>& Ps,
                Eigen::VectorXd& F, Eigen::MatrixXd* J) const {
    F.setZero(n_);
    if (J) J->setZero(n_, n_);
    try {
      for (int j = 0; j < M_; ++j) {
        if (J) {
          intervalWithJacobian(j, Gs, Ps, F, *J);
        } else {
          intervalValue(j, Gs, Ps, F);
        }
      }
    } catch (const StepTooLarge&) {
      return false;
    }
    return F.allFinite();
  }

  // The nodes moved by a·dx: G_j exp(a δ_j), P_j + a Δp_j.
  void retract(const std::vector<Quat<double>>& G, const std::vector<Vector3>& P,
               const Eigen::VectorXd& dx, double a, std::vector<Quat<double>>& Gs,
               std::vector<Vector3>& Ps) const {
    Gs = G;
    Ps = P;
    Ps[0] += a * dx.segment<3>(0);
    for (int j = 1; j < M_; ++j) {
      Gs[j] = so3::quaternionProduct<double>(
          G[j],
          so3::quaternionOfRotationVector<double>(Vector3(a * dx.segment<3>(3 + 6 * (j - 1)))));
      Ps[j] += a * dx.segment<3>(3 + 6 * (j - 1) + 3);
    }
  }

 private:
  using D = Dual<9>;

  void intervalValue(int j, const std::vector<Quat<double>>& Gs, const std::vector<Vector3>& Ps,
                     Eigen::VectorXd& F) const {
    const bool last = j == M_ - 1;
    const int row = 6 * j;
    const ExtremalState<double> x = integrateTaylor<double>({Ps[j], Gs[j], 0.0}, tau_, rq_.weights,
                                                            rq_.max_step, nullptr, kNoSamples);
    const Quat<double> next_conj = last ? target_conj_ : conjugate(Gs[j + 1]);
    F.segment<3>(row) = terminalResidual<double>(x.q, next_conj);
    if (!last) F.segment<3>(row + 3) = x.p - Ps[j + 1];
  }

  // Interval j with Dual<9> over (δ_j, p_j, δ_{j+1}): its rows of F and J.
  void intervalWithJacobian(int j, const std::vector<Quat<double>>& Gs,
                            const std::vector<Vector3>& Ps, Eigen::VectorXd& F,
                            Eigen::MatrixXd& J) const {
    const bool last = j == M_ - 1;
    const int row = 6 * j;
    const int col_p = j == 0 ? 0 : 3 + 6 * (j - 1) + 3, col_d = 3 + 6 * (j - 1);
    const int col_dn = 3 + 6 * j;  // δ_{j+1}
    so3::Vec3<D> d0, q, dn;
    for (int i = 0; i < 3; ++i) {
      d0(i) = D(0.0, i);
      q(i) = D(Ps[j](i), 3 + i);
      dn(i) = D(0.0, 6 + i);
    }
    const Quat<D> start =
        so3::quaternionProduct<D>(Gs[j].cast<D>(), so3::quaternionOfRotationVector<D>(d0));
    const ExtremalState<D> x = integrateTaylor<D>({q, start, D(0.0)}, tau_, rq_.weights,
                                                  rq_.max_step, nullptr, kNoSamples);
    Quat<D> next_conj;
    if (last) {
      next_conj = target_conj_.cast<D>();
    } else {
      const Quat<D> nx =
          so3::quaternionProduct<D>(Gs[j + 1].cast<D>(), so3::quaternionOfRotationVector<D>(dn));
      next_conj = Quat<D>(nx(0), -nx(1), -nx(2), -nx(3));
    }
    const so3::Vec3<D> rg =
        so3::logOfQuaternion<D>(so3::quaternionProduct<D>(next_conj, Quat<D>(x.q / x.q.norm())));
    for (int i = 0; i < 3; ++i) {
      F(row + i) = rg(i).v;
      if (j > 0) J.block<1, 3>(row + i, col_d) = rg(i).d.segment<3>(0).transpose();
      J.block<1, 3>(row + i, col_p) = rg(i).d.segment<3>(3).transpose();
      if (!last) J.block<1, 3>(row + i, col_dn) = rg(i).d.segment<3>(6).transpose();
      if (last) continue;
      F(row + 3 + i) = x.p(i).v - Ps[j + 1](i);
      if (j > 0) J.block<1, 3>(row + 3 + i, col_d) = x.p(i).d.segment<3>(0).transpose();
      J.block<1, 3>(row + 3 + i, col_p) = x.p(i).d.segment<3>(3).transpose();
      J(row + 3 + i, col_dn + 3 + i) = -1.0;  // ∂(p_end − p_{j+1})/∂p_{j+1}
    }
  }

  const DriftTwoInputRequest& rq_;
  const Quat<double> target_conj_;
  const int M_;
  const double tau_;
  const int n_;
};

// For long horizons, where the sensitivity of g(T) to p(0) grows: [0, T] is split into M equal
// intervals; unknowns are p(0) and, at the inner nodes, (g_j, p_j) with g_j updated on the group
// (ĝ_j exp(δ_j)). Equations: continuity of g and p at each inner node and log(targetᵀ g_end) = 0
// at T, 6(M−1) + 3 in all; Newton with exact block Jacobians (Dual<9> over δ_j, p_j, δ_{j+1})
// and backtracking on the residual norm. Returns true when the residual norm ≤ tol.
bool multipleShootingSolve(const DriftTwoInputRequest& rq, const Quat<double>& target_conj, int M,
                           double tol, int max_iterations, Vector3& p, int& iterations,
                           double& error) {
  const MultipleShooting shooting(rq, target_conj, M);
  std::vector<Quat<double>> G;
  std::vector<Vector3> P;
  Eigen::VectorXd F;
  Eigen::MatrixXd J;
  if (!shooting.initialNodes(p, G, P) || !shooting.evaluate(G, P, F, &J)) {
    error = INFINITY;
    return false;
  }
  error = F.norm();
  while (error > tol && max_iterations-- > 0) {
    ++iterations;
    Eigen::FullPivLU<Eigen::MatrixXd> lu(J);
    if (!lu.isInvertible()) break;
    const Eigen::VectorXd dx = -lu.solve(F);
    double a = 1.0;
    bool accepted = false;
    for (int ls = 0; ls < 30; ++ls, a *= 0.5) {
      std::vector<Quat<double>> Gs;
      std::vector<Vector3> Ps;
      shooting.retract(G, P, dx, a, Gs, Ps);
      Eigen::VectorXd Ft;
      if (!shooting.evaluate(Gs, Ps, Ft, nullptr)) continue;
      if (Ft.norm() <= (1.0 - 1e-4 * a) * error || (Ft.norm() <= 1e-13 && Ft.norm() <= error)) {
        G = Gs;
        P = Ps;
        error = Ft.norm();
        accepted = true;
        break;
      }
    }
    if (!accepted || error <= tol) break;
    if (!shooting.evaluate(G, P, F, &J)) break;
  }
  p = P[0];
  return error <= tol;
}

std::string vec(const Vector3& v) {
  std::ostringstream os;
  os.precision(10);
  os << "(" << v.x() << ", " << v.y() << ", " << v.z() << ")";
  return os.str();
}

// One start carried to a solution of the requested problem.
struct Attempt {
  Solve solve;
  int stages = 1;
  std::string how;
};

// From a guess: LM at the requested weights; if that fails, continuation on the target along
// the geodesic g(λ) = g_a exp(λ log(g_aᵀ g1)) from the endpoint g_a the guess reaches (adaptive
// increments, intermediate targets to 1e-8 rad).
Attempt solveFromGuess(Shooter& sh, const DriftTwoInputRequest& rq, const Vector3& guess,
                       double p_scale, const Deadline& deadline) {
  const Quat<double> g1_conj = conjugate(quaternionOf(rq.g1));
  Attempt a;
  a.how = "direct solve from the guess";
  a.solve = levenbergMarquardt(sh, g1_conj, rq.weights, guess, rq.tolerance, rq.max_iterations,
                               p_scale, deadline);
  if (a.solve.ok || deadline.expired()) return a;
  Vector3 r0;
  if (!sh.value(guess, g1_conj, rq.weights, &r0, nullptr)) return a;
  const Matrix3 g_a = rq.g1 * so3::exp(r0);
  const Vector3 path = so3::log(Matrix3(g_a.transpose() * rq.g1));
  double lambda = 0.0, dl = 0.25;
  int stages = 0, iterations = a.solve.iterations;
  Vector3 p = guess;
  Solve last;
  while (lambda < 1.0 && stages < rq.max_continuation_stages && iterations < rq.max_iterations &&
         dl > 1e-6 && !deadline.expired()) {
    const double next = std::min(1.0, lambda + dl);
    const Quat<double> target = conjugate(quaternionOf(g_a * so3::exp(Vector3(next * path))));
    ++stages;
    const Solve s =
        levenbergMarquardt(sh, target, rq.weights, p, next == 1.0 ? rq.tolerance : 1e-8,
                           std::min(20, rq.max_iterations - iterations), p_scale, deadline);
    iterations += s.iterations;
    if (s.ok) {
      p = s.p;
      lambda = next;
      dl *= 2;
      last = s;
    } else {
      dl *= 0.5;
    }
  }
  a.stages = 1 + stages;
  a.how = "direct solve from the guess failed; continuation on the target over " +
          std::to_string(stages) + " targets";
  if (lambda == 1.0) a.solve = last;
  a.solve.iterations = iterations;
  return a;
}

// Smallest increment of the weight continuation: a branch that needs finer steps has (nearly)
// a fold there; other starts are cheaper to try than resolving it.
constexpr double kMinWeightIncrement = 1.0 / 32.0;

// From an extremal of the symmetric problem (weights (c̄, c̄)): LM at the requested weights
// directly; if that fails, continuation in the weights c(λ) = (1−λ)(c̄, c̄) + λ(c1, c2), each
// stage starting from the previous extremal with the same controls u_i = p_i/c_i.
Attempt solveFromSymmetric(Shooter& sh, const DriftTwoInputRequest& rq, const Vector3& p_sym,
                           double c_bar, double p_scale, const Deadline& deadline) {
  const Quat<double> g1_conj = conjugate(quaternionOf(rq.g1));
  const DriftTwoInputWeights& w = rq.weights;
  auto sameControls = [](const Vector3& p, const DriftTwoInputWeights& from,
                         const DriftTwoInputWeights& to) {
    return Vector3(p.x() * to.c1 / from.c1, p.y() * to.c2 / from.c2, p.z());
  };
  const DriftTwoInputWeights sym{c_bar, c_bar};
  Attempt a;
  a.how = "direct";
  a.solve = levenbergMarquardt(sh, g1_conj, w, sameControls(p_sym, sym, w), rq.tolerance,
                               std::min(30, rq.max_iterations), p_scale, deadline);
  if (a.solve.ok || deadline.expired() || (w.c1 == c_bar && w.c2 == c_bar)) return a;
  double lambda = 0.0, dl = 0.5;
  Vector3 p = p_sym;
  DriftTwoInputWeights at = sym;
  int stages = 0, iterations = a.solve.iterations;
  Solve last;
  while (lambda < 1.0 && stages < rq.max_continuation_stages && iterations < rq.max_iterations &&
         dl > kMinWeightIncrement && !deadline.expired()) {
    const double next = std::min(1.0, lambda + dl);
    const DriftTwoInputWeights wn{(1 - next) * c_bar + next * w.c1,
                                  (1 - next) * c_bar + next * w.c2};
    ++stages;
    const Solve s = levenbergMarquardt(
        sh, g1_conj, wn, sameControls(p, at, wn), next == 1.0 ? rq.tolerance : 1e-8,
        std::min(next == 1.0 ? 30 : 12, rq.max_iterations - iterations), p_scale, deadline);
    iterations += s.iterations;
    if (next == 1.0 && !s.ok && s.error <= 100 * rq.tolerance) {  // at g1: a round-off floor
      last = s;
      lambda = 1.0;
      break;
    }
    if (s.ok) {
      p = s.p;
      at = wn;
      lambda = next;
      dl = std::min(2 * dl, 1.0 - lambda);
      last = s;
    } else {
      dl *= 0.5;
    }
  }
  a.stages = 1 + stages;
  a.how = "continuation in the weights over " + std::to_string(stages) + " stages";
  if (lambda == 1.0) a.solve = last;
  a.solve.iterations = iterations;
  return a;
}

// For p3 ∈ {0, ±c̄, c̄/2, 2c̄}: (p1, p2) from the least-squares solution of the shooting
// equation linearized at (0, 0, p3), r + ∂r/∂(p1, p2) (p1, p2) = 0.
std::vector<Vector3> linearizedStarts(Shooter& sh, const DriftTwoInputRequest& rq, double c) {
  const Quat<double> g1_conj = conjugate(quaternionOf(rq.g1));
  std::vector<Vector3> starts;
  for (double p3 : {0.0, c, -c, 0.5 * c, 2.0 * c}) {
    Vector3 r;
    Matrix3 J;
    if (!sh.jacobian(Vector3(0, 0, p3), g1_conj, rq.weights, &r, &J, nullptr)) continue;
    const Eigen::Matrix<double, 3, 2> B = J.leftCols<2>();
    Eigen::Vector2d q = B.completeOrthogonalDecomposition().solve(-r);
    // g1 reached from (0, 0, p3) up to a rotation about e3 (which (p1, p2) cannot change to
    // first order): start off the singular axis instead
    if (!(q.norm() > 1e-3 * c) && r.norm() > rq.tolerance) q = Eigen::Vector2d(0.1, 0.1) * c;
    starts.emplace_back(q.x(), q.y(), p3);
  }
  return starts;
}

std::string costList(const std::vector<double>& costs) {
  std::ostringstream os;
  os.precision(6);
  for (size_t i = 0; i < costs.size(); ++i) os << (i ? ", " : "") << costs[i];
  return os.str();
}

}  // namespace

void driftTwoInputShootingResidual(const Matrix3& g0, const Matrix3& g1, double T,
                                   const DriftTwoInputWeights& w, const Vector3& p0,
                                   Vector3* residual, Matrix3* jacobian, double max_step) {
  Shooter sh(g0, T, max_step);
  const Quat<double> g1_conj = conjugate(quaternionOf(g1));
  const bool ok = jacobian ? sh.jacobian(p0, g1_conj, w, residual, jacobian, nullptr)
                           : sh.value(p0, g1_conj, w, residual, nullptr);
  if (!ok) throw StepTooLarge("shooting: costate " + vec(p0) + " too large to integrate");
}

DriftTwoInputTrajectory sampleDriftTwoInputExtremal(const Matrix3& g0, const Vector3& p0, double T,
                                                    int steps, const DriftTwoInputWeights& w,
                                                    double max_step, int* integration_steps) {
  validateDriftTwoInputExtremalInputs(w, T, steps, p0);
  DriftTwoInputTrajectory out;
  out.t.resize(steps + 1);
  out.p.resize(steps + 1);
  out.g.resize(steps + 1);
  out.u.resize(steps + 1);
  auto record = [&](int k, const ExtremalState<double>& x) {
    out.t[k] = k == steps ? T : T * k / steps;
    out.p[k] = x.p;
    out.g[k] = so3::matrixFromQuaternion<double>(x.q);
    out.u[k] = Eigen::Vector2d(x.p.x() / w.c1, x.p.y() / w.c2);
  };
  const ExtremalState<double> x0{p0, quaternionOf(g0), 0.0};
  record(0, x0);
  int next = 1;  // next sample to fill: dense output of the step that contains t_next
  const ExtremalState<double> xT = integrateTaylor<double>(
      x0, T, w, max_step, integration_steps, [&](double t, double h, const auto& series) {
        const bool last = t + h >= T;
        while (next <= steps) {
          const double tk = T * next / steps;
          if (!last && tk > t + h) break;
          record(next, next == steps ? series.at(h) : series.at(std::min(tk - t, h)));
          ++next;
        }
      });
  out.g[0] = g0;  // exactly the given g0 (not its round trip through a quaternion)
  out.cost = xT.cost;
  return out;
}

namespace {

// Multiple shooting finds p(0) from the guess (default: the cheapest symmetric extremal); a few
// single-shooting steps then polish it against the one-piece integration.
Attempt multipleShootingAttempt(Shooter& sh, const DriftTwoInputRequest& rq, double c_bar,
                                double p_scale, const Deadline& deadline) {
  Vector3 start = Vector3::Zero();
  if (rq.initial_costate) {
    start = *rq.initial_costate;
  } else {
    const auto sym =
        symmetricExtremals(Matrix3(rq.g0.transpose() * rq.g1), rq.duration, c_bar, kMaxWinding);
    if (!sym.empty()) start = sym.front().p0;
  }
  Attempt a;
  a.solve.p = start;
  const Quat<double> g1_conj = conjugate(quaternionOf(rq.g1));
  const bool ms_ok =
      multipleShootingSolve(rq, g1_conj, rq.shooting_intervals, rq.tolerance, rq.max_iterations,
                            a.solve.p, a.solve.iterations, a.solve.error);
  if (ms_ok || a.solve.error <= 1e-6) {
    const int ms_iterations = a.solve.iterations;
    a.solve =
        levenbergMarquardt(sh, g1_conj, rq.weights, a.solve.p, rq.tolerance, 5, p_scale, deadline);
    a.solve.iterations += ms_iterations;
  }
  a.how = "multiple shooting on " + std::to_string(rq.shooting_intervals) + " intervals";
  return a;
}

// Starts from the extremals of the symmetric problem (and, where those form circles, from the
// linearized shooting equation), each carried to the requested weights; appends them to
// *attempts and returns the description of where they came from.
std::string symmetricAttempts(Shooter& sh, const DriftTwoInputRequest& rq, double c_bar,
                              double p_scale, const Deadline& deadline,
                              std::vector<Attempt>* attempts) {
  const auto sym =
      symmetricExtremals(Matrix3(rq.g0.transpose() * rq.g1), rq.duration, c_bar, kMaxWinding);
  const int n = std::min<int>(kMaxStarts, static_cast<int>(sym.size()));
  // Same controls, other weights: the cost changes by a factor in [min c/c̄, max c/c̄]. A
  // symmetric extremal whose cost times min c/c̄ exceeds the best cost found is therefore not
  // pursued (a heuristic bound: it assumes the extremal's controls change little on the way
  // to the requested weights). For c1 = c2 the symmetric extremals are the extremals: only
  // the cheapest is polished.
  const double ratio = c_bar / std::min(rq.weights.c1, rq.weights.c2);
  double best_cost = INFINITY;
  int skipped = 0;
  for (int i = 0; i < n && !deadline.expired(); ++i) {
    if (best_cost < INFINITY && sym[i].cost >= best_cost * ratio) {
      ++skipped;
      continue;
    }
    attempts->push_back(solveFromSymmetric(sh, rq, sym[i].p0, c_bar, p_scale, deadline));
    if (attempts->back().solve.ok) best_cost = std::min(best_cost, attempts->back().solve.cost);
  }
  if (n < 2) {
    // g0ᵀg1 (nearly) a rotation about e3: the symmetric extremals form circles (rotating p0
    // about e3 is then a symmetry) that the scan above does not list. Starts from the
    // shooting equation linearized at (0, 0, p3) instead (there the Jacobian is singular:
    // p3 only sets the rotation rate of a zero (p1, p2)).
    for (const Vector3& start : linearizedStarts(sh, rq, c_bar)) {
      if (deadline.expired()) break;
      attempts->push_back(solveFromGuess(sh, rq, start, p_scale, deadline));
    }
  }
  std::ostringstream os;
  os << attempts->size() << " start" << (attempts->size() == 1 ? "" : "s")
     << " (extremals of the symmetric problem c1 = c2 = " << c_bar << ": " << sym.size()
     << " listed, the " << n << " cheapest considered, " << skipped
     << " of them not pursued by the cost bound";
  if (n < 2) os << "; starts from the linearized shooting equation";
  os << ")";
  return os.str();
}

// The least-cost converged attempt (or, when none converged, the one closest to g1) and the
// distinct extremals (p(0) apart) among the converged ones.
struct Selection {
  const Attempt* best = nullptr;
  std::vector<const Attempt*> distinct;
};

// Also counts the plan's iterations and starts and lists the other extremals' costs.
Selection selectAttempt(const std::vector<Attempt>& attempts, DriftTwoInputPlan* plan) {
  Selection sel;
  for (const Attempt& a : attempts) {
    plan->iterations += a.solve.iterations;
    ++plan->starts;
    if (!a.solve.ok) continue;
    ++plan->converged_starts;
    bool seen = false;
    for (const Attempt* d : sel.distinct) {
      seen = seen || (d->solve.p - a.solve.p).norm() <= 1e-6 * (1.0 + a.solve.p.norm());
    }
    if (!seen) sel.distinct.push_back(&a);
    if (!sel.best || a.solve.cost < sel.best->solve.cost) sel.best = &a;
  }
  if (!sel.best) {  // nothing converged: the attempt closest to g1
    for (const Attempt& a : attempts) {
      if (!sel.best || a.solve.error < sel.best->solve.error) sel.best = &a;
    }
  }
  for (const Attempt* d : sel.distinct) {
    if (d != sel.best) plan->other_costs.push_back(d->solve.cost);
  }
  std::sort(plan->other_costs.begin(), plan->other_costs.end());
  return sel;
}

std::string extremalText(const Selection& sel, const DriftTwoInputPlan& plan,
                         const std::string& start_kind) {
  std::ostringstream os;
  os.precision(6);
  if (sel.best && sel.best->solve.ok) {
    os << "least cost of " << sel.distinct.size() << " distinct extremal"
       << (sel.distinct.size() == 1 ? "" : "s") << " found from " << start_kind;
    if (!plan.other_costs.empty()) os << "; the others cost " << costList(plan.other_costs);
  } else {
    os << "none found from " << start_kind;
  }
  return os.str();
}

std::string planMessage(const DriftTwoInputRequest& rq, const DriftTwoInputPlan& plan,
                        const Attempt* best, bool converged, bool timed_out) {
  const Vector3& p = plan.initial_costate;
  std::ostringstream os;
  os.precision(6);
  std::ostringstream budget;
  budget.precision(6);
  if (timed_out) {
    budget << "; time budget of " << rq.time_budget_s << " s reached: search stopped after "
           << plan.starts << " start(s)";
  }
  if (converged) {
    os << "converged (" << best->how << ", " << plan.iterations << " iterations, "
       << plan.converged_starts << " of " << plan.starts << " starts converged" << budget.str()
       << "): extremal with p(0) = " << vec(p) << ", cost " << plan.cost << ", terminal error "
       << plan.terminal_error << " rad; " << plan.extremal;
  } else {
    os << (timed_out ? "timed out" : "not converged") << " after " << plan.iterations
       << " iterations (" << (best ? best->how : std::string("no start")) << budget.str()
       << "): best p(0) = " << vec(p) << ", terminal error " << plan.terminal_error
       << " rad; try an initial_costate, multiple shooting or a shorter duration";
  }
  return os.str();
}

}  // namespace

DriftTwoInputPlan planDriftTwoInput(const DriftTwoInputRequest& rq) {
  validate(rq);
  const Deadline deadline(rq.time_budget_s);
  DriftTwoInputPlan plan;
  Shooter sh(rq.g0, rq.duration, rq.max_step);
  const double c_bar = 0.5 * (rq.weights.c1 + rq.weights.c2);
  // Costate scale of a maneuver that turns by about π in T: (c/T)·π; bounds LM steps below.
  const double p_scale = c_bar * M_PI / rq.duration;

  std::vector<Attempt> attempts;
  std::string start_kind;
  if (rq.shooting_intervals > 1) {
    attempts.push_back(multipleShootingAttempt(sh, rq, c_bar, p_scale, deadline));
    start_kind = rq.initial_costate ? "the guess" : "the cheapest symmetric extremal";
  } else if (rq.initial_costate) {
    attempts.push_back(solveFromGuess(sh, rq, *rq.initial_costate, p_scale, deadline));
    start_kind = "the guess";
  } else {
    start_kind = symmetricAttempts(sh, rq, c_bar, p_scale, deadline, &attempts);
  }
  const bool timed_out = deadline.expired();

  const Selection sel = selectAttempt(attempts, &plan);
  const Attempt* best = sel.best;
  const Vector3 p = best ? best->solve.p : Vector3::Zero();
  plan.initial_costate = p;
  plan.continuation_stages = best ? best->stages : 0;
  plan.extremal = extremalText(sel, plan, start_kind);
  try {
    plan.trajectory = sampleDriftTwoInputExtremal(rq.g0, p, rq.duration, rq.steps, rq.weights,
                                                  rq.max_step, &plan.integration_steps);
    plan.cost = plan.trajectory.cost;
    plan.terminal_error = so3::angleBetween(rq.g1, plan.trajectory.g.back());
  } catch (const StepTooLarge& e) {
    plan.termination = Termination::StepTooLarge;
    plan.terminal_error = INFINITY;
    plan.message = std::string("extremal could not be integrated: ") + e.what();
    return plan;
  }
  const bool converged = best && best->solve.ok && plan.terminal_error <= rq.tolerance;
  plan.termination = converged   ? Termination::Converged
                     : timed_out ? Termination::TimedOut
                                 : Termination::NotConverged;
  plan.message = planMessage(rq, plan, best, converged, timed_out);
  return plan;
}

}  // namespace attitude_planner
