// benchmark_solvers: one solve of the seed's discrete problem (seed 000, Problem 3.2) by one
// solver, timed, with its peak memory; scripts/benchmark runs it once per process and repetition
// and writes docs/results/performance.md.
//
// Solvers (all on the same discrete problem; every result is replayed through evaluatePlan so the
// reported cost and terminal miss are measured the same way for all of them):
//   newton        ours: Newton on the reduced problem (planManeuver, either scheme)
//   slsqp         NLopt LD_SLSQP on the direct method, exact gradients (solveWithNlopt)
//   auglag        NLopt AUGLAG_EQ with an LD_LBFGS subsolver on the same direct method
//   ipopt         IPOPT on a simultaneous transcription (quaternions q_1..q_N, Ω_1..Ω_{N−2},
//                 τ_1..τ_{N−1}; kinematics, dynamics and terminal constraints), exact sparse
//                 Jacobian and exact sparse Hessian of the Lagrangian (only if built with IPOPT);
//                 with the scene's node constraints too (per-axis torque limits as variable bounds,
//                 max_torque_norm, max_angular_rate, keep_out, keep_in and reaction-wheel
//                 limits as exact constraint rows; the wheel rows' derivation is its own)
//   ipopt_lbfgs   the same, with IPOPT's limited-memory (L-BFGS) Hessian instead (for comparison)
//   free_time     minimum time, ours: ONE free-time interior-point solve (free_time_solver.hpp)
//                 from ipopt_free_time's start, the scheme paper (its own JSON line too)
//   ipopt_free_time  minimum time: the same transcription with h an unknown, objective N h, from
//                 the eigenaxis slew with an excursion (L-BFGS Hessian; one JSON line of its own:
//                 time_s, minimum_duration, status; docs/results/minimum_time.md's peer row)
//   minimum_time_search  minimum time by the former search on T over minimum-effort solves
//                 (drivers/minimum_time_search.hpp) on the scene's request as it is (any scheme,
//                 constraints, effects): the upper bound the free-time answer is checked against
//                 (one JSON line: time_s, minimum_duration, status, max_constraint_violation)
//   complex_step  the seed's own approach: Newton on the necessary conditions (corrected eq. (28),
//                 dynamics, terminal attitude) in 3(2N−3) unknowns τ, Ω with a dense
//                 complex-step Jacobian and a dense LU per iteration (as the seed did with fsolve)
// Output: one JSON object per line on stdout.
// --check-hessian compares IPOPT's exact Hessian (eval_h) with central differences of the
// Lagrangian's gradient (eval_grad_f + eval_jac_gᵀλ) at a random point; exit 0 iff they agree
// (--constrained: with one constraint of every kind, so their rows and Hessian terms too).
#include <sys/resource.h>

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <complex>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <fstream>
#include <functional>
#include <iomanip>
#include <iostream>
#include <nlopt.hpp>
#include <optional>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "attitude_planner/errors.hpp"
#include "attitude_planner/io/scene.hpp"
#include "attitude_planner/planner.hpp"
#include "attitude_planner/planning/minimum_time.hpp"
#include "lie/dual.hpp"
#include "planning/drivers/free_time_recipe.hpp"
#include "planning/drivers/minimum_time_search.hpp"
#include "planning/newton/newton_solver.hpp"
#include "planning/problem/verdict.hpp"
#include "planning/transcription/direct_method.hpp"
#include "planning/transcription/reduced_problem.hpp"
#include "planning/transcription/stage_constraints.hpp"
#include "support/random_problems.hpp"
#include "support/study_tools.hpp"

#ifdef AP_HAVE_IPOPT
#include <coin/IpIpoptApplication.hpp>
#include <coin/IpTNLP.hpp>
#endif

#ifdef AP_HAVE_IPOPT
// ---- second-order forward mode for IPOPT's exact Hessian -----------------------------------
namespace benchmark_ad {

/// Hyper-dual number for N variables: value, gradient and (full, symmetric) Hessian, propagated
/// exactly through +, −, ×, ÷, sqrt, sin, cos. Usable as an Eigen scalar, so the templated
/// ap::so3 formulas (quaternionOfRotationVector, exp) give exact second derivatives. Branches
/// compare values only, as ap::Dual does. Benchmark code only (ap::Dual does not nest).
template <int N>
struct HyperDual {
  double v = 0.0;
  double g[N] = {};
  double H[N][N] = {};

  HyperDual() = default;
  HyperDual(double value) : v(value) {}  // NOLINT: implicit from constants, as Eigen expects
  HyperDual(double value, int direction) : v(value) { g[direction] = 1.0; }

  HyperDual& operator+=(const HyperDual& o) {
    v += o.v;
    for (int i = 0; i < N; ++i) g[i] += o.g[i];
    for (int i = 0; i < N; ++i)
      for (int j = 0; j < N; ++j) H[i][j] += o.H[i][j];
    return *this;
  }
  HyperDual& operator-=(const HyperDual& o) {
    v -= o.v;
    for (int i = 0; i < N; ++i) g[i] -= o.g[i];
    for (int i = 0; i < N; ++i)
      for (int j = 0; j < N; ++j) H[i][j] -= o.H[i][j];
    return *this;
  }
  /// (ab)'' = a b'' + b a'' + a' b'ᵀ + b' a'ᵀ
  HyperDual& operator*=(const HyperDual& o) {
    for (int i = 0; i < N; ++i)
      for (int j = 0; j < N; ++j)
        H[i][j] = v * o.H[i][j] + o.v * H[i][j] + g[i] * o.g[j] + o.g[i] * g[j];
    for (int i = 0; i < N; ++i) g[i] = g[i] * o.v + o.g[i] * v;
    v *= o.v;
    return *this;
  }
  HyperDual& operator/=(const HyperDual& o) { return *this *= reciprocal(o); }
  HyperDual& scale(double s) {
    v *= s;
    for (int i = 0; i < N; ++i) g[i] *= s;
    for (int i = 0; i < N; ++i)
      for (int j = 0; j < N; ++j) H[i][j] *= s;
    return *this;
  }
  HyperDual operator-() const { return HyperDual(*this).scale(-1.0); }
  HyperDual operator+() const { return *this; }

  /// f(a) given f, f′, f″ at a.v: f(a)′ = f′ a′, f(a)″ = f′ a″ + f″ a′ a′ᵀ.
  static HyperDual chain(const HyperDual& a, double f, double df, double d2f) {
    HyperDual r;
    r.v = f;
    for (int i = 0; i < N; ++i) r.g[i] = df * a.g[i];
    for (int i = 0; i < N; ++i)
      for (int j = 0; j < N; ++j) r.H[i][j] = df * a.H[i][j] + d2f * a.g[i] * a.g[j];
    return r;
  }
  static HyperDual reciprocal(const HyperDual& a) {
    const double inv = 1.0 / a.v;
    return chain(a, inv, -inv * inv, 2.0 * inv * inv * inv);
  }
};

template <int N>
HyperDual<N> operator+(HyperDual<N> a, const HyperDual<N>& b) {
  return a += b;
}
template <int N>
HyperDual<N> operator-(HyperDual<N> a, const HyperDual<N>& b) {
  return a -= b;
}
template <int N>
HyperDual<N> operator*(HyperDual<N> a, const HyperDual<N>& b) {
  return a *= b;
}
template <int N>
HyperDual<N> operator/(HyperDual<N> a, const HyperDual<N>& b) {
  return a /= b;
}
template <int N>
HyperDual<N> operator+(HyperDual<N> a, double b) {
  a.v += b;
  return a;
}
template <int N>
HyperDual<N> operator+(double b, HyperDual<N> a) {
  a.v += b;
  return a;
}
template <int N>
HyperDual<N> operator-(HyperDual<N> a, double b) {
  a.v -= b;
  return a;
}
template <int N>
HyperDual<N> operator-(double b, const HyperDual<N>& a) {
  HyperDual<N> r = -a;
  r.v += b;
  return r;
}
template <int N>
HyperDual<N> operator*(HyperDual<N> a, double b) {
  return a.scale(b);
}
template <int N>
HyperDual<N> operator*(double b, HyperDual<N> a) {
  return a.scale(b);
}
template <int N>
HyperDual<N> operator/(HyperDual<N> a, double b) {
  return a.scale(1.0 / b);
}
template <int N>
HyperDual<N> operator/(double b, const HyperDual<N>& a) {
  return HyperDual<N>::reciprocal(a).scale(b);
}
template <int N>
bool operator<(const HyperDual<N>& a, const HyperDual<N>& b) {
  return a.v < b.v;
}
template <int N>
bool operator>(const HyperDual<N>& a, const HyperDual<N>& b) {
  return a.v > b.v;
}
template <int N>
bool operator<=(const HyperDual<N>& a, const HyperDual<N>& b) {
  return a.v <= b.v;
}
template <int N>
bool operator>=(const HyperDual<N>& a, const HyperDual<N>& b) {
  return a.v >= b.v;
}
template <int N>
bool operator==(const HyperDual<N>& a, const HyperDual<N>& b) {
  return a.v == b.v;
}
template <int N>
bool operator!=(const HyperDual<N>& a, const HyperDual<N>& b) {
  return a.v != b.v;
}
template <int N>
HyperDual<N> sqrt(const HyperDual<N>& a) {
  const double s = std::sqrt(a.v);
  return HyperDual<N>::chain(a, s, 0.5 / s, -0.25 / (s * a.v));
}
template <int N>
HyperDual<N> sin(const HyperDual<N>& a) {
  const double s = std::sin(a.v);
  return HyperDual<N>::chain(a, s, std::cos(a.v), -s);
}
template <int N>
HyperDual<N> cos(const HyperDual<N>& a) {
  const double c = std::cos(a.v);
  return HyperDual<N>::chain(a, c, -std::sin(a.v), -c);
}
template <int N>
HyperDual<N> abs(const HyperDual<N>& a) {
  return a.v < 0 ? -a : a;
}

}  // namespace benchmark_ad

namespace Eigen {
template <int N>
struct NumTraits<benchmark_ad::HyperDual<N>> : NumTraits<double> {
  using Real = benchmark_ad::HyperDual<N>;
  using NonInteger = benchmark_ad::HyperDual<N>;
  using Nested = benchmark_ad::HyperDual<N>;
  using Literal = benchmark_ad::HyperDual<N>;
  enum {
    IsComplex = 0,
    IsInteger = 0,
    IsSigned = 1,
    RequireInitialization = 1,
    ReadCost = 1,
    AddCost = 1 + N + N * N,
    MulCost = 1 + 3 * N + 4 * N * N
  };
};
template <int N, typename BinaryOp>
struct ScalarBinaryOpTraits<benchmark_ad::HyperDual<N>, double, BinaryOp> {
  using ReturnType = benchmark_ad::HyperDual<N>;
};
template <int N, typename BinaryOp>
struct ScalarBinaryOpTraits<double, benchmark_ad::HyperDual<N>, BinaryOp> {
  using ReturnType = benchmark_ad::HyperDual<N>;
};
}  // namespace Eigen
#endif

namespace ap = attitude_planner;
using ap::Matrix3;
using ap::Vector3;

namespace {

using attitude_planner::study::median;

const char* const kUsage =
    "usage: benchmark_solvers --solver newton|slsqp|auglag|ipopt|ipopt_lbfgs|complex_step|\n"
    "                                  free_time|ipopt_free_time|minimum_time_search (minimum\n"
    "                                  time, own JSON line)\n"
    "                         [--scene SCENE.yaml] [--steps N] [--scheme paper|variational]\n"
    "                         [--time-budget S] [--in-process K]\n"
    "                         [--start geodesic|unconstrained|ours]  the peers' start (ipopt):\n"
    "                         the geodesic (default), our unconstrained optimum, as ours starts a\n"
    "                         constrained solve, or our constrained optimum (does the peer stay\n"
    "                         there?); computed before the peer's clock starts\n"
    "       benchmark_solvers --quick   every solver on the seed's rest-to-rest example, N = 16\n"
    "       benchmark_solvers --random-suite COUNT [--seed S] [--out FILE.md] [--time-budget S]\n"
    "                         [--cases I,J,...]  (only these case indices, e.g. to re-plan one)\n"
    "                         ours and IPOPT (exact Hessian, paper scheme, same start) on the\n"
    "                         seeded random problems of test/support/random_problems.hpp\n"
    "       benchmark_solvers --check-hessian [--steps N] [--constrained] [--wheels]\n"
    "                         [--free-time]   IPOPT's exact Hessian (--wheels: with a biased\n"
    "                         pyramid's wheel rows; --free-time: the Jacobian of\n"
    "                         ipopt_free_time's NLP with its h column, which has no exact "
    "Hessian)\n"
    "                         against central differences of its exact gradients, its Jacobian\n"
    "                         against differences of its constraints (exit 0 iff relative errors\n"
    "                         <= 1e-6; --constrained: with one node constraint of every kind;\n"
    "                         exit 3 if this build has no IPOPT)\n"
    "Prints one JSON line: solver, scheme, steps, time_s, iterations, cost, converged,\n"
    "terminal_miss, peak_rss_kb, message. Without --scene: the seed's rest-to-rest example.\n";

/// What a peer returns: the torques τ_0..τ_N and its own account.
struct PeerOutcome {
  std::vector<Vector3> torque;
  int iterations = 0;
  bool ok = false;
  bool optimal = false;  ///< the peer's own strict verdict (IPOPT: Solve_Succeeded)
  std::string message;
};

/// The seed's rest-to-rest example (scenes/rest_to_rest.yaml): π/3 about x in 12.8 s.
ap::PlanningProblem seedRestToRest(int steps) {
  ap::PlanningProblem p;
  p.inertia << 13.25, -7.80, -11.40, -7.80, 16.25, 4.71, -11.40, 4.71, 18.37;
  p.duration = 12.8;
  p.steps = steps;
  p.final_attitude = ap::so3::exp(Vector3(M_PI / 3.0, 0.0, 0.0));
  p.allow_nonphysical_inertia = true;
  return p;
}

/// Peak resident set size of this process [kB] (VmHWM).
long peakRssKb() {
  std::ifstream in("/proc/self/status");
  std::string line;
  while (std::getline(in, line)) {
    if (line.rfind("VmHWM:", 0) == 0) return std::atol(line.c_str() + 6);
  }
  struct rusage usage;
  getrusage(RUSAGE_SELF, &usage);
  return usage.ru_maxrss;
}

/// The geodesic start every peer shares with ours: steps ω_k of ReducedProblem's initial guess.
std::vector<Vector3> geodesicSteps(const ap::PlanningProblem& problem) {
  return ap::ReducedProblem(problem).current();
}

std::vector<Vector3> geodesicTorques(const ap::PlanningProblem& problem) {
  const ap::ReducedProblem reduced(problem);
  return reduced.torques(reduced.current());
}

// ---- NLopt AUGLAG + LBFGS on the direct method ---------------------------------------------

struct AuglagData {
  const ap::PlanningProblem* problem = nullptr;
  int evaluations = 0;
};

double auglagObjective(unsigned n, const double* x, double* grad, void* data) {
  ++static_cast<AuglagData*>(data)->evaluations;
  double f = 0.0;
  for (unsigned i = 0; i < n; ++i) {
    f += 0.5 * x[i] * x[i];
    if (grad) grad[i] = x[i];
  }
  return f;
}

void auglagConstraints(unsigned m, double* result, unsigned n, const double* x_raw, double* grad,
                       void* data) {
  auto* d = static_cast<AuglagData*>(data);
  const Eigen::Map<const Eigen::VectorXd> x(x_raw, n);
  try {
    const ap::TerminalConstraints c = ap::evaluateTerminalConstraints(*d->problem, x, grad);
    for (unsigned i = 0; i < m; ++i) result[i] = c.value(i);
    if (grad) {
      Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(
          grad, m, n) = c.jacobian;
    }
  } catch (const ap::StepTooLarge&) {
    for (unsigned i = 0; i < m; ++i) result[i] = 1e3;
    if (grad) std::fill(grad, grad + static_cast<std::size_t>(m) * n, 0.0);
  }
}

PeerOutcome solveAuglag(const ap::PlanningProblem& problem, double time_budget) {
  const int N = problem.steps;
  const unsigned n = 3u * static_cast<unsigned>(N - 1);
  const Eigen::VectorXd start = ap::unknownsFromTorqueSequence(geodesicTorques(problem));
  std::vector<double> x(start.data(), start.data() + n);
  AuglagData data{&problem, 0};
  nlopt::opt opt(nlopt::AUGLAG_EQ, n);
  nlopt::opt local(nlopt::LD_LBFGS, n);
  // Inner tolerances tighter than round-off make LBFGS stop with a generic failure; these are the
  // tightest that let the outer iteration proceed.
  local.set_ftol_rel(1e-14);
  local.set_xtol_rel(1e-12);
  local.set_vector_storage(20);
  opt.set_local_optimizer(local);
  opt.set_min_objective(auglagObjective, &data);
  opt.add_equality_mconstraint(auglagConstraints, &data,
                               std::vector<double>(ap::kTerminalConstraints, 1e-12));
  opt.set_xtol_rel(1e-13);
  opt.set_ftol_rel(1e-15);
  opt.set_maxtime(time_budget);
  PeerOutcome out;
  double f = 0.0;
  nlopt::result code = nlopt::FAILURE;
  try {
    code = opt.optimize(x, f);
  } catch (const nlopt::roundoff_limited& e) {
    code = nlopt::ROUNDOFF_LIMITED;  // x holds the last iterate; judged by its cost and miss
    out.message = e.what();
  } catch (const std::exception& e) {
    out.message = e.what();
  }
  out.ok = (code > 0 && code != nlopt::MAXTIME_REACHED) || code == nlopt::ROUNDOFF_LIMITED;
  out.message += " nlopt code " + std::to_string(static_cast<int>(code));
  out.iterations = data.evaluations;  // objective evaluations (LBFGS iterations + line search)
  out.torque = ap::torqueSequenceFromUnknowns(Eigen::Map<const Eigen::VectorXd>(x.data(), n));
  return out;
}

// ---- IPOPT on a simultaneous transcription -------------------------------------------------

#ifdef AP_HAVE_IPOPT
using Quaternion = Eigen::Vector4d;  // (w, x, y, z), Hamilton

/// Q(q) with q ⊗ p = left(q) p.
Eigen::Matrix4d leftProduct(const Quaternion& q) {
  Eigen::Matrix4d L;
  L << q(0), -q(1), -q(2), -q(3), q(1), q(0), -q(3), q(2), q(2), q(3), q(0), -q(1), q(3), -q(2),
      q(1), q(0);
  return L;
}
/// p ⊗ q = right(q) p.
Eigen::Matrix4d rightProduct(const Quaternion& q) {
  Eigen::Matrix4d R;
  R << q(0), -q(1), -q(2), -q(3), q(1), q(0), q(3), -q(2), q(2), -q(3), q(0), q(1), q(3), q(2),
      -q(1), q(0);
  return R;
}

/// The reaction-wheel data the transcription's wheel rows need, formed here from the scene's
/// array (not from the planner's quantities): π₀ = R_0 (J Ω(0) + Σ_i a_i h_w,i(0)) with the unit
/// spin axes a_i, and the array quantities of one node as functions of its local unknowns.
struct PeerWheels {
  PeerWheels() = default;
  explicit PeerWheels(const ap::PlanningProblem& p)
      : inertia(p.inertia), inverse_inertia(p.inertia.inverse()) {
    Vector3 array = Vector3::Zero();
    const ap::ReactionWheels& w = p.reaction_wheels;
    for (int i = 0; i < w.count(); ++i) array += w.spin_axes[i].normalized() * w.initialMomentum(i);
    total = p.initial_attitude * (p.inertia * p.initial_velocity + array);
  }
  /// q (torque false) or a (torque true) at a node with quaternion `q`, the step rate before it
  /// and its torque: R(q)ᵀπ₀ = (w² − |u|²)π₀ + 2u(u·π₀) − 2w u×π₀ (q = (w, u), the rotation for
  /// unit q), Π = J Ω_{k−1} + h τ_k/2, q = R(q)ᵀπ₀ − Π, a = −(τ + J⁻¹Π × q).
  template <typename S>
  Eigen::Matrix<S, 3, 1> quantity(bool torque, const Eigen::Matrix<S, 4, 1>& q,
                                  const Eigen::Matrix<S, 3, 1>& omega_before,
                                  const Eigen::Matrix<S, 3, 1>& tau, const S& h) const {
    using V = Eigen::Matrix<S, 3, 1>;
    const S w = q(0);
    const V u = q.template tail<3>();
    const V pi = total.cast<S>();
    const V body_total =
        (w * w - u.dot(u)) * pi + S(2.0) * u.dot(pi) * u - S(2.0) * w * u.cross(pi);
    const V node_momentum = inertia.cast<S>() * omega_before + S(0.5) * h * tau;
    const V array_momentum = body_total - node_momentum;
    if (!torque) return array_momentum;
    return -(tau + (inverse_inertia.cast<S>() * node_momentum).cross(array_momentum));
  }
  Matrix3 inertia = Matrix3::Identity(), inverse_inertia = Matrix3::Identity();
  Vector3 total = Vector3::Zero();  ///< π₀, world
};

/// Simultaneous transcription of the paper scheme. Unknowns: q_1..q_N (4 each), Ω_1..Ω_{N−2}
/// (3 each), τ_1..τ_{N−1} (3 each). Constraints:
///   kinematics  q_{k+1} − q_k ⊗ e(hΩ_k) = 0,                 k = 0..N−1 (4 each)
///   dynamics    exp(hΩ_k^) J Ω_k − J Ω_{k−1} − h τ_k = 0,    k = 1..N−1 (3 each; eq. (18))
///   terminal    vec(q_N*⁻¹ ⊗ q_N) = 0                        (3)
/// with q_0, Ω_0, Ω_{N−1} the boundary data. Every constraint is local: the KKT matrix is banded.
/// Hessian of the Lagrangian σ f + Σ λ_i g_i (exact_hessian): per k = 1..N−2 the (q_k, Ω_k)
/// block of the kinematics (q_k ⊗ e(hΩ_k) is bilinear in q_k and e, so no q_k q_k part) plus the
/// Ω_k Ω_k block of the dynamics, and σ on the τ diagonal; the terminal constraint is linear.
/// Node constraints (the problem's stage constraints, ap::buildStageConstraints, as ours imposes
/// them; rows after the equalities): the box sides are bounds on the τ variables; every other one
/// is a row lower ≤ g(r) ≤ upper of its quantity r (StageConstraint::rowValue; its gradient and
/// curvature, stage_constraints.hpp), which this transcription forms per quantity:
///   torque     r = τ_k,  k = 1..N−1    (Hessian λ g'' on the τ_k diagonal)
///   step rate  r = Ω_k,  k = 1..N−2    (λ g'' on the Ω_k diagonal; Ω_0, Ω_{N−1} data)
///   pointing   r = qᵀM q, k = 2..N−2   (q_1, q_{N−1} follow from the data)
/// where sᵀR(q)b = qᵀMq for unit q, M = [[s·b, (b×s)ᵀ], [b×s, s bᵀ + b sᵀ − (s·b) I]]; its
/// Hessian λ(g' 2M + g'' 4MqqᵀM) fills a q_k q_k block (in the pattern only with a cone).
class TranscriptionNlp : public Ipopt::TNLP {
 public:
  /// `start`: the steps ω_k to start from (empty: the geodesic start ReducedProblem begins on).
  TranscriptionNlp(const ap::PlanningProblem& p, bool exact_hessian,
                   std::vector<Vector3> start = {})
      : p_(p),
        N_(p.steps),
        h_(p.duration / p.steps),
        exact_hessian_(exact_hessian),
        start_(std::move(start)),
        stage_constraints_(ap::buildStageConstraints(p_)) {
    q0_ = ap::so3::quaternionCoefficients<double>(p.initial_attitude);
    qN_ = ap::so3::quaternionCoefficients<double>(p.final_attitude);
    if (p.reaction_wheels.present()) wheels_ = PeerWheels(p);
    for (const auto& c : stage_constraints_) {
      if (c->axis() >= 0) continue;  // a box side: a bound on τ (get_bounds_info)
      int first = 1, last = N_ - 1;
      switch (c->quantity()) {
        case ap::StageQuantity::Torque:
          break;
        case ap::StageQuantity::StepRate:
          last = N_ - 2;
          break;
        case ap::StageQuantity::Pointing:
          first = 2, last = N_ - 2, has_cone_ = true;
          break;
        case ap::StageQuantity::NodeRate:  // the paper scheme has no end torques
          throw ap::InvalidInput("ipopt: the transcription has no node rates (paper scheme)");
        case ap::StageQuantity::WheelMomentum:  // q_0, q_N: boundary data
        case ap::StageQuantity::WheelTorque:    // the paper scheme has no end torques
          has_wheels_ = true;
          break;
      }
      for (int k = first; k <= last; ++k) rows_of_constraints_.push_back({c.get(), k});
    }
  }
  /// sᵀR(q)b = qᵀ M q for a unit quaternion q (w, x, y, z).
  static Eigen::Matrix4d pointingForm(const ap::StageConstraint& c) {
    const Vector3& s = c.spec()->world_direction;
    const Vector3& b = c.spec()->body_axis;
    Eigen::Matrix4d M;
    M(0, 0) = s.dot(b);
    M.block<3, 1>(1, 0) = b.cross(s);
    M.block<1, 3>(0, 1) = b.cross(s).transpose();
    M.block<3, 3>(1, 1) = s * b.transpose() + b * s.transpose() - s.dot(b) * Matrix3::Identity();
    return M;
  }
  int Q(int k) const { return 4 * (k - 1); }                          // k = 1..N
  int W(int k) const { return 4 * N_ + 3 * (k - 1); }                 // k = 1..N−2
  int T(int k) const { return 4 * N_ + 3 * (N_ - 2) + 3 * (k - 1); }  // k = 1..N−1
  int n() const { return 4 * N_ + 3 * (N_ - 2) + 3 * (N_ - 1); }
  int equalities() const { return 4 * N_ + 3 * (N_ - 1) + 3; }
  int m() const { return equalities() + static_cast<int>(rows_of_constraints_.size()); }
  int iterations = 0;
  std::vector<Vector3> torque;

  bool get_nlp_info(Ipopt::Index& n, Ipopt::Index& m, Ipopt::Index& nnz_jac, Ipopt::Index& nnz_h,
                    IndexStyleEnum& style) override {
    n = this->n();
    m = this->m();
    buildPattern();
    nnz_jac = static_cast<Ipopt::Index>(rows_.size());
    nnz_h = exact_hessian_ ? static_cast<Ipopt::Index>(hrows_.size()) : 0;
    style = C_STYLE;
    return true;
  }
  bool get_bounds_info(Ipopt::Index n, Ipopt::Number* xl, Ipopt::Number* xu, Ipopt::Index m,
                       Ipopt::Number* gl, Ipopt::Number* gu) override {
    for (int i = 0; i < n; ++i) xl[i] = -kInfinite, xu[i] = kInfinite;
    for (const auto& c : stage_constraints_) {
      if (c->axis() < 0) continue;
      for (int k = 1; k <= N_ - 1; ++k) {
        xl[T(k) + c->axis()] = std::max(xl[T(k) + c->axis()], c->rowLower());
        xu[T(k) + c->axis()] = std::min(xu[T(k) + c->axis()], c->rowUpper());
      }
    }
    for (int i = 0; i < m; ++i) gl[i] = gu[i] = 0.0;
    for (std::size_t r = 0; r < rows_of_constraints_.size(); ++r) {
      const ap::StageConstraint& c = *rows_of_constraints_[r].constraint;
      const int row = equalities() + static_cast<int>(r);
      gl[row] = std::max(c.rowLower(), -kInfinite), gu[row] = std::min(c.rowUpper(), kInfinite);
    }
    return true;
  }
  bool get_starting_point(Ipopt::Index, bool, Ipopt::Number* x, bool, Ipopt::Number*,
                          Ipopt::Number*, Ipopt::Index, bool, Ipopt::Number*) override {
    // The given start, or the geodesic (feasible: the torques are its dynamics' torques).
    const std::vector<Vector3> w = start_.empty() ? geodesicSteps(p_) : start_;
    const ap::ReducedProblem reduced(p_);
    const std::vector<Vector3> tau = reduced.torques(w);
    Quaternion q = q0_;
    for (int k = 0; k < N_; ++k) {
      q = ap::so3::quaternionProduct<double>(
          q, ap::so3::quaternionOfRotationVector<double>(Vector3(w[k])));
      Eigen::Map<Quaternion>(x + Q(k + 1)) = q;
    }
    for (int k = 1; k <= N_ - 2; ++k) Eigen::Map<Vector3>(x + W(k)) = w[k] / h_;
    for (int k = 1; k <= N_ - 1; ++k) Eigen::Map<Vector3>(x + T(k)) = tau[k];
    return true;
  }
  bool eval_f(Ipopt::Index, const Ipopt::Number* x, bool, Ipopt::Number& f) override {
    f = 0.0;
    for (int i = T(1); i < n(); ++i) f += 0.5 * x[i] * x[i];
    return true;
  }
  bool eval_grad_f(Ipopt::Index n, const Ipopt::Number* x, bool, Ipopt::Number* g) override {
    for (int i = 0; i < n; ++i) g[i] = i >= T(1) ? x[i] : 0.0;
    return true;
  }
  bool eval_g(Ipopt::Index, const Ipopt::Number* x, bool, Ipopt::Index, Ipopt::Number* g) override {
    for (int k = 0; k < N_; ++k) {
      const Quaternion qk = k == 0 ? q0_ : Quaternion(Eigen::Map<const Quaternion>(x + Q(k)));
      const Quaternion e = ap::so3::quaternionOfRotationVector<double>(Vector3(h_ * omega(x, k)));
      Eigen::Map<Quaternion>(g + 4 * k) =
          Eigen::Map<const Quaternion>(x + Q(k + 1)) - ap::so3::quaternionProduct<double>(qk, e);
    }
    const Matrix3& J = p_.inertia;
    for (int k = 1; k <= N_ - 1; ++k) {
      const Vector3 w = omega(x, k);
      Eigen::Map<Vector3>(g + 4 * N_ + 3 * (k - 1)) = ap::so3::exp(Vector3(h_ * w)) * (J * w) -
                                                      J * omega(x, k - 1) -
                                                      h_ * Eigen::Map<const Vector3>(x + T(k));
    }
    const Quaternion qN(Eigen::Map<const Quaternion>(x + Q(N_)));
    const Quaternion conj(qN_(0), -qN_(1), -qN_(2), -qN_(3));
    Eigen::Map<Vector3>(g + 4 * N_ + 3 * (N_ - 1)) =
        ap::so3::quaternionProduct<double>(conj, qN).tail<3>();
    for (std::size_t r = 0; r < rows_of_constraints_.size(); ++r) {
      const auto& [c, k] = rows_of_constraints_[r];
      g[equalities() + r] = c->rowValue(rowQuantity(*c, x, k));
    }
    return true;
  }
  bool eval_jac_g(Ipopt::Index, const Ipopt::Number* x, bool, Ipopt::Index, Ipopt::Index,
                  Ipopt::Index* iRow, Ipopt::Index* jCol, Ipopt::Number* values) override {
    if (!values) {
      for (std::size_t i = 0; i < rows_.size(); ++i) iRow[i] = rows_[i], jCol[i] = cols_[i];
      return true;
    }
    using Dual3 = ap::Dual<3>;
    std::size_t z = 0;
    const Matrix3& J = p_.inertia;
    for (int k = 0; k < N_; ++k) {
      // q_{k+1}: identity
      for (int i = 0; i < 4; ++i) values[z++] = 1.0;
      const Vector3 w = omega(x, k);
      const Quaternion e = ap::so3::quaternionOfRotationVector<double>(Vector3(h_ * w));
      const Quaternion qk = k == 0 ? q0_ : Quaternion(Eigen::Map<const Quaternion>(x + Q(k)));
      if (k >= 1) {
        const Eigen::Matrix4d D = -rightProduct(e);
        for (int r = 0; r < 4; ++r)
          for (int c = 0; c < 4; ++c) values[z++] = D(r, c);
      }
      if (k >= 1 && k <= N_ - 2) {
        ap::so3::Vec3<Dual3> wd;
        for (int i = 0; i < 3; ++i) wd(i) = Dual3(h_ * w(i), i);
        const Eigen::Matrix<Dual3, 4, 1> ed = ap::so3::quaternionOfRotationVector<Dual3>(wd);
        Eigen::Matrix<double, 4, 3> de;
        for (int r = 0; r < 4; ++r)
          for (int c = 0; c < 3; ++c) de(r, c) = h_ * ed(r).d(c);
        const Eigen::Matrix<double, 4, 3> D = -leftProduct(qk) * de;
        for (int r = 0; r < 4; ++r)
          for (int c = 0; c < 3; ++c) values[z++] = D(r, c);
      }
    }
    for (int k = 1; k <= N_ - 1; ++k) {
      if (k <= N_ - 2) {  // ∂/∂Ω_k of exp(hΩ^) J Ω
        const Vector3 w = omega(x, k);
        ap::so3::Vec3<Dual3> wd;
        for (int i = 0; i < 3; ++i) wd(i) = Dual3(w(i), i);
        const ap::so3::Vec3<Dual3> f =
            ap::so3::exp<Dual3>(ap::so3::Vec3<Dual3>(wd * h_)) * (J.cast<Dual3>() * wd);
        for (int r = 0; r < 3; ++r)
          for (int c = 0; c < 3; ++c) values[z++] = f(r).d(c);
      }
      if (k - 1 >= 1) {
        for (int r = 0; r < 3; ++r)
          for (int c = 0; c < 3; ++c) values[z++] = -J(r, c);
      }
      for (int i = 0; i < 3; ++i) values[z++] = -h_;
    }
    const Quaternion conj(qN_(0), -qN_(1), -qN_(2), -qN_(3));
    const Eigen::Matrix4d L = leftProduct(conj);
    for (int r = 1; r < 4; ++r)
      for (int c = 0; c < 4; ++c) values[z++] = L(r, c);
    const std::vector<std::array<WheelJet, 2>> wheel_jets = wheelJets(x);
    for (const auto& [c, k] : rows_of_constraints_) {
      const Vector3 d = c->rowGradient(rowQuantity(*c, x, k));
      if (c->quantity() == ap::StageQuantity::Pointing) {  // ∂(qᵀMq)/∂q = 2Mq
        const Quaternion dq =
            d(0) * (2.0 * pointingForm(*c) * Eigen::Map<const Quaternion>(x + Q(k)));
        for (int i = 0; i < 4; ++i) values[z++] = dq(i);
      } else if (isWheelRow(*c)) {  // gᵀ ∂r over the node's local unknowns
        const Eigen::Matrix<double, 1, kWheelLocals> row =
            d.transpose() * wheel_jets[k][isTorqueRow(*c)].d;
        for (int a = 0; a < kWheelLocals; ++a)
          if (wheelLocal(k, a) >= 0) values[z++] = row(a);
      } else {  // r is the variable block itself (τ_k or Ω_k)
        for (int i = 0; i < 3; ++i) values[z++] = d(i);
      }
    }
    return true;
  }
  bool eval_h(Ipopt::Index, const Ipopt::Number* x, bool, Ipopt::Number obj_factor, Ipopt::Index,
              const Ipopt::Number* lambda, bool, Ipopt::Index, Ipopt::Index* iRow,
              Ipopt::Index* jCol, Ipopt::Number* values) override {
    if (!exact_hessian_) return false;
    if (!values) {
      for (std::size_t i = 0; i < hrows_.size(); ++i) iRow[i] = hrows_[i], jCol[i] = hcols_[i];
      return true;
    }
    using HD = benchmark_ad::HyperDual<3>;
    const Matrix3& J = p_.inertia;
    // The node constraints' terms: λ-weighted, per node (τ and Ω diagonals, q_k q_k blocks).
    std::vector<double> tau_diagonal(N_ + 1, obj_factor), omega_diagonal(N_ + 1, 0.0);
    std::vector<Eigen::Matrix4d> cone_block(has_cone_ ? N_ + 1 : 0, Eigen::Matrix4d::Zero());
    std::vector<WheelBlock> wheel_block(has_wheels_ ? N_ + 1 : 0, WheelBlock::Zero());
    const std::vector<std::array<WheelJet, 2>> wheel_jets = wheelJets(x);
    for (std::size_t r = 0; r < rows_of_constraints_.size(); ++r) {
      const auto& [c, k] = rows_of_constraints_[r];
      const double l = lambda[equalities() + r];
      switch (c->quantity()) {
        case ap::StageQuantity::Torque:
          tau_diagonal[k] += l * c->rowCurvature();
          break;
        case ap::StageQuantity::StepRate:
          omega_diagonal[k] += l * c->rowCurvature();
          break;
        case ap::StageQuantity::Pointing: {  // g(qᵀMq): g' 2M + g'' (2Mq)(2Mq)ᵀ
          const Eigen::Matrix4d M = pointingForm(*c);
          const Vector3 r = rowQuantity(*c, x, k);
          const Quaternion Mq = 2.0 * M * Eigen::Map<const Quaternion>(x + Q(k));
          cone_block[k] += 2.0 * (l * c->rowGradient(r)(0)) * M;
          if (c->rowCurvature() != 0.0)
            cone_block[k] += l * c->rowCurvature() * Mq * Mq.transpose();
          break;
        }
        case ap::StageQuantity::WheelMomentum:
        case ap::StageQuantity::WheelTorque:
          addWheelRowCurvature(*c, wheel_jets[k][isTorqueRow(*c)], l, &wheel_block[k]);
          break;
        case ap::StageQuantity::NodeRate:
          break;  // refused in the constructor
      }
    }
    std::size_t z = 0;
    for (int k = 1; k <= N_ - 2; ++k) {
      const Vector3 w = omega(x, k);
      const Quaternion qk(Eigen::Map<const Quaternion>(x + Q(k)));
      const Quaternion mu(Eigen::Map<const Quaternion>(lambda + 4 * k));           // kinematics k
      const Vector3 nu(Eigen::Map<const Vector3>(lambda + 4 * N_ + 3 * (k - 1)));  // dynamics k
      ap::so3::Vec3<HD> wd;
      for (int i = 0; i < 3; ++i) wd(i) = HD(w(i), i);
      // Kinematics, −μᵀ(q_k ⊗ e(hΩ_k)): e and its first and second derivatives in Ω_k.
      const Eigen::Matrix<HD, 4, 1> e =
          ap::so3::quaternionOfRotationVector<HD>(ap::so3::Vec3<HD>(wd * h_));
      // ∂²/∂Ω_j ∂q_k = −R(∂e/∂Ω_j)ᵀ μ   (q ⊗ p = right(p) q)
      for (int j = 0; j < 3; ++j) {
        const Quaternion de(e(0).g[j], e(1).g[j], e(2).g[j], e(3).g[j]);
        const Quaternion col = -rightProduct(de).transpose() * mu;
        for (int a = 0; a < 4; ++a) values[z++] = col(a);
      }
      // ∂²/∂Ω² of −μᵀ L(q_k) e = Σ_r c_r ∂²e_r, c = −L(q_k)ᵀ μ; plus νᵀ exp(hΩ^) J Ω.
      const Quaternion c = -leftProduct(qk).transpose() * mu;
      const ap::so3::Vec3<HD> f =
          ap::so3::exp<HD>(ap::so3::Vec3<HD>(wd * h_)) * (J.cast<HD>() * wd);
      for (int i = 0; i < 3; ++i) {
        for (int j = 0; j <= i; ++j) {
          double v = 0.0;
          for (int r = 0; r < 4; ++r) v += c(r) * e(r).H[i][j];
          for (int r = 0; r < 3; ++r) v += nu(r) * f(r).H[i][j];
          if (i == j) v += omega_diagonal[k];
          values[z++] = v;
        }
      }
    }
    for (int k = 1; k <= N_ - 1; ++k)
      for (int i = 0; i < 3; ++i) values[z++] = tau_diagonal[k];
    if (has_cone_) {
      for (int k = 2; k <= N_ - 2; ++k)
        for (int i = 0; i < 4; ++i)
          for (int j = 0; j <= i; ++j) values[z++] = cone_block[k](i, j);
    }
    for (const WheelHessianEntry& e : wheel_hessian_) values[z++] = wheel_block[e.k](e.a, e.b);
    return true;
  }
  bool intermediate_callback(Ipopt::AlgorithmMode, Ipopt::Index iter, Ipopt::Number, Ipopt::Number,
                             Ipopt::Number, Ipopt::Number, Ipopt::Number, Ipopt::Number,
                             Ipopt::Number, Ipopt::Number, Ipopt::Index, const Ipopt::IpoptData*,
                             Ipopt::IpoptCalculatedQuantities*) override {
    iterations = iter;
    return true;
  }
  void finalize_solution(Ipopt::SolverReturn, Ipopt::Index, const Ipopt::Number* x,
                         const Ipopt::Number*, const Ipopt::Number*, Ipopt::Index,
                         const Ipopt::Number*, const Ipopt::Number*, Ipopt::Number,
                         const Ipopt::IpoptData*, Ipopt::IpoptCalculatedQuantities*) override {
    torque.assign(N_ + 1, Vector3::Zero());
    for (int k = 1; k <= N_ - 1; ++k) torque[k] = Eigen::Map<const Vector3>(x + T(k));
  }

 protected:
  /// Ω_k: unknown for k = 1..N−2, boundary data for k = 0 and N−1.
  Vector3 omega(const double* x, int k) const {
    if (k == 0) return p_.initial_velocity;
    if (k == N_ - 1) return p_.final_velocity;
    return Eigen::Map<const Vector3>(x + W(k));
  }
  /// The row quantity r of constraint `c` at node k (stage_constraints.hpp): τ_k, Ω_k or the
  /// pointing cosine qᵀMq in r(0).
  Vector3 rowQuantity(const ap::StageConstraint& c, const double* x, int k) const {
    switch (c.quantity()) {
      case ap::StageQuantity::Torque:
        return Eigen::Map<const Vector3>(x + T(k));
      case ap::StageQuantity::StepRate:
        return omega(x, k);
      case ap::StageQuantity::Pointing: {
        const Quaternion q(Eigen::Map<const Quaternion>(x + Q(k)));
        return Vector3(q.dot(pointingForm(c) * q), 0.0, 0.0);
      }
      case ap::StageQuantity::WheelMomentum:
      case ap::StageQuantity::WheelTorque: {
        const Quaternion q(Eigen::Map<const Quaternion>(x + Q(k)));
        return wheels_.quantity<double>(isTorqueRow(c), q, omega(x, k - 1),
                                        Eigen::Map<const Vector3>(x + T(k)), h_);
      }
      case ap::StageQuantity::NodeRate:
        break;  // refused in the constructor
    }
    return Vector3::Zero();
  }
  // ---- reaction-wheel rows (this transcription's own derivation) ----
  // At node k = 1..N−1 of the paper scheme the body's node momentum is the mean of the two
  // steps' momenta seen from node k, Π_k = (F_k J Ω_k + J Ω_{k−1})/2, and the dynamics row
  // F_k J Ω_k = J Ω_{k−1} + h τ_k makes it Π_k = J Ω_{k−1} + h τ_k/2: affine in the unknowns.
  // The array's momentum q_k = R(q_k)ᵀπ₀ − Π_k (R(q)ᵀπ₀ homogeneous quadratic in the
  // quaternion), its torque a_k = −(τ_k + J⁻¹Π_k × q_k). Their derivatives in the node's local
  // unknowns (q_k, Ω_{k−1}, τ_k) by second-order forward mode (HyperDual): a row g(r) has
  // gradient g'ᵀ∂r and curvature Σ g'_j ∇²r_j + g''·∂rᵀ∂r (g'' = rowCurvature()).
  static constexpr int kWheelLocals = 10;
  using WheelBlock = Eigen::Matrix<double, kWheelLocals, kWheelLocals>;
  struct WheelJet {
    Vector3 value;
    Eigen::Matrix<double, 3, kWheelLocals> d;
    WheelBlock second[3];
  };
  static bool isWheelRow(const ap::StageConstraint& c) {
    return c.quantity() == ap::StageQuantity::WheelMomentum ||
           c.quantity() == ap::StageQuantity::WheelTorque;
  }
  /// The unknown behind local a of node k: q_k (0..3), Ω_{k−1} (4..6; data at k = 1: −1),
  /// τ_k (7..9). Increasing in a, so local a ≥ b is the Hessian's lower triangle.
  int wheelLocal(int k, int a) const {
    if (a < 4) return Q(k) + a;
    if (a < 7) return k >= 2 ? W(k - 1) + a - 4 : -1;
    return T(k) + a - 7;
  }
  static bool isTorqueRow(const ap::StageConstraint& c) {
    return c.quantity() == ap::StageQuantity::WheelTorque;
  }
  /// The jets of node k's array momentum (entry 0) and torque (entry 1), k = 1..N−1 (entry k).
  std::vector<std::array<WheelJet, 2>> wheelJets(const double* x) const {
    std::vector<std::array<WheelJet, 2>> out(has_wheels_ ? N_ : 0);
    for (int k = 1; k < static_cast<int>(out.size()); ++k)
      out[k] = {wheelJet(false, x, k), wheelJet(true, x, k)};
    return out;
  }
  WheelJet wheelJet(bool torque, const double* x, int k) const {
    using HD = benchmark_ad::HyperDual<kWheelLocals>;
    Eigen::Matrix<HD, 4, 1> q;
    Eigen::Matrix<HD, 3, 1> omega_before, tau;
    const Vector3 w = omega(x, k - 1);
    for (int i = 0; i < 4; ++i) q(i) = HD(x[Q(k) + i], i);
    for (int i = 0; i < 3; ++i) omega_before(i) = HD(w(i), 4 + i);
    for (int i = 0; i < 3; ++i) tau(i) = HD(x[T(k) + i], 7 + i);
    const Eigen::Matrix<HD, 3, 1> r = wheels_.quantity(torque, q, omega_before, tau, HD(h_));
    WheelJet jet;
    for (int j = 0; j < 3; ++j) {
      jet.value(j) = r(j).v;
      for (int a = 0; a < kWheelLocals; ++a) jet.d(j, a) = r(j).g[a];
      for (int a = 0; a < kWheelLocals; ++a)
        for (int b = 0; b < kWheelLocals; ++b) jet.second[j](a, b) = r(j).H[a][b];
    }
    return jet;
  }
  static void addWheelRowCurvature(const ap::StageConstraint& c, const WheelJet& jet, double lambda,
                                   WheelBlock* block) {
    const Vector3 g = c.rowGradient(jet.value);
    for (int j = 0; j < 3; ++j) *block += lambda * g(j) * jet.second[j];
    if (c.rowCurvature() != 0.0) *block += lambda * c.rowCurvature() * jet.d.transpose() * jet.d;
  }
  void buildPattern() {
    rows_.clear();
    cols_.clear();
    const auto block = [&](int r0, int c0, int nr, int nc, bool diagonal) {
      for (int r = 0; r < nr; ++r)
        for (int c = 0; c < nc; ++c)
          if (!diagonal || r == c) rows_.push_back(r0 + r), cols_.push_back(c0 + c);
    };
    for (int k = 0; k < N_; ++k) {
      block(4 * k, Q(k + 1), 4, 4, true);
      if (k >= 1) block(4 * k, Q(k), 4, 4, false);
      if (k >= 1 && k <= N_ - 2) block(4 * k, W(k), 4, 3, false);
    }
    for (int k = 1; k <= N_ - 1; ++k) {
      const int r0 = 4 * N_ + 3 * (k - 1);
      if (k <= N_ - 2) block(r0, W(k), 3, 3, false);
      if (k - 1 >= 1) block(r0, W(k - 1), 3, 3, false);
      block(r0, T(k), 3, 3, true);
    }
    block(4 * N_ + 3 * (N_ - 1), Q(N_), 3, 4, false);
    for (std::size_t r = 0; r < rows_of_constraints_.size(); ++r) {
      const auto& [c, k] = rows_of_constraints_[r];
      const int row = equalities() + static_cast<int>(r);
      if (c->quantity() == ap::StageQuantity::Torque) {
        block(row, T(k), 1, 3, false);
      } else if (c->quantity() == ap::StageQuantity::StepRate) {
        block(row, W(k), 1, 3, false);
      } else if (isWheelRow(*c)) {
        for (int a = 0; a < kWheelLocals; ++a)
          if (wheelLocal(k, a) >= 0) rows_.push_back(row), cols_.push_back(wheelLocal(k, a));
      } else {
        block(row, Q(k), 1, 4, false);
      }
    }
    // Hessian, lower triangle (row ≥ column; every W index exceeds every Q index), in eval_h's
    // order: per k = 1..N−2 the Ω_k × q_k block (row-major), the Ω_k Ω_k lower triangle; then
    // the τ diagonal.
    hrows_.clear();
    hcols_.clear();
    for (int k = 1; k <= N_ - 2; ++k) {
      for (int j = 0; j < 3; ++j)
        for (int a = 0; a < 4; ++a) hrows_.push_back(W(k) + j), hcols_.push_back(Q(k) + a);
      for (int i = 0; i < 3; ++i)
        for (int j = 0; j <= i; ++j) hrows_.push_back(W(k) + i), hcols_.push_back(W(k) + j);
    }
    for (int k = 1; k <= N_ - 1; ++k)
      for (int i = 0; i < 3; ++i) hrows_.push_back(T(k) + i), hcols_.push_back(T(k) + i);
    if (has_cone_) {  // q_k q_k lower triangles, k = 2..N−2
      for (int k = 2; k <= N_ - 2; ++k)
        for (int i = 0; i < 4; ++i)
          for (int j = 0; j <= i; ++j) hrows_.push_back(Q(k) + i), hcols_.push_back(Q(k) + j);
    }
    // The wheel rows' (q_k, Ω_{k−1}, τ_k) blocks, k = 1..N−1, lower triangles. They overlap the
    // entries above (Ω Ω, τ diagonal, q_k q_k): IPOPT adds repeated triplet entries
    // (TripletToCSRConverter), so each term stays where it is formed.
    wheel_hessian_.clear();
    for (int k = 1; has_wheels_ && k <= N_ - 1; ++k) {
      for (int a = 0; a < kWheelLocals; ++a) {
        for (int b = 0; b <= a; ++b) {
          if (wheelLocal(k, a) < 0 || wheelLocal(k, b) < 0) continue;
          hrows_.push_back(wheelLocal(k, a)), hcols_.push_back(wheelLocal(k, b));
          wheel_hessian_.push_back({k, a, b});
        }
      }
    }
  }

 protected:
  ap::PlanningProblem p_;
  int N_;
  double h_;  ///< fixed here; FreeTimeNlp's last unknown
  bool exact_hessian_;
  std::vector<Vector3> start_;
  Quaternion q0_, qN_;
  std::vector<int> rows_, cols_;
  std::vector<int> hrows_, hcols_;
  /// IPOPT's infinite bound (nlp_upper_bound_inf).
  static constexpr double kInfinite = 1e19;
  ap::StageConstraints stage_constraints_;  ///< points into p_.constraints (declared after p_)
  struct ConstraintRow {
    const ap::StageConstraint* constraint;  ///< into stage_constraints_
    int k;                                  ///< node
  };
  std::vector<ConstraintRow> rows_of_constraints_;
  bool has_cone_ = false;
  bool has_wheels_ = false;
  PeerWheels wheels_;
  struct WheelHessianEntry {
    int k, a, b;  ///< node, local row ≥ local column
  };
  std::vector<WheelHessianEntry> wheel_hessian_;
};

/// exact_hessian: IPOPT's Newton steps use eval_h; otherwise its L-BFGS approximation.
/// start: ω_0..ω_{N−1} of the starting plan (empty: the geodesic).
PeerOutcome solveIpopt(const ap::PlanningProblem& problem, double time_budget, bool exact_hessian,
                       std::vector<Vector3> start = {}) {
  if (problem.scheme != ap::SchemeKind::Paper || problem.effects) {
    throw ap::InvalidInput("ipopt: the transcription is the paper scheme without effects (scheme " +
                           ap::schemeName(problem.scheme) +
                           (problem.effects ? ", with effects)" : ")"));
  }
  Ipopt::SmartPtr<TranscriptionNlp> nlp =
      new TranscriptionNlp(problem, exact_hessian, std::move(start));
  Ipopt::SmartPtr<Ipopt::IpoptApplication> app = IpoptApplicationFactory();
  app->Options()->SetIntegerValue("print_level", 0);
  app->Options()->SetStringValue("sb", "yes");
  app->Options()->SetStringValue("hessian_approximation",
                                 exact_hessian ? "exact" : "limited-memory");
  app->Options()->SetNumericValue("tol", 1e-12);
  app->Options()->SetNumericValue("constr_viol_tol", 1e-12);
  app->Options()->SetIntegerValue("max_iter", 5000);
  app->Options()->SetNumericValue("max_cpu_time", time_budget);
  // IPOPT relaxes every bound by 1e-8 relative by default; ours meets them exactly.
  if (problem.hasNodeConstraints()) app->Options()->SetNumericValue("bound_relax_factor", 0.0);
  PeerOutcome out;
  if (app->Initialize() != Ipopt::Solve_Succeeded) {
    out.message = "IPOPT initialization failed";
    return out;
  }
  const Ipopt::ApplicationReturnStatus status = app->OptimizeTNLP(nlp);
  out.ok = status == Ipopt::Solve_Succeeded || status == Ipopt::Solved_To_Acceptable_Level;
  out.optimal = status == Ipopt::Solve_Succeeded;
  out.message = "ipopt status " + std::to_string(static_cast<int>(status));
  out.iterations = nlp->iterations;
  out.torque = nlp->torque;
  return out;
}

/// The same transcription with the time step h as one more unknown (the last) and the objective
/// T = N h: the free-T discrete problem of minimum time (paper scheme, node constraints as
/// above), for the minimum-time peer row (docs/results/minimum_time.md). Its Jacobian adds the
/// h column, ∂/∂h of the kinematics (−q_k ⊗ ∂e(hΩ_k)/∂h) and of the dynamics
/// (∂(exp(hΩ_k^) J Ω_k)/∂h − τ_k), by forward-mode duals; the Hessian is IPOPT's L-BFGS
/// approximation (the exact one would need the h rows and columns of every block).
class FreeTimeNlp : public TranscriptionNlp {
 public:
  FreeTimeNlp(const ap::PlanningProblem& p, std::vector<Vector3> start)
      : TranscriptionNlp(p, false, std::move(start)) {
    for (std::size_t r = 0; r < rows_of_constraints_.size(); ++r)
      if (isWheelRow(*rows_of_constraints_[r].constraint)) wheel_rows_.push_back(r);
  }
  int H() const { return n(); }  ///< the index of h
  double time_step = 0.0;        ///< h at the end

  bool get_nlp_info(Ipopt::Index& n, Ipopt::Index& m, Ipopt::Index& nnz_jac, Ipopt::Index& nnz_h,
                    IndexStyleEnum& style) override {
    TranscriptionNlp::get_nlp_info(n, m, nnz_jac, nnz_h, style);
    base_nnz_ = nnz_jac;
    n += 1;
    nnz_jac += 4 * N_ + 3 * (N_ - 1);  // the h column: kinematics and dynamics rows
    nnz_jac += static_cast<Ipopt::Index>(wheel_rows_.size());  // and the wheel rows
    nnz_h = 0;
    return true;
  }
  bool get_bounds_info(Ipopt::Index n, Ipopt::Number* xl, Ipopt::Number* xu, Ipopt::Index m,
                       Ipopt::Number* gl, Ipopt::Number* gu) override {
    TranscriptionNlp::get_bounds_info(n, xl, xu, m, gl, gu);
    xl[H()] = 1e-3 * h_, xu[H()] = 1e3 * h_;
    return true;
  }
  bool get_starting_point(Ipopt::Index n, bool init_x, Ipopt::Number* x, bool init_z,
                          Ipopt::Number* zl, Ipopt::Number* zu, Ipopt::Index m, bool init_l,
                          Ipopt::Number* l) override {
    TranscriptionNlp::get_starting_point(n, init_x, x, init_z, zl, zu, m, init_l, l);
    x[H()] = h_;
    return true;
  }
  bool eval_f(Ipopt::Index, const Ipopt::Number* x, bool, Ipopt::Number& f) override {
    f = N_ * x[H()];
    return true;
  }
  bool eval_grad_f(Ipopt::Index n, const Ipopt::Number*, bool, Ipopt::Number* g) override {
    for (int i = 0; i < n; ++i) g[i] = 0.0;
    g[H()] = N_;
    return true;
  }
  bool eval_g(Ipopt::Index n, const Ipopt::Number* x, bool new_x, Ipopt::Index m,
              Ipopt::Number* g) override {
    h_ = x[H()];
    return TranscriptionNlp::eval_g(n, x, new_x, m, g);
  }
  bool eval_jac_g(Ipopt::Index n, const Ipopt::Number* x, bool new_x, Ipopt::Index m,
                  Ipopt::Index nele, Ipopt::Index* iRow, Ipopt::Index* jCol,
                  Ipopt::Number* values) override {
    if (!values) {
      TranscriptionNlp::eval_jac_g(n, x, new_x, m, base_nnz_, iRow, jCol, values);
      for (int r = 0; r < 4 * N_ + 3 * (N_ - 1); ++r) {
        iRow[base_nnz_ + r] = r;
        jCol[base_nnz_ + r] = H();
      }
      for (std::size_t i = 0; i < wheel_rows_.size(); ++i) {
        iRow[base_nnz_ + 4 * N_ + 3 * (N_ - 1) + i] =
            equalities() + static_cast<int>(wheel_rows_[i]);
        jCol[base_nnz_ + 4 * N_ + 3 * (N_ - 1) + i] = H();
      }
      return true;
    }
    h_ = x[H()];
    TranscriptionNlp::eval_jac_g(n, x, new_x, m, base_nnz_, iRow, jCol, values);
    using Dual1 = ap::Dual<1>;
    const Dual1 h(h_, 0);
    double* column = values + base_nnz_;
    for (int k = 0; k < N_; ++k) {
      const Vector3 w = omega(x, k);
      ap::so3::Vec3<Dual1> v;
      for (int i = 0; i < 3; ++i) v(i) = h * w(i);
      const Eigen::Matrix<Dual1, 4, 1> e = ap::so3::quaternionOfRotationVector<Dual1>(v);
      Quaternion de;
      for (int r = 0; r < 4; ++r) de(r) = e(r).d(0);
      const Quaternion qk = k == 0 ? q0_ : Quaternion(Eigen::Map<const Quaternion>(x + Q(k)));
      const Quaternion d = -ap::so3::quaternionProduct<double>(qk, de);
      for (int r = 0; r < 4; ++r) column[4 * k + r] = d(r);
    }
    const Matrix3& J = p_.inertia;
    for (int k = 1; k <= N_ - 1; ++k) {
      const Vector3 w = omega(x, k);
      ap::so3::Vec3<Dual1> v;
      for (int i = 0; i < 3; ++i) v(i) = h * w(i);
      const ap::so3::Vec3<Dual1> f = ap::so3::exp<Dual1>(v) * (J * w).cast<Dual1>();
      const Vector3 tau(Eigen::Map<const Vector3>(x + T(k)));
      for (int r = 0; r < 3; ++r) column[4 * N_ + 3 * (k - 1) + r] = f(r).d(0) - tau(r);
    }
    wheelTimeStepColumn(x, column + 4 * N_ + 3 * (N_ - 1));
    return true;
  }
  void finalize_solution(Ipopt::SolverReturn status, Ipopt::Index n, const Ipopt::Number* x,
                         const Ipopt::Number* zl, const Ipopt::Number* zu, Ipopt::Index m,
                         const Ipopt::Number* g, const Ipopt::Number* l, Ipopt::Number f,
                         const Ipopt::IpoptData* data,
                         Ipopt::IpoptCalculatedQuantities* q) override {
    TranscriptionNlp::finalize_solution(status, n, x, zl, zu, m, g, l, f, data, q);
    time_step = x[H()];
  }

 private:
  /// ∂g/∂h of the wheel rows: g'(r)ᵀ ∂r/∂h, where h enters r (q_k, a_k) only through the node
  /// momentum Π_k = J Ω_{k−1} + h τ_k/2 (∂Π/∂h = τ_k/2; the quaternion, Ω_{k−1} and τ_k are
  /// unknowns of their own), by a forward-mode dual in h of the same PeerWheels::quantity.
  void wheelTimeStepColumn(const double* x, double* column) const {
    using Dual1 = ap::Dual<1>;
    for (std::size_t i = 0; i < wheel_rows_.size(); ++i) {
      const auto& [c, k] = rows_of_constraints_[wheel_rows_[i]];
      const Quaternion q(Eigen::Map<const Quaternion>(x + Q(k)));
      const Vector3 tau(Eigen::Map<const Vector3>(x + T(k)));
      const Eigen::Matrix<Dual1, 3, 1> r =
          wheels_.quantity<Dual1>(isTorqueRow(*c), q.cast<Dual1>(), omega(x, k - 1).cast<Dual1>(),
                                  tau.cast<Dual1>(), Dual1(h_, 0));
      Vector3 value, dh;
      for (int j = 0; j < 3; ++j) value(j) = r(j).v, dh(j) = r(j).d(0);
      column[i] = c->rowGradient(value).dot(dh);
    }
  }

  Ipopt::Index base_nnz_ = 0;
  std::vector<std::size_t> wheel_rows_;  ///< indices into rows_of_constraints_
};

/// The eigenaxis bang–bang slew at the least T its per-axis bounds allow (rest to rest, about a
/// principal axis: no gyroscopic torque), with a 0.3 rad sin² excursion about the diagonal of
/// the two body axes most perpendicular to the eigenaxis — the start that reaches the published
/// optima in ours (drivers/minimum_time_starts.cpp's structured starts). Sets problem->duration to
/// that T; without a per-axis box (a torque norm, reaction-wheel limits) T is the planner's
/// eigenaxis guess (eigenaxisDurationGuess).
std::vector<Vector3> excursionStart(ap::PlanningProblem* problem) {
  const Vector3 rotation =
      ap::so3::log(Matrix3(problem->initial_attitude.transpose() * problem->final_attitude));
  const double angle = rotation.norm();
  const Vector3 e = rotation / angle;
  const Vector3 Je = (problem->inertia * e).cwiseAbs();
  // Without a per-axis box (a torque norm, wheel limits): the planner's eigenaxis guess.
  const double box = (Je.array() / problem->max_torque.array()).maxCoeff();
  const double T = box > 0.0 && std::isfinite(box) ? std::sqrt(4 * angle * box)
                                                   : ap::eigenaxisDurationGuess(*problem);
  problem->duration = T;
  std::vector<Vector3> projected;
  for (int a = 0; a < 3; ++a) {
    const Vector3 p = Vector3::Unit(a) - e * e(a);
    if (p.norm() > 0.3) projected.push_back(p.normalized());
  }
  const Vector3 off = projected.size() >= 2 ? Vector3((projected[0] + projected[1]).normalized())
                                            : e.unitOrthogonal();
  std::vector<Matrix3> R;
  const int N = problem->steps;
  for (int k = 0; k <= N; ++k) {
    const double s = static_cast<double>(k) / N;
    const double theta = s <= 0.5 ? 2 * angle * s * s : angle * (1 - 2 * (1 - s) * (1 - s));
    R.push_back(problem->initial_attitude * ap::so3::exp(Vector3(theta * e)) *
                ap::so3::exp(Vector3(0.3 * std::pow(std::sin(M_PI * s), 2) * off)));
  }
  std::vector<Vector3> w;
  for (int k = 0; k < N; ++k) w.push_back(ap::so3::log(Matrix3(R[k].transpose() * R[k + 1])));
  return w;
}

/// --solver free_time: ours, ONE free-time interior-point solve from excursionStart (the same
/// start and scheme as ipopt_free_time; planMinimumTime runs several starts and a polish).
int solveOursFreeTime(ap::PlanningProblem problem) {
  problem.objective = ap::Objective::MinimumEffort;
  const auto start = std::chrono::steady_clock::now();
  const std::vector<Vector3> steps = excursionStart(&problem);
  std::vector<Matrix3> R{problem.initial_attitude};
  for (const Vector3& w : steps) R.push_back(R.back() * ap::so3::exp(w));
  const ap::FreeTimeOutcome o = ap::solveFreeTime(problem, R, problem.duration, 1e-9, 500);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf(
      "{\"solver\": \"free_time\", \"scheme\": \"%s\", \"steps\": %d, \"time_s\": %.6g, "
      "\"minimum_duration\": %.10g, \"status\": \"%s\", \"iterations\": %d}\n",
      ap::schemeName(problem.scheme).c_str(), problem.steps, seconds, o.duration,
      ap::terminationName(o.termination).c_str(), o.iterations);
  return o.termination == ap::Termination::Converged ? 0 : 1;
}

/// --solver ipopt_free_time: IPOPT on the free-T problem from excursionStart, the scheme paper.
/// Prints one JSON line: time_s, minimum_duration (N h at the end), status, iterations.
int solveIpoptFreeTime(ap::PlanningProblem problem, double time_budget) {
  problem.scheme = ap::SchemeKind::Paper;
  problem.objective = ap::Objective::MinimumEffort;
  const auto start = std::chrono::steady_clock::now();
  std::vector<Vector3> steps = excursionStart(&problem);
  Ipopt::SmartPtr<FreeTimeNlp> nlp = new FreeTimeNlp(problem, std::move(steps));
  Ipopt::SmartPtr<Ipopt::IpoptApplication> app = IpoptApplicationFactory();
  app->Options()->SetIntegerValue("print_level", 0);
  app->Options()->SetStringValue("sb", "yes");
  app->Options()->SetStringValue("hessian_approximation", "limited-memory");
  app->Options()->SetNumericValue("tol", 1e-9);
  app->Options()->SetIntegerValue("max_iter", 5000);
  app->Options()->SetNumericValue("max_cpu_time", time_budget);
  app->Options()->SetNumericValue("bound_relax_factor", 0.0);
  if (app->Initialize() != Ipopt::Solve_Succeeded) {
    std::cerr << "IPOPT initialization failed\n";
    return 1;
  }
  const Ipopt::ApplicationReturnStatus status = app->OptimizeTNLP(nlp);
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf(
      "{\"solver\": \"ipopt_free_time\", \"scheme\": \"paper\", \"steps\": %d, \"time_s\": %.6g, "
      "\"minimum_duration\": %.10g, \"status\": \"%s\", \"iterations\": %d}\n",
      problem.steps, seconds, problem.steps * nlp->time_step,
      status == Ipopt::Solve_Succeeded ? "optimal"
      : status == Ipopt::Solved_To_Acceptable_Level
          ? "acceptable"
          : ("status " + std::to_string(static_cast<int>(status))).c_str(),
      nlp->iterations);
  return status == Ipopt::Solve_Succeeded || status == Ipopt::Solved_To_Acceptable_Level ? 0 : 1;
}

/// The problem --check-hessian checks: nonzero boundary rates and, constrained, one constraint
/// of every kind (two cones: both signs of their rows); with wheels a biased four-wheel pyramid
/// with per-wheel momentum and torque limits and the envelope (every wheel row kind).
ap::PlanningProblem hessianCheckProblem(int steps, bool constrained, bool wheels) {
  ap::PlanningProblem problem = seedRestToRest(steps);
  problem.initial_velocity = Vector3(0.02, -0.01, 0.03);  // nonzero boundary data too
  problem.final_velocity = Vector3(-0.01, 0.02, 0.01);
  if (constrained) {
    problem.max_torque = Vector3(0.5, 0.6, 0.7);
    problem.constraints = {
        ap::PlanningConstraint::maxTorqueNorm(0.8), ap::PlanningConstraint::maxAngularRate(0.3),
        ap::PlanningConstraint::keepOut(Vector3(0, 0, 1), Vector3(0.6, 0.8, 0), 0.4, 0.01),
        ap::PlanningConstraint::keepIn(Vector3(1, 0, 0), Vector3(0, 0.6, 0.8), 1.9)};
  }
  if (wheels) {
    const double s = std::sqrt(2.0 / 3.0), c = std::sqrt(1.0 / 3.0);
    problem.reaction_wheels.spin_axes = {Vector3(s, 0, c), Vector3(0, s, c), Vector3(-s, 0, c),
                                         Vector3(0, -s, c)};
    problem.reaction_wheels.max_torque = {0.3, 0.25, 0.3, 0.35};
    problem.reaction_wheels.max_momentum = {3.0};
    problem.reaction_wheels.initial_momentum = {0.3, -0.2, 0.5, 0.1};
    problem.reaction_wheels.max_momentum_norm = 4.0;
  }
  return problem;
}

/// The NLP's sizes (get_nlp_info).
struct NlpSizes {
  Ipopt::Index n = 0, m = 0, nnz_jac = 0, nnz_h = 0;
};

/// The check's point: the geodesic start perturbed (quaternions off the unit sphere, rates by
/// up to 0.4 rad/s, one rate below the series threshold) and random multipliers.
void randomPoint(TranscriptionNlp& nlp, int steps, const NlpSizes& size, std::vector<double>* x,
                 std::vector<double>* lambda) {
  x->assign(size.n, 0.0);
  lambda->assign(size.m, 0.0);
  nlp.get_starting_point(size.n, true, x->data(), false, nullptr, nullptr, size.m, false, nullptr);
  std::mt19937 rng(20240611);
  std::uniform_real_distribution<double> uniform(-1.0, 1.0);
  for (int k = 1; k <= steps; ++k)
    for (int i = 0; i < 4; ++i) (*x)[nlp.Q(k) + i] += 0.1 * uniform(rng);
  for (int k = 1; k <= steps - 2; ++k)
    for (int i = 0; i < 3; ++i) (*x)[nlp.W(k) + i] += 0.4 * uniform(rng);
  if (steps >= 4) {
    for (int i = 0; i < 3; ++i) (*x)[nlp.W(2) + i] = 1e-7 * uniform(rng);  // series branch
  }
  for (int k = 1; k <= steps - 1; ++k)
    for (int i = 0; i < 3; ++i) (*x)[nlp.T(k) + i] += uniform(rng);
  for (double& l : *lambda) l = uniform(rng);
}

/// The exact Hessian of the Lagrangian, dense and symmetric; `seen` marks the pattern (the lower
/// triangle) and *pattern_errors counts entries above the diagonal or out of range. Repeated
/// entries are added, as IPOPT adds them (the wheel rows' node blocks overlap other terms).
Eigen::MatrixXd exactHessian(TranscriptionNlp& nlp, const NlpSizes& size,
                             const std::vector<double>& x, const std::vector<double>& lambda,
                             double sigma, Eigen::MatrixXi* seen, int* pattern_errors) {
  const Ipopt::Index n = size.n, nnz_h = size.nnz_h;
  std::vector<Ipopt::Index> hr(nnz_h), hc(nnz_h);
  std::vector<double> hv(nnz_h);
  nlp.eval_h(n, x.data(), true, sigma, size.m, lambda.data(), true, nnz_h, hr.data(), hc.data(),
             nullptr);
  nlp.eval_h(n, x.data(), true, sigma, size.m, lambda.data(), true, nnz_h, nullptr, nullptr,
             hv.data());
  Eigen::MatrixXd H = Eigen::MatrixXd::Zero(n, n);
  *seen = Eigen::MatrixXi::Zero(n, n);
  *pattern_errors = 0;
  for (int i = 0; i < nnz_h; ++i) {
    if (hr[i] < hc[i] || hr[i] >= n || hc[i] < 0) {
      ++*pattern_errors;
      continue;
    }
    (*seen)(hr[i], hc[i]) = 1;
    H(hr[i], hc[i]) += hv[i];
    if (hr[i] != hc[i]) H(hc[i], hr[i]) += hv[i];
  }
  return H;
}

/// Central differences (step `step`) of ∇L = σ∇f + Jᵀλ, from the exact first derivatives.
Eigen::MatrixXd differencedHessian(TranscriptionNlp& nlp, const NlpSizes& size,
                                   const std::vector<double>& x, const std::vector<double>& lambda,
                                   double sigma, double step) {
  const Ipopt::Index n = size.n, m = size.m, nnz_jac = size.nnz_jac;
  std::vector<Ipopt::Index> jr(nnz_jac), jc(nnz_jac);
  std::vector<double> jv(nnz_jac), grad(n);
  nlp.eval_jac_g(n, x.data(), true, m, nnz_jac, jr.data(), jc.data(), nullptr);
  const auto gradient = [&](const std::vector<double>& y) {
    Eigen::VectorXd gl(n);
    nlp.eval_grad_f(n, y.data(), true, grad.data());
    nlp.eval_jac_g(n, y.data(), true, m, nnz_jac, nullptr, nullptr, jv.data());
    for (int i = 0; i < n; ++i) gl(i) = sigma * grad[i];
    for (int i = 0; i < nnz_jac; ++i) gl(jc[i]) += lambda[jr[i]] * jv[i];
    return gl;
  };
  Eigen::MatrixXd fd(n, n);
  std::vector<double> y = x;
  for (int j = 0; j < n; ++j) {
    y[j] = x[j] + step;
    const Eigen::VectorXd plus = gradient(y);
    y[j] = x[j] - step;
    const Eigen::VectorXd minus = gradient(y);
    y[j] = x[j];
    fd.col(j) = (plus - minus) / (2.0 * step);
  }
  return fd;
}

/// The constraint Jacobian (eval_jac_g) against central differences of eval_g: the largest
/// row-scaled error.
double jacobianRelativeError(TranscriptionNlp& nlp, const NlpSizes& size,
                             const std::vector<double>& x, double step) {
  const Ipopt::Index n = size.n, m = size.m, nnz_jac = size.nnz_jac;
  std::vector<Ipopt::Index> jr(nnz_jac), jc(nnz_jac);
  std::vector<double> jv(nnz_jac);
  nlp.eval_jac_g(n, x.data(), true, m, nnz_jac, jr.data(), jc.data(), nullptr);
  Eigen::MatrixXd jac = Eigen::MatrixXd::Zero(m, n), jac_fd(m, n);
  nlp.eval_jac_g(n, x.data(), true, m, nnz_jac, nullptr, nullptr, jv.data());
  for (int i = 0; i < nnz_jac; ++i) jac(jr[i], jc[i]) += jv[i];
  std::vector<double> g_plus(m), g_minus(m), y = x;
  for (int j = 0; j < n; ++j) {
    y[j] = x[j] + step;
    nlp.eval_g(n, y.data(), true, m, g_plus.data());
    y[j] = x[j] - step;
    nlp.eval_g(n, y.data(), true, m, g_minus.data());
    y[j] = x[j];
    for (int i = 0; i < m; ++i) jac_fd(i, j) = (g_plus[i] - g_minus[i]) / (2.0 * step);
  }
  double worst = 0.0;
  for (int i = 0; i < m; ++i) {
    const double row_scale = std::max(jac.row(i).cwiseAbs().maxCoeff(), 1e-300);
    worst = std::max(worst, (jac.row(i) - jac_fd.row(i)).cwiseAbs().maxCoeff() / row_scale);
  }
  return worst;
}

/// --check-hessian: eval_h against central differences of ∇L = σ∇f + Jᵀλ (both from the exact
/// first derivatives, eval_grad_f and eval_jac_g) at a random point with random multipliers.
/// The point perturbs the geodesic start (rates by up to 0.4 rad/s, i.e. |hΩ| up to ~0.5 rad at
/// N = 16, quaternions off the unit sphere) and puts one rate below the series threshold of
/// quaternionOfRotationVector/exp, so both branches are exercised. Prints one JSON line.
int checkHessian(int steps, bool constrained, bool wheels) {
  Ipopt::SmartPtr<TranscriptionNlp> nlp =
      new TranscriptionNlp(hessianCheckProblem(steps, constrained, wheels), true);
  NlpSizes size;
  Ipopt::TNLP::IndexStyleEnum style;
  nlp->get_nlp_info(size.n, size.m, size.nnz_jac, size.nnz_h, style);
  const Ipopt::Index n = size.n;
  std::vector<double> x, lambda;
  randomPoint(*nlp, steps, size, &x, &lambda);
  const double sigma = 0.7;
  constexpr double kStep = 1e-5;
  Eigen::MatrixXi seen;
  int pattern_errors = 0;
  const Eigen::MatrixXd H = exactHessian(*nlp, size, x, lambda, sigma, &seen, &pattern_errors);
  const Eigen::MatrixXd fd = differencedHessian(*nlp, size, x, lambda, sigma, kStep);
  // The FD matrix is symmetric only up to its own error: compare with its symmetric part and
  // report the asymmetry (a bound on the FD error) separately.
  const double asymmetry = (fd - fd.transpose()).cwiseAbs().maxCoeff();
  const Eigen::MatrixXd fd_sym = 0.5 * (fd + fd.transpose());
  const double scale = H.cwiseAbs().maxCoeff();
  const double error = (H - fd_sym).cwiseAbs().maxCoeff();
  double outside = 0.0;  // largest FD entry where the pattern has none
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      if (!seen(std::max(i, j), std::min(i, j)))
        outside = std::max(outside, std::abs(fd_sym(i, j)));
  // Entrywise, on the entries that are not negligible.
  double entry_error = 0.0;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      if (std::abs(H(i, j)) > 1e-3 * scale)
        entry_error = std::max(entry_error, std::abs(H(i, j) - fd_sym(i, j)) / std::abs(H(i, j)));
  const double relative = error / scale;
  const double jacobian_relative = jacobianRelativeError(*nlp, size, x, kStep);
  const bool pass = pattern_errors == 0 && relative <= 1e-6 && outside <= 1e-6 * scale &&
                    jacobian_relative <= 1e-6;
  std::printf(
      "{\"check\": \"hessian\", \"constrained\": %s, \"wheels\": %s, \"steps\": %d, "
      "\"n\": %d, \"m\": %d, "
      "\"nnz_h\": %d, \"fd_step\": %g, "
      "\"max_abs_entry\": %.6g, \"max_abs_error\": %.3g, \"relative_error\": %.3g, "
      "\"max_entry_relative_error\": %.3g, \"fd_outside_pattern\": %.3g, \"fd_asymmetry\": "
      "%.3g, \"jacobian_relative_error\": %.3g, \"pattern_errors\": %d, \"pass\": %s}\n",
      constrained ? "true" : "false", wheels ? "true" : "false", steps, static_cast<int>(n),
      static_cast<int>(size.m), static_cast<int>(size.nnz_h), kStep, scale, error, relative,
      entry_error, outside, asymmetry, jacobian_relative, pattern_errors, pass ? "true" : "false");
  return pass ? 0 : 1;
}

/// --check-hessian --free-time: the free-time NLP (ipopt_free_time: h the last unknown) has no
/// exact Hessian (IPOPT's L-BFGS), so its Jacobian is what is checked, the h column included
/// (kinematics, dynamics and, with --wheels, the wheel rows' ∂g/∂h), against central differences
/// of eval_g at the same random point. Prints one JSON line.
int checkFreeTimeJacobian(int steps, bool constrained, bool wheels) {
  Ipopt::SmartPtr<FreeTimeNlp> nlp =
      new FreeTimeNlp(hessianCheckProblem(steps, constrained, wheels), {});
  NlpSizes size;
  Ipopt::TNLP::IndexStyleEnum style;
  nlp->get_nlp_info(size.n, size.m, size.nnz_jac, size.nnz_h, style);
  std::vector<double> x, lambda;
  randomPoint(*nlp, steps, size, &x, &lambda);
  constexpr double kStep = 1e-6;
  x[nlp->H()] *= 1.1;  // off the start's h, which the rest of the point was built for
  const double relative = jacobianRelativeError(*nlp, size, x, kStep);
  const bool pass = relative <= 1e-6;
  std::printf(
      "{\"check\": \"free_time_jacobian\", \"constrained\": %s, \"wheels\": %s, \"steps\": %d, "
      "\"n\": %d, \"m\": %d, \"nnz_jac\": %d, \"fd_step\": %g, \"hessian\": \"limited-memory "
      "(none formed)\", \"jacobian_relative_error\": %.3g, \"pass\": %s}\n",
      constrained ? "true" : "false", wheels ? "true" : "false", steps, static_cast<int>(size.n),
      static_cast<int>(size.m), static_cast<int>(size.nnz_jac), kStep, relative,
      pass ? "true" : "false");
  return pass ? 0 : 1;
}
#endif

// ---- the seed's approach: Newton on the necessary conditions, dense complex-step Jacobian ----

using Complex = std::complex<double>;
double realPart(double x) {
  return x;
}
double realPart(const Complex& x) {
  return x.real();
}

template <typename S>
using V3 = Eigen::Matrix<S, 3, 1>;
template <typename S>
using M3 = Eigen::Matrix<S, 3, 3>;

/// Σ a_i b_i without conjugation (Eigen's dot conjugates complex scalars, which would break the
/// complex step: every function below must stay analytic in its argument).
template <typename S>
S plainDot(const V3<S>& a, const V3<S>& b) {
  return a(0) * b(0) + a(1) * b(1) + a(2) * b(2);
}

/// a × b without conjugation (Eigen's cross conjugates its result for complex scalars).
template <typename S>
V3<S> plainCross(const V3<S>& a, const V3<S>& b) {
  return V3<S>(a(1) * b(2) - a(2) * b(1), a(2) * b(0) - a(0) * b(2), a(0) * b(1) - a(1) * b(0));
}

template <typename S>
M3<S> hatOf(const V3<S>& v) {
  M3<S> m;
  m << S(0), -v(2), v(1), v(2), S(0), -v(0), -v(1), v(0), S(0);
  return m;
}

/// exp(w^) (Rodrigues), analytic in w so the complex step differentiates it.
template <typename S>
M3<S> expOf(const V3<S>& w) {
  const S t2 = plainDot<S>(w, w);
  S a, b;
  if (std::abs(realPart(t2)) < 1e-8) {
    a = S(1) - t2 / 6.0 + t2 * t2 / 120.0;
    b = S(0.5) - t2 / 24.0 + t2 * t2 / 720.0;
  } else {
    const S t = std::sqrt(t2);
    a = std::sin(t) / t;
    b = (S(1) - std::cos(t)) / t2;
  }
  const M3<S> W = hatOf<S>(w);
  return M3<S>::Identity() + a * W + b * W * W;
}

/// Jr⁻¹(w) = I + ½ w^ + c w^², c = (1 − (θ/2) cot(θ/2))/θ².
template <typename S>
M3<S> rightJacobianInverseOf(const V3<S>& w) {
  const S t2 = plainDot<S>(w, w);
  S c;
  if (std::abs(realPart(t2)) < 1e-8) {
    c = S(1.0 / 12.0) + t2 / 720.0;
  } else {
    const S half = std::sqrt(t2) / 2.0;
    c = (S(1) - half * std::cos(half) / std::sin(half)) / t2;
  }
  const M3<S> W = hatOf<S>(w);
  return M3<S>::Identity() + S(0.5) * W + c * W * W;
}

template <typename S>
Eigen::Matrix<S, 4, 1> quaternionOf(const V3<S>& w) {
  const S t2 = plainDot<S>(w, w);
  S c, k;
  if (std::abs(realPart(t2)) < 1e-8) {
    c = S(1) - t2 / 8.0;
    k = S(0.5) - t2 / 48.0;
  } else {
    const S t = std::sqrt(t2);
    c = std::cos(t / 2.0);
    k = std::sin(t / 2.0) / t;
  }
  Eigen::Matrix<S, 4, 1> q;
  q << c, k * w(0), k * w(1), k * w(2);
  return q;
}

template <typename S>
Eigen::Matrix<S, 4, 1> quaternionTimes(const Eigen::Matrix<S, 4, 1>& p,
                                       const Eigen::Matrix<S, 4, 1>& q) {
  const V3<S> pv = p.template tail<3>(), qv = q.template tail<3>();
  Eigen::Matrix<S, 4, 1> r;
  r(0) = p(0) * q(0) - plainDot<S>(pv, qv);
  r.template tail<3>() = p(0) * qv + q(0) * pv + plainCross<S>(pv, qv);
  return r;
}

/// The seed's system, 3(2N−3) equations in x = (τ_1..τ_{N−1}, Ω_1..Ω_{N−2}):
///   h² × corrected eq. (28), k = 2..N−2 (docs/results/necessary_conditions.md)
///   J Ω_k − exp(hΩ_k)ᵀ (h τ_k + J Ω_{k−1}), k = 1..N−1 (eq. (18))
///   log(R_Nᵀ R_0 Π_k exp(hΩ_k)) (terminal attitude, through quaternions)
template <typename S>
void seedResidual(const ap::PlanningProblem& p, const Eigen::Matrix<S, Eigen::Dynamic, 1>& x,
                  Eigen::Matrix<S, Eigen::Dynamic, 1>* r) {
  const int N = p.steps;
  const double h = p.duration / N;
  const M3<S> J = p.inertia.cast<S>();
  const auto tau = [&](int k) -> V3<S> {
    return (k < 1 || k > N - 1) ? V3<S>::Zero() : V3<S>(x.template segment<3>(3 * (k - 1)));
  };
  const auto W = [&](int k) -> V3<S> {
    if (k == 0) return p.initial_velocity.cast<S>();
    if (k == N - 1) return p.final_velocity.cast<S>();
    return x.template segment<3>(3 * (N - 1) + 3 * (k - 1));
  };
  r->resize(3 * (2 * N - 3));
  std::vector<M3<S>> g(N), Jt(N);
  for (int k = 0; k < N; ++k) {
    const V3<S> w = W(k) * h;
    g[k] = expOf<S>(w);
    Jt[k] = rightJacobianInverseOf<S>(w).transpose() * J;
  }
  int row = 0;
  for (int k = 2; k <= N - 2; ++k) {
    const V3<S> t = -Jt[k - 1] * tau(k) + g[k] * Jt[k] * tau(k + 1) +
                    Jt[k - 1] * g[k - 1].transpose() * tau(k - 1) -
                    g[k] * Jt[k] * g[k].transpose() * tau(k) -
                    h * g[k] * plainCross<S>(J * W(k), g[k].transpose() * tau(k)) +
                    h * plainCross<S>(J * W(k - 1), g[k - 1].transpose() * tau(k - 1));
    r->template segment<3>(row) = t;
    row += 3;
  }
  for (int k = 1; k <= N - 1; ++k) {
    r->template segment<3>(row) = J * W(k) - g[k].transpose() * (h * tau(k) + J * W(k - 1));
    row += 3;
  }
  Eigen::Matrix<S, 4, 1> q = ap::so3::quaternionCoefficients<double>(
                                 Matrix3(p.final_attitude.transpose() * p.initial_attitude))
                                 .cast<S>();
  for (int k = 0; k < N; ++k) q = quaternionTimes<S>(q, quaternionOf<S>(V3<S>(W(k) * h)));
  // log of a quaternion near the identity: 2 atan(|v|/w) v/|v| (≈ 2v/w (1 − s²/3w²))
  const V3<S> v = q.template tail<3>();
  const S s2 = plainDot<S>(v, v);
  V3<S> log_q;
  if (std::abs(realPart(s2)) < 1e-16) {
    log_q = v * (S(2) / q(0)) * (S(1) - s2 / (S(3) * q(0) * q(0)));
  } else {
    const S s = std::sqrt(s2);
    log_q = v * (S(2) * std::atan(s / q(0)) / s);
  }
  r->template segment<3>(row) = log_q;
}

PeerOutcome solveComplexStep(const ap::PlanningProblem& p, double time_budget) {
  const auto start = std::chrono::steady_clock::now();
  const int N = p.steps;
  const double h = p.duration / N;
  const int n = 3 * (2 * N - 3);
  // The geodesic start ours uses: its torques and velocities.
  const std::vector<Vector3> w = geodesicSteps(p);
  const std::vector<Vector3> tau = geodesicTorques(p);
  Eigen::VectorXd x(n);
  for (int k = 1; k <= N - 1; ++k) x.segment<3>(3 * (k - 1)) = tau[k];
  for (int k = 1; k <= N - 2; ++k) x.segment<3>(3 * (N - 1) + 3 * (k - 1)) = w[k] / h;
  const auto residual = [&](const Eigen::VectorXd& y) {
    Eigen::VectorXd r;
    seedResidual<double>(p, y, &r);
    return r;
  };
  PeerOutcome out;
  Eigen::VectorXd r = residual(x);
  double r_norm = r.norm();
  Eigen::MatrixXd jac(n, n);
  Eigen::Matrix<Complex, Eigen::Dynamic, 1> xc(n), rc;
  constexpr double kStep = 1e-30;
  for (int it = 0; it < 50; ++it) {
    if (std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count() >
        time_budget) {
      out.message = "time budget exceeded";
      break;
    }
    // Dense complex-step Jacobian: one residual evaluation per unknown.
    xc = x.cast<Complex>();
    for (int j = 0; j < n; ++j) {
      xc(j) += Complex(0.0, kStep);
      seedResidual<Complex>(p, xc, &rc);
      for (int i = 0; i < n; ++i) jac(i, j) = rc(i).imag() / kStep;
      xc(j) = x(j);
    }
    const Eigen::VectorXd dx = -jac.partialPivLu().solve(r);
    ++out.iterations;
    double step = 1.0;
    bool improved = false;
    for (int back = 0; back < 30; ++back) {
      const Eigen::VectorXd trial = x + step * dx;
      const Eigen::VectorXd r_trial = residual(trial);
      if (r_trial.allFinite() && r_trial.norm() < r_norm) {
        x = trial;
        r = r_trial;
        r_norm = r.norm();
        improved = true;
        break;
      }
      step *= 0.5;
    }
    // Converged: the full Newton step is at round-off relative to x.
    if (dx.norm() <= 1e-11 * x.norm() || !improved) {
      out.ok = true;
      out.message = improved ? "step below 1e-11 relative" : "residual at round-off";
      break;
    }
  }
  out.torque.assign(N + 1, Vector3::Zero());
  for (int k = 1; k <= N - 1; ++k) out.torque[k] = x.segment<3>(3 * (k - 1));
  return out;
}

// ---- driver --------------------------------------------------------------------------------

struct Measurement {
  std::string solver, scheme, message;
  int steps = 0, iterations = 0;
  double time_s = 0.0, cost = 0.0, terminal_miss = 0.0;
  double warm_time_s = 0.0;      ///< median of the repeated in-process solves (0: not measured)
  double warm_min_time_s = 0.0;  ///< the least of them: the time least disturbed by other load
  double max_constraint_violation = 0.0;  ///< checkConstraints on the replayed plan
  int active_constraints = 0;             ///< node constraints at their bound (checkConstraints)
  bool converged = false;
  long peak_rss_kb = 0;
};

std::string escaped(const std::string& s) {
  std::string out;
  for (char c : s) {
    if (c == '"' || c == '\\') out += '\\';
    out += (c == '\n') ? ' ' : c;
  }
  return out;
}

void printJson(const Measurement& m) {
  std::printf(
      "{\"solver\": \"%s\", \"scheme\": \"%s\", \"steps\": %d, \"time_s\": %.9g, "
      "\"iterations\": %d, \"cost\": %.17g, \"converged\": %s, \"terminal_miss\": %.3g, "
      "\"peak_rss_kb\": %ld, \"warm_time_s\": %.9g, \"max_constraint_violation\": %.3g, "
      "\"active_constraints\": %d, \"message\": \"%s\", \"warm_min_time_s\": %.9g}\n",
      m.solver.c_str(), m.scheme.c_str(), m.steps, m.time_s, m.iterations, m.cost,
      m.converged ? "true" : "false", m.terminal_miss, m.peak_rss_kb, m.warm_time_s,
      m.max_constraint_violation, m.active_constraints, escaped(m.message).c_str(),
      m.warm_min_time_s);
  std::fflush(stdout);
}

/// Where the peer starts (`--start`): the geodesic; our unconstrained optimum, the start ours
/// takes for a constrained solve; or our constrained optimum, so that a peer that stays there
/// shows it is a local optimum of the same problem (a peer answer with another cost is then
/// another local optimum, not a better solve of ours). Computed before the peer's clock starts.
enum class PeerStart { Geodesic, Unconstrained, Ours };

/// The steps ω_k of our optimum, without (Unconstrained) or with (Ours) the constraints.
std::vector<Vector3> ourSteps(const ap::PlanningProblem& problem, PeerStart start) {
  ap::PlanningProblem solved = problem;
  if (start == PeerStart::Unconstrained) {
    solved.constraints.clear();
    solved.max_torque = Vector3::Constant(std::numeric_limits<double>::infinity());
  }
  const ap::PlanResult r = ap::planManeuver(solved, ap::SolverOptions());
  if (!r.converged()) throw ap::InvalidInput("--start: our plan did not converge: " + r.message());
  std::vector<Vector3> w;
  for (int k = 0; k < r.maneuver.steps(); ++k) {
    w.push_back(
        ap::so3::log(Matrix3(r.maneuver.attitude[k].transpose() * r.maneuver.attitude[k + 1])));
  }
  return w;
}

Measurement run(const std::string& solver, const ap::PlanningProblem& problem, double time_budget,
                PeerStart peer_start = PeerStart::Geodesic) {
  Measurement m;
  m.solver = solver;
  m.scheme = ap::schemeName(problem.scheme);
  m.steps = problem.steps;
  std::vector<Vector3> start_steps;
  if (peer_start != PeerStart::Geodesic) start_steps = ourSteps(problem, peer_start);
  const auto start = std::chrono::steady_clock::now();
  PeerOutcome peer;
  ap::PlanResult ours;
  bool is_ours = false;
  if (solver == "newton") {
    ap::SolverOptions options;
    options.time_budget_s = time_budget;
    ours = ap::planManeuver(problem, options);
    is_ours = true;
  } else if (solver == "slsqp") {
    ap::SolverOptions options;
    options.solver = ap::SolverKind::Nlopt;
    options.max_iterations = 100000;
    options.time_budget_s = time_budget;
    ours = ap::planManeuver(problem, options);
    is_ours = true;
  } else if (solver == "auglag") {
    peer = solveAuglag(problem, time_budget);
  } else if (solver == "ipopt" || solver == "ipopt_lbfgs") {
#ifdef AP_HAVE_IPOPT
    peer = solveIpopt(problem, time_budget, solver == "ipopt", start_steps);
#else
    throw ap::InvalidInput("ipopt: this build has no IPOPT (install coinor-libipopt-dev)");
#endif
  } else if (solver == "complex_step") {
    peer = solveComplexStep(problem, time_budget);
  } else {
    throw ap::InvalidInput("unknown solver '" + solver + "'");
  }
  m.time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (is_ours) {
    m.iterations = ours.iterations;
    m.converged = ours.converged();
    m.message = ours.message();
  } else {
    // The peer's torques replayed exactly as ours are (outside the timed region).
    ap::PlanResult replay;
    ap::evaluatePlan(problem, peer.torque, &replay);
    ours = replay;
    m.iterations = peer.iterations;
    m.converged =
        peer.ok && std::max(replay.terminal_attitude_error, replay.terminal_velocity_error) <= 1e-8;
    m.message = peer.message;
  }
  m.cost = ours.cost;
  m.terminal_miss = std::max(ours.terminal_attitude_error, ours.terminal_velocity_error);
  if (problem.hasNodeConstraints() && ours.maneuver.steps() == problem.steps) {
    const ap::ConstraintCheck check = ap::checkConstraints(problem, ours.maneuver);
    m.max_constraint_violation = check.max_violation;
    m.active_constraints = check.active;
    // A peer "converges" only onto a plan that meets the constraints it was given.
    if (!is_ours && m.max_constraint_violation > 1e-8) m.converged = false;
  }
  m.peak_rss_kb = peakRssKb();
  return m;
}

int quick() {
  const ap::PlanningProblem problem = seedRestToRest(16);
  std::vector<std::string> solvers = {"newton", "slsqp", "auglag", "complex_step"};
#ifdef AP_HAVE_IPOPT
  solvers.push_back("ipopt");
  solvers.push_back("ipopt_lbfgs");
#endif
  double reference = 0.0;
  int failures = 0;
  for (const std::string& s : solvers) {
    const Measurement m = run(s, problem, 60.0);
    printJson(m);
    if (s == "newton") reference = m.cost;
    // AUGLAG+LBFGS is reported, not required: it does not reach the optimum on this problem.
    if (s == "auglag") continue;
    if (!m.converged) ++failures;
    if (std::abs(m.cost - reference) > 1e-8 * reference) ++failures;
  }
  return failures == 0 ? 0 : 1;
}

// ---- the seeded randomized suite ------------------------------------------

struct SuiteRow {
  ap::robustness::RandomCase c;
  ap::PlanResult ours;
  bool ipopt_ran = false;  ///< IPOPT transcribes the paper scheme only
  PeerOutcome ipopt;
  double ipopt_cost = 0.0, ipopt_time_s = 0.0, ipopt_replay_miss = 0.0;
};

std::string percent(int part, int whole) {
  char b[64];
  std::snprintf(b, sizeof b, "%d / %d (%.1f %%)", part, whole, whole ? 100.0 * part / whole : 0.0);
  return b;
}

/// One case of the suite: ours (planManeuver, default options but the time budget) and, on a
/// paper-scheme case, IPOPT from the same start (newtonInitialSteps); one JSON line to stderr.
SuiteRow runSuiteCase(const ap::robustness::RandomCase& c, double time_budget) {
  SuiteRow row;
  row.c = c;
  ap::SolverOptions options;
  options.time_budget_s = time_budget;
  row.ours = ap::planManeuver(c.problem, options);
#ifdef AP_HAVE_IPOPT
  if (c.problem.scheme == ap::SchemeKind::Paper) {
    row.ipopt_ran = true;
    const auto start = std::chrono::steady_clock::now();
    row.ipopt = solveIpopt(c.problem, time_budget, true, ap::newtonInitialSteps(c.problem));
    row.ipopt_time_s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    if (row.ipopt.torque.size() == static_cast<size_t>(c.problem.steps + 1)) {
      ap::PlanResult replay;
      try {
        ap::evaluatePlan(c.problem, row.ipopt.torque, &replay);
        row.ipopt_cost = replay.cost;
        row.ipopt_replay_miss = replay.replay_miss;
      } catch (const ap::StepTooLarge&) {
        row.ipopt.optimal = false;
      }
    } else {
      row.ipopt.optimal = false;
    }
  }
#endif
  std::fprintf(stderr,
               "{\"case\": %d, \"label\": \"%s\", \"termination\": \"%s\", \"iterations\": %d, "
               "\"time_s\": %.4g, \"cost\": %.17g, \"ipopt\": %s, \"ipopt_cost\": %.17g, "
               "\"ipopt_iterations\": %d, \"ipopt_time_s\": %.4g}\n",
               c.index, escaped(c.label).c_str(), ap::terminationName(row.ours.termination).c_str(),
               row.ours.iterations, row.ours.solve_time_s, row.ours.cost,
               row.ipopt_ran ? (row.ipopt.optimal ? "\"optimal\"" : "\"failed\"") : "null",
               row.ipopt_cost, row.ipopt.iterations, row.ipopt_time_s);
  return row;
}

/// The suite's figures over the cases of one scheme (or all).
struct SuiteTally {
  int cases = 0, converged = 0, with_ipopt = 0, ipopt_optimal = 0, ours_where_ipopt = 0;
  int both = 0, not_costlier = 0, cheaper = 0, costlier = 0;
  std::vector<double> iterations, times, ipopt_iterations, ipopt_times;
  double worst_ratio = 0.0;  ///< largest ours/IPOPT cost where both converged
};

/// `scheme_filter`: −1 all, else static_cast<int>(SchemeKind).
SuiteTally tallySuite(const std::vector<SuiteRow>& rows, int scheme_filter) {
  SuiteTally t;
  for (const SuiteRow& r : rows) {
    if (scheme_filter >= 0 && static_cast<int>(r.c.problem.scheme) != scheme_filter) continue;
    ++t.cases;
    t.converged += r.ours.converged();
    t.iterations.push_back(r.ours.iterations);
    t.times.push_back(r.ours.solve_time_s);
    if (!r.ipopt_ran) continue;
    ++t.with_ipopt;
    t.ipopt_iterations.push_back(r.ipopt.iterations);
    t.ipopt_times.push_back(r.ipopt_time_s);
    if (!r.ipopt.optimal) continue;
    ++t.ipopt_optimal;
    t.ours_where_ipopt += r.ours.converged();
    if (!r.ours.converged()) continue;
    ++t.both;
    const double rel = (r.ours.cost - r.ipopt_cost) / r.ipopt_cost;
    t.not_costlier += rel <= 1e-8;
    t.cheaper += rel < -1e-8;
    t.costlier += rel > 1e-8;
    t.worst_ratio = std::max(t.worst_ratio, r.ours.cost / r.ipopt_cost);
  }
  return t;
}

/// "median / max" of `values` (0 for none).
std::string medianAndMax(const std::vector<double>& values) {
  std::ostringstream out;
  out << std::defaultfloat << std::setprecision(3) << median(values) << " / "
      << (values.empty() ? 0 : *std::max_element(values.begin(), values.end()));
  return out.str();
}

/// The section's heading and how it was made.
void writeSuiteIntro(std::ostream& md, int count, std::uint64_t seed, double time_budget,
                     double wall) {
  const time_t now = std::time(nullptr);
  char date[64];
  std::strftime(date, sizeof date, "%Y-%m-%d %H:%M UTC", std::gmtime(&now));
  md << "## Randomized suite (issue 19, item 5)\n\n"
     << "Generated by `scripts/robustness --random` (`benchmark_solvers --random-suite " << count
     << " --seed " << seed << "`) on " << date << "; do not edit by hand. " << count
     << " problems from the seeded generator `test/support/random_problems.hpp` (physical "
        "inertias with the triangle inequality and seed-like strongly anisotropic ones, random "
        "attitudes, boundary rates up to 5 rad/s with h|Ω| ≤ 0.5, horizons 0.5–100 s, paper and "
        "variational alternately); the first 40 are also asserted by `test_random_suite` in "
        "`scripts/test`. Ours: `planManeuver` with default options (200 Newton iterations per "
        "level) and a "
     << time_budget
     << " s budget. IPOPT: the simultaneous transcription of `benchmark_solvers --solver ipopt` "
        "(exact Hessian, tol 1e-12), started from the same initial guess as ours "
        "(`newtonInitialSteps`: the rate-honouring Hermite curve to the nearest lift); it "
        "transcribes the paper scheme only, so variational cases have no IPOPT figure. IPOPT "
        "counts as converged on Solve_Succeeded; its cost is that of its torques. Relative cost "
        "difference = (ours − IPOPT) / IPOPT. Wall time of the whole run "
     << std::fixed << std::setprecision(0) << wall << " s on a 2-core machine shared with other "
     << "builds (times vary ±50 % with the load).\n\n";
}

/// The figures, per scheme and in all.
void writeSuiteFigures(std::ostream& md, const SuiteTally& all, const SuiteTally& paper,
                       const SuiteTally& variational) {
  md << std::defaultfloat << std::setprecision(3);
  md << "| figure | all | paper | variational |\n|---|---|---|---|\n";
  md << "| cases | " << all.cases << " | " << paper.cases << " | " << variational.cases << " |\n";
  md << "| ours converged | " << percent(all.converged, all.cases) << " | "
     << percent(paper.converged, paper.cases) << " | "
     << percent(variational.converged, variational.cases) << " |\n";
  md << "| ours median / max iterations | " << medianAndMax(all.iterations) << " | "
     << medianAndMax(paper.iterations) << " | " << medianAndMax(variational.iterations) << " |\n";
  md << "| ours median / max time [s] | " << medianAndMax(all.times) << " | "
     << medianAndMax(paper.times) << " | " << medianAndMax(variational.times) << " |\n";
  md << "| IPOPT converged | " << percent(all.ipopt_optimal, all.with_ipopt) << " | "
     << percent(paper.ipopt_optimal, paper.with_ipopt) << " | n/a |\n";
  md << "| IPOPT median iterations / time [s] | " << median(all.ipopt_iterations) << " / "
     << median(all.ipopt_times) << " | " << median(paper.ipopt_iterations) << " / "
     << median(paper.ipopt_times) << " | n/a |\n";
  md << "| ours converged where IPOPT converged | "
     << percent(all.ours_where_ipopt, all.ipopt_optimal) << " | "
     << percent(paper.ours_where_ipopt, paper.ipopt_optimal) << " | n/a |\n";
  md << "| both converged: ours cost ≤ IPOPT's (1e-8 rel) | " << percent(all.not_costlier, all.both)
     << " | " << percent(paper.not_costlier, paper.both) << " | n/a |\n";
  md << "| both converged: ours cheaper / costlier (beyond 1e-8 rel) | " << all.cheaper << " / "
     << all.costlier << " | " << paper.cheaper << " / " << paper.costlier << " | n/a |\n";
  md << "| both converged: worst ours / IPOPT cost | " << all.worst_ratio << " | "
     << paper.worst_ratio << " | n/a |\n\n";
}

/// The targets the suite was made for, met or not on this run.
void writeSuiteTargets(std::ostream& md, const SuiteTally& all, const SuiteTally& paper) {
  const double cost_share = paper.with_ipopt ? double(paper.not_costlier) / paper.with_ipopt : 0.0;
  md << "Targets of issue 19 (measured on this run):\n\n"
     << "| target | measured | met |\n|---|---|---|\n"
     << "| 100 % convergence on the suite | " << percent(all.converged, all.cases) << " | "
     << (all.converged == all.cases ? "yes" : "**no**") << " |\n"
     << "| converged wherever IPOPT converged | "
     << percent(all.ours_where_ipopt, all.ipopt_optimal) << " | "
     << (all.ours_where_ipopt == all.ipopt_optimal ? "yes" : "**no**") << " |\n"
     << "| cost ≤ IPOPT's (1e-8 rel) in ≥ 99 % of the cases with an IPOPT figure (ours must have "
        "converged) | "
     << percent(paper.not_costlier, paper.with_ipopt) << " | "
     << (cost_share >= 0.99 ? "yes" : "**no**") << " |\n"
     << "| median iterations ≤ 20 | " << median(all.iterations) << " | "
     << (median(all.iterations) <= 20 ? "yes" : "**no**") << " |\n\n";
}

/// One row of the every-case table.
void writeSuiteCase(std::ostream& md, const SuiteRow& r) {
  const ap::PlanningProblem& p = r.c.problem;
  char line[1024];
  std::snprintf(
      line, sizeof line,
      "| %d | %s | %s | %.3g | %d | %.2f | %.2f | %s | %d | %.3f | %.10g | %.1e |", r.c.index,
      ap::robustness::inertiaFamilyName(r.c.family).c_str(), ap::schemeName(p.scheme).c_str(),
      p.duration, p.steps, p.initial_velocity.norm(), p.final_velocity.norm(),
      r.ours.converged() ? "converged"
                         : ("**" + ap::terminationName(r.ours.termination) + "**").c_str(),
      r.ours.iterations, r.ours.solve_time_s, r.ours.cost, r.ours.replay_miss);
  md << line;
  if (!r.ipopt_ran) {
    md << " – | | | | |\n";
    return;
  }
  std::snprintf(line, sizeof line, " %s | %d | %.3f | %.10g |",
                r.ipopt.optimal ? "converged" : "failed", r.ipopt.iterations, r.ipopt_time_s,
                r.ipopt_cost);
  md << line;
  if (r.ipopt.optimal && r.ours.converged()) {
    const double rel = (r.ours.cost - r.ipopt_cost) / r.ipopt_cost;
    std::snprintf(line, sizeof line, " %.2e%s |\n", rel,
                  rel < -1e-8  ? " (ours cheaper)"
                  : rel > 1e-8 ? " (**IPOPT cheaper**)"
                               : "");
    md << line;
  } else {
    md << " – |\n";
  }
}

/// `text` to `out_path`, or to stdout if it is empty; false if it cannot be written.
bool writeText(const std::string& text, const std::string& out_path) {
  if (out_path.empty()) {
    std::cout << text;
    return true;
  }
  std::ofstream out(out_path);
  out << text;
  if (!out) std::cerr << "benchmark_solvers: cannot write " << out_path << "\n";
  return static_cast<bool>(out);
}

/// Runs `count` cases of the suite seeded `seed` (runSuiteCase). Writes a markdown section to
/// `out_path` (stdout if empty); one JSON line per case to stderr.
int randomSuite(int count, std::uint64_t seed, double time_budget, const std::string& out_path,
                const std::vector<int>& only_cases) {
  std::vector<SuiteRow> rows;
  const auto wall_start = std::chrono::steady_clock::now();
  for (const ap::robustness::RandomCase& c : ap::robustness::randomSuite(seed, count)) {
    const bool chosen = only_cases.empty() || std::find(only_cases.begin(), only_cases.end(),
                                                        c.index) != only_cases.end();
    if (chosen) rows.push_back(runSuiteCase(c, time_budget));
  }
  const double wall =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  std::ostringstream md;
  writeSuiteIntro(md, count, seed, time_budget, wall);
  writeSuiteFigures(md, tallySuite(rows, -1),
                    tallySuite(rows, static_cast<int>(ap::SchemeKind::Paper)),
                    tallySuite(rows, static_cast<int>(ap::SchemeKind::Variational)));
  writeSuiteTargets(md, tallySuite(rows, -1),
                    tallySuite(rows, static_cast<int>(ap::SchemeKind::Paper)));
  md << "<details><summary>Every case</summary>\n\n"
     << "| # | inertia | scheme | T [s] | N | \\|Ω_0\\| | \\|Ω_{N−1}\\| | ours | it | time [s] | "
        "cost | replay miss [rad] | IPOPT | it | time [s] | cost | (ours − IPOPT)/IPOPT |\n"
     << "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
  for (const SuiteRow& r : rows) writeSuiteCase(md, r);
  md << "\n</details>\n";
  return writeText(md.str(), out_path) ? 0 : 1;
}

/// The command line.
struct BenchmarkArgs {
  std::string solver, scene, scheme;
  bool check_hessian = false;
  bool constrained = false;
  bool wheels = false;     ///< --check-hessian --wheels
  bool free_time = false;  ///< --check-hessian --free-time
  PeerStart peer_start = PeerStart::Geodesic;
  int steps = 0;
  int suite_count = 0;
  std::uint64_t suite_seed = 19;
  std::vector<int> only_cases;
  std::string out_path;
  int in_process = 1;  // solves in this process; > 1 adds the warm median (runs 2..K)
  double time_budget = 120.0;
};

/// Parses the arguments into *args; an exit status if the program ends here (--quick, --help, a
/// usage error).
std::optional<int> parseArguments(int argc, char** argv, BenchmarkArgs* args) {
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    const auto value = [&]() -> std::string {
      if (i + 1 >= argc) {
        std::cerr << a << ": missing value\n" << kUsage;
        std::exit(2);
      }
      return argv[++i];
    };
    if (a == "--quick") return quick();
    if (a == "--help") {
      std::cout << kUsage;
      return 0;
    }
    if (a == "--solver") {
      args->solver = value();
    } else if (a == "--scene") {
      args->scene = value();
    } else if (a == "--steps") {
      args->steps = std::atoi(value().c_str());
    } else if (a == "--scheme") {
      args->scheme = value();
    } else if (a == "--check-hessian") {
      args->check_hessian = true;
    } else if (a == "--constrained") {
      args->constrained = true;
    } else if (a == "--wheels") {
      args->wheels = true;
    } else if (a == "--free-time") {
      args->free_time = true;
    } else if (a == "--start") {
      const std::string v = value();
      if (v != "geodesic" && v != "unconstrained" && v != "ours") {
        std::cerr << "--start: expected geodesic, unconstrained or ours, got '" << v << "'\n";
        return 2;
      }
      args->peer_start = v == "ours"            ? PeerStart::Ours
                         : v == "unconstrained" ? PeerStart::Unconstrained
                                                : PeerStart::Geodesic;
    } else if (a == "--time-budget") {
      args->time_budget = std::atof(value().c_str());
    } else if (a == "--random-suite") {
      args->suite_count = std::atoi(value().c_str());
      if (args->suite_count <= 0) {
        std::cerr << "--random-suite: expected a positive count, got '" << argv[i] << "'\n";
        return 1;
      }
    } else if (a == "--cases") {
      std::stringstream list(value());
      for (std::string item; std::getline(list, item, ',');)
        args->only_cases.push_back(std::atoi(item.c_str()));
    } else if (a == "--seed") {
      args->suite_seed = std::strtoull(value().c_str(), nullptr, 10);
    } else if (a == "--out") {
      args->out_path = value();
    } else if (a == "--in-process") {
      args->in_process = std::atoi(value().c_str());
    } else {
      std::cerr << "unknown argument '" << a << "'\n" << kUsage;
      return 2;
    }
  }
  return std::nullopt;
}

/// --solver minimum_time_search: the search on T over minimum-effort solves on the request as it
/// is (planManeuver answers minimum time by the free-time interior point wherever it applies).
/// Prints one JSON line: time_s, minimum_duration (the least T found feasible), status,
/// max_constraint_violation (of its plan at that T).
int searchMinimumTimeOnce(const ap::PlanningProblem& problem) {
  ap::validateProblem(problem);
  const auto start = std::chrono::steady_clock::now();
  const ap::PlanResult r = ap::searchMinimumTime(problem, ap::SolverOptions());
  const double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  std::printf(
      "{\"solver\": \"minimum_time_search\", \"scheme\": \"%s\", \"steps\": %d, "
      "\"time_s\": %.6g, \"minimum_duration\": %.17g, \"status\": \"%s\", "
      "\"max_constraint_violation\": %.6g}\n",
      ap::schemeName(problem.scheme).c_str(), problem.steps, seconds, r.minimum_duration,
      ap::terminationName(r.termination).c_str(), r.max_constraint_violation);
  return r.converged() ? 0 : 1;
}

/// One solver on one problem (--solver): prints its JSON line; the exit status.
int benchmarkOneSolver(const BenchmarkArgs& args) {
  try {
    ap::PlanningProblem problem =
        args.scene.empty() ? seedRestToRest(128) : ap::loadScene(args.scene).problem;
    if (args.steps > 0) problem.steps = args.steps;
    if (!args.scheme.empty()) problem.scheme = ap::parseScheme(args.scheme, "--scheme");
    if (args.solver == "minimum_time_search") return searchMinimumTimeOnce(problem);
    if (args.solver == "free_time" || args.solver == "ipopt_free_time") {
#ifdef AP_HAVE_IPOPT  // the two share the peer's start (excursionStart)
      if (args.solver == "ipopt_free_time") return solveIpoptFreeTime(problem, args.time_budget);
      problem.scheme = ap::SchemeKind::Paper;
      return solveOursFreeTime(problem);
#else
      std::cerr << "benchmark_solvers: " << args.solver << ": this build has no IPOPT\n";
      return 3;
#endif
    }
    Measurement m = run(args.solver, problem, args.time_budget, args.peer_start);
    if (args.in_process > 1) {
      // Warm solves, as a node serving requests sees them (caches, pages, lazy binding warm):
      // reported apart from time_s, which stays the first, cold solve of a fresh process.
      std::vector<double> warm;
      for (int r = 1; r < args.in_process; ++r)
        warm.push_back(run(args.solver, problem, args.time_budget, args.peer_start).time_s);
      std::sort(warm.begin(), warm.end());
      m.warm_time_s = warm[warm.size() / 2];
      m.warm_min_time_s = warm.front();
    }
    printJson(m);
  } catch (const std::exception& e) {
    std::cerr << "benchmark_solvers: " << e.what() << "\n";
    return 1;
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  BenchmarkArgs args;
  if (const std::optional<int> status = parseArguments(argc, argv, &args)) return *status;
  if (args.check_hessian) {
#ifdef AP_HAVE_IPOPT
    if (args.free_time) {
      return checkFreeTimeJacobian(args.steps > 0 ? args.steps : 16, args.constrained, args.wheels);
    }
    return checkHessian(args.steps > 0 ? args.steps : 16, args.constrained, args.wheels);
#else
    std::cerr << "benchmark_solvers: --check-hessian: this build has no IPOPT "
                 "(install coinor-libipopt-dev)\n";
    return 3;
#endif
  }
  if (args.suite_count > 0) {
    return randomSuite(args.suite_count, args.suite_seed, args.time_budget, args.out_path,
                       args.only_cases);
  }
  if (args.solver.empty()) {
    std::cerr << kUsage;
    return 2;
  }
  return benchmarkOneSolver(args);
}
