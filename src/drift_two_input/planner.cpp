// Shooting for the drift + two-input BVP (seed 001, (3.8)–(3.10)); see the header.
#include "attitude_planner/drift_two_input/planner.hpp"

#include <Eigen/LU>
#include <Eigen/QR>
#include <cmath>
#include <sstream>
#include <vector>

#include "attitude_planner/errors.hpp"
#include "lie/dual.hpp"

namespace attitude_planner {

namespace {

// g(T) and p(T) from (g0, p0) by n_steps steps of the given order, in scalar type S.
template <typename S>
so3::Mat3<S> shootEndpoint(const Matrix3& g0, so3::Vec3<S> p, double T, int n_steps, int order,
                           const DriftTwoInputWeights& w) {
  so3::Mat3<S> g = g0.cast<S>();
  const double h = T / n_steps;
  for (int k = 0; k < n_steps; ++k) {
    if (!drift_two_input::stepOfOrder<S>(g, p, h, w, order)) {
      std::ostringstream os;
      os << "implicit step " << k << " (h = " << h << " s) did not converge during shooting";
      throw StepTooLarge(os.str());
    }
  }
  return g;
}

}  // namespace

void driftTwoInputShootingResidual(const Matrix3& g0, const Matrix3& g1, double T, int n_steps,
                                   int order, const DriftTwoInputWeights& w, const Vector3& p0,
                                   Vector3* residual, Matrix3* jacobian) {
  if (!jacobian) {  // value only: plain doubles, several times cheaper than Dual<3>
    const Matrix3 g = shootEndpoint<double>(g0, p0, T, n_steps, order, w);
    *residual = so3::log(Matrix3(g1.transpose() * g));
    return;
  }
  using D = Dual<3>;
  const so3::Vec3<D> p(D(p0.x(), 0), D(p0.y(), 1), D(p0.z(), 2));  // seed the three directions
  const so3::Mat3<D> g = shootEndpoint<D>(g0, p, T, n_steps, order, w);
  const so3::Vec3<D> r = so3::log<D>(so3::Mat3<D>(g1.cast<D>().transpose() * g));
  for (int i = 0; i < 3; ++i) {
    (*residual)(i) = r(i).v;
    jacobian->row(i) = r(i).d.transpose();
  }
}

namespace {

void validate(const DriftTwoInputRequest& rq) {
  validateDriftTwoInputWeights(rq.weights);
  auto fail = [](const std::string& field, double value, const std::string& why) {
    std::ostringstream os;
    os << field << " " << why << ", got " << value;
    throw InvalidInput(os.str());
  };
  if (!std::isfinite(rq.duration) || rq.duration <= 0) fail("duration", rq.duration, "must be > 0");
  if (rq.steps < 1) fail("steps", rq.steps, "must be >= 1");
  if (!std::isfinite(rq.max_step) || rq.max_step <= 0) fail("max_step", rq.max_step, "must be > 0");
  if (!(rq.tolerance > 0)) fail("tolerance", rq.tolerance, "must be > 0");
  if (rq.max_iterations < 1) fail("max_iterations", rq.max_iterations, "must be >= 1");
  if (rq.shooting_intervals < 1 || rq.shooting_intervals > rq.steps) {
    fail("shooting_intervals", rq.shooting_intervals, "must be in [1, steps]");
  }
  if (rq.max_continuation_stages < 1) {
    fail("max_continuation_stages", rq.max_continuation_stages, "must be >= 1");
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

constexpr int kOrder = 4;  // triple-jump composition of the midpoint scheme

// Multiple shooting (for long horizons, where the sensitivity of g(T) to p(0) grows): the
// n_steps steps are split into M intervals [k_j, k_{j+1}); unknowns are p(0) and, at the inner
// nodes, (g_j, p_j) with g_j updated on the group (ĝ_j exp(δ_j)). Equations: continuity of g and
// p at each inner node and log(targetᵀ g_end) = 0 at T, 6(M−1) + 3 in all, Newton with exact
// block Jacobians (Dual<9> over δ_j, p_j, δ_{j+1}) and backtracking on the residual norm.
// Returns true when the residual norm ≤ tol; p holds p(0).
bool multipleShootingSolve(const DriftTwoInputRequest& rq, const Matrix3& target, int n_steps,
                           int M, double tol, int max_iterations, Vector3& p, int& iterations,
                           double& error) {
  const double h = rq.duration / n_steps;
  std::vector<int> k(M + 1);
  for (int j = 0; j <= M; ++j) k[j] = static_cast<int>(std::llround(double(j) * n_steps / M));
  const int n = 6 * (M - 1) + 3;
  std::vector<Matrix3> G(M);
  std::vector<Vector3> P(M);
  // initial nodes on the single-shooting trajectory from p
  {
    Matrix3 g = rq.g0;
    Vector3 q = p;
    for (int j = 0; j < M; ++j) {
      G[j] = g;
      P[j] = q;
      for (int i = k[j]; i < k[j + 1]; ++i) {
        if (!drift_two_input::stepOfOrder<double>(g, q, h, rq.weights, kOrder)) {
          error = INFINITY;
          return false;
        }
      }
    }
  }
  G[0] = rq.g0;
  using D = Dual<9>;
  // residual (and, if J, Jacobian) of the whole system at nodes (G, P)
  auto evaluate = [&](const std::vector<Matrix3>& Gs, const std::vector<Vector3>& Ps,
                      Eigen::VectorXd& F, Eigen::MatrixXd* J) -> bool {
    F.setZero(n);
    if (J) J->setZero(n, n);
    for (int j = 0; j < M; ++j) {
      const bool last = j == M - 1;
      const int row = 6 * j;
      const int col_p = j == 0 ? 0 : 3 + 6 * (j - 1) + 3, col_d = 3 + 6 * (j - 1);
      const int col_dn = 3 + 6 * j;  // δ_{j+1}
      if (!J) {
        Matrix3 g = Gs[j];
        Vector3 q = Ps[j];
        for (int i = k[j]; i < k[j + 1]; ++i) {
          if (!drift_two_input::stepOfOrder<double>(g, q, h, rq.weights, kOrder)) return false;
        }
        const Matrix3& next = last ? target : Gs[j + 1];
        F.segment<3>(row) = so3::log(Matrix3(next.transpose() * g));
        if (!last) F.segment<3>(row + 3) = q - Ps[j + 1];
        continue;
      }
      so3::Vec3<D> d0, q, dn;
      for (int i = 0; i < 3; ++i) {
        d0(i) = D(0.0, i);
        q(i) = D(Ps[j](i), 3 + i);
        dn(i) = D(0.0, 6 + i);
      }
      so3::Mat3<D> g = Gs[j].cast<D>() * so3::exp<D>(d0);
      for (int i = k[j]; i < k[j + 1]; ++i) {
        if (!drift_two_input::stepOfOrder<D>(g, q, h, rq.weights, kOrder)) return false;
      }
      const so3::Mat3<D> next = last ? so3::Mat3<D>(target.cast<D>())
                                     : so3::Mat3<D>(Gs[j + 1].cast<D>() * so3::exp<D>(dn));
      const so3::Vec3<D> rg = so3::log<D>(so3::Mat3<D>(next.transpose() * g));
      for (int i = 0; i < 3; ++i) {
        F(row + i) = rg(i).v;
        if (j > 0) J->block<1, 3>(row + i, col_d) = rg(i).d.segment<3>(0).transpose();
        J->block<1, 3>(row + i, col_p) = rg(i).d.segment<3>(3).transpose();
        if (!last) J->block<1, 3>(row + i, col_dn) = rg(i).d.segment<3>(6).transpose();
        if (last) continue;
        F(row + 3 + i) = q(i).v - Ps[j + 1](i);
        if (j > 0) J->block<1, 3>(row + 3 + i, col_d) = q(i).d.segment<3>(0).transpose();
        J->block<1, 3>(row + 3 + i, col_p) = q(i).d.segment<3>(3).transpose();
        (*J)(row + 3 + i, col_dn + 3 + i) = -1.0;  // ∂(q_end − p_{j+1})/∂p_{j+1}
      }
    }
    return true;
  };
  auto retract = [&](const Eigen::VectorXd& dx, double a, std::vector<Matrix3>& Gs,
                     std::vector<Vector3>& Ps) {
    Gs = G;
    Ps = P;
    Ps[0] += a * dx.segment<3>(0);
    for (int j = 1; j < M; ++j) {
      Gs[j] = G[j] * so3::exp(Vector3(a * dx.segment<3>(3 + 6 * (j - 1))));
      Ps[j] += a * dx.segment<3>(3 + 6 * (j - 1) + 3);
    }
  };
  Eigen::VectorXd F;
  Eigen::MatrixXd J;
  if (!evaluate(G, P, F, &J)) {
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
      std::vector<Matrix3> Gs;
      std::vector<Vector3> Ps;
      retract(dx, a, Gs, Ps);
      Eigen::VectorXd Ft;
      if (!evaluate(Gs, Ps, Ft, nullptr)) continue;
      if (Ft.norm() <= (1.0 - 1e-4 * a) * error || (Ft.norm() <= 1e-13 && Ft.norm() <= error)) {
        G = Gs;
        P = Ps;
        error = Ft.norm();
        accepted = true;
        break;
      }
    }
    if (!accepted || error <= tol) break;
    if (!evaluate(G, P, F, &J)) break;
  }
  p = P[0];
  return error <= tol;
}

// Newton with backtracking on ½|r|² for one target; updates p and counts iterations.
// Returns true when |r| ≤ tol.
bool newtonSolve(const DriftTwoInputRequest& rq, const Matrix3& target, int n_steps, double tol,
                 int max_iterations, Vector3& p, int& iterations, double& error) {
  if (rq.shooting_intervals > 1) {
    // Multiple shooting finds p(0); a few single-shooting Newton steps then polish it against
    // the one-piece integration that produces the output (the node residuals are amplified by
    // the sensitivity of g(T) to p(0) when the pieces are joined).
    const bool ms_ok = multipleShootingSolve(rq, target, n_steps, rq.shooting_intervals, tol,
                                             max_iterations, p, iterations, error);
    if (!ms_ok && !(error <= 1e-6)) return false;
    max_iterations = 5;
  }
  Vector3 r;
  Matrix3 J;
  try {
    driftTwoInputShootingResidual(rq.g0, target, rq.duration, n_steps, kOrder, rq.weights, p, &r,
                                  &J);
  } catch (const StepTooLarge&) {
    error = INFINITY;
    return false;
  }
  error = r.norm();
  while (error > tol && max_iterations-- > 0) {
    ++iterations;
    Eigen::FullPivLU<Matrix3> lu(J);
    if (!lu.isInvertible()) return false;  // singular: conjugate point or abnormal direction
    const Vector3 dp = -lu.solve(r);
    double step = 1.0;
    bool accepted = false;
    for (int ls = 0; ls < 30; ++ls, step *= 0.5) {
      const Vector3 trial = p + step * dp;
      Vector3 rt;
      try {
        driftTwoInputShootingResidual(rq.g0, target, rq.duration, n_steps, kOrder, rq.weights,
                                      trial, &rt, nullptr);
      } catch (const StepTooLarge&) {
        continue;  // too large a costate for the step: shorten
      }
      // Armijo on |r|; at round-off level accept any non-increase (the last digits are noise)
      if (rt.norm() <= (1.0 - 1e-4 * step) * error || (rt.norm() <= 1e-13 && rt.norm() <= error)) {
        p = trial;
        error = rt.norm();
        accepted = true;
        break;
      }
    }
    if (!accepted || error <= tol) break;
    try {  // Jacobian at the accepted point (the residual's value is recomputed, identical)
      driftTwoInputShootingResidual(rq.g0, target, rq.duration, n_steps, kOrder, rq.weights, p, &r,
                                    &J);
    } catch (const StepTooLarge&) {
      break;
    }
  }
  return error <= tol;
}

std::string vec(const Vector3& v) {
  std::ostringstream os;
  os.precision(10);
  os << "(" << v.x() << ", " << v.y() << ", " << v.z() << ")";
  return os.str();
}

struct Attempt {
  bool ok = false;
  Vector3 p = Vector3::Zero();
  double error = INFINITY;
  int iterations = 0, stages = 0;
  std::string how;
};

// Newton from `start`; if that fails, continuation on the target: g(λ) = g_a exp(λ log(g_aᵀ g1)),
// g_a the endpoint reached from `start`, λ from 0 to 1 with adaptive increments. Intermediate
// targets are solved loosely (1e-8 rad); only g1 itself to the requested tolerance.
Attempt solveFrom(const DriftTwoInputRequest& rq, int n_steps, const Vector3& start, int budget) {
  Attempt a;
  a.p = start;
  a.ok = newtonSolve(rq, rq.g1, n_steps, rq.tolerance, budget, a.p, a.iterations, a.error);
  a.stages = 1;
  a.how = "direct Newton solve";
  if (a.ok) return a;
  Vector3 p = start, r0;
  try {
    driftTwoInputShootingResidual(rq.g0, rq.g1, rq.duration, n_steps, kOrder, rq.weights, p, &r0,
                                  nullptr);
  } catch (const StepTooLarge&) {
    return a;
  }
  const Matrix3 g_a = rq.g1 * so3::exp(r0);  // endpoint reached from the start
  const Vector3 path = so3::log(Matrix3(g_a.transpose() * rq.g1));
  double lambda = 0.0, dl = 0.25;
  int stages = 0;
  while (lambda < 1.0 && stages < rq.max_continuation_stages && a.iterations < budget &&
         dl > 1e-6) {
    const double next = std::min(1.0, lambda + dl);
    const Matrix3 target = g_a * so3::exp(Vector3(next * path));
    Vector3 trial = p;
    double e = INFINITY;
    ++stages;
    if (newtonSolve(rq, target, n_steps, next == 1.0 ? rq.tolerance : 1e-8,
                    std::min(20, budget - a.iterations), trial, a.iterations, e)) {
      p = trial;
      lambda = next;
      dl *= 2;
      if (next == 1.0) a.error = e;
    } else {
      dl *= 0.5;
    }
  }
  a.stages = 1 + stages;
  if (lambda == 1.0) {
    a.ok = true;
    a.p = p;
  }
  a.how =
      "direct solve failed; continuation on the target over " + std::to_string(stages) + " targets";
  return a;
}

// Default starts when the request has no guess. At p1 = p2 = 0 the shooting Jacobian is singular
// (p3 then only sets the rotation rate of a zero (p1, p2)), so u ≡ 0 is a bad start. For a few
// values of p3 take (p1, p2) from the least-squares solution of the shooting equation
// linearized at (0, 0, p3): r + J[:, 0:2] (p1, p2) = 0.
std::vector<Vector3> defaultStarts(const DriftTwoInputRequest& rq, int n_steps) {
  const double c = 0.5 * (rq.weights.c1 + rq.weights.c2);
  std::vector<Vector3> starts;
  for (double p3 : {0.0, c, -c, 0.5 * c, 2.0 * c}) {
    Vector3 r;
    Matrix3 J;
    try {
      driftTwoInputShootingResidual(rq.g0, rq.g1, rq.duration, n_steps, kOrder, rq.weights,
                                    Vector3(0, 0, p3), &r, &J);
    } catch (const StepTooLarge&) {
      continue;
    }
    const Eigen::Matrix<double, 3, 2> B = J.leftCols<2>();
    const Eigen::Vector2d q = B.completeOrthogonalDecomposition().solve(-r);
    starts.emplace_back(q.x(), q.y(), p3);
  }
  return starts;
}

}  // namespace

DriftTwoInputPlan planDriftTwoInput(const DriftTwoInputRequest& rq) {
  validate(rq);
  DriftTwoInputPlan plan;
  const double dt = rq.duration / rq.steps;
  plan.substeps = std::max(1, static_cast<int>(std::ceil(dt / rq.max_step - 1e-12)));
  const int n_steps = rq.steps * plan.substeps;
  DriftTwoInputIntegration opts;
  opts.substeps = plan.substeps;
  opts.order = kOrder;

  // With a guess: solve from it. Without: solve from each default start and keep the converged
  // extremal of least cost (non-uniqueness: different starts may find different extremals).
  std::vector<Vector3> starts;
  if (rq.initial_costate) {
    starts.push_back(*rq.initial_costate);
  } else {
    starts = defaultStarts(rq, n_steps);
    if (starts.empty()) starts.push_back(Vector3(0.1, 0.1, 0.0));
  }
  const int budget = std::max(1, rq.max_iterations / static_cast<int>(starts.size()));
  Attempt best;
  double best_cost = INFINITY;
  int iterations = 0, converged_starts = 0;
  for (const Vector3& start : starts) {
    Attempt a = solveFrom(rq, n_steps, start, budget);
    iterations += a.iterations;
    double cost = INFINITY;
    if (a.ok) {
      ++converged_starts;
      try {
        cost = integrateDriftTwoInputExtremal(rq.g0, a.p, rq.duration, rq.steps, rq.weights, opts)
                   .cost;
      } catch (const StepTooLarge&) {
        a.ok = false;
      }
    }
    const bool better =
        (a.ok && (!best.ok || cost < best_cost)) || (!best.ok && a.error < best.error);
    if (better) {
      best = a;
      best_cost = cost;
    }
  }
  const Vector3 p = best.p;
  const bool ok = best.ok;
  plan.continuation_stages = best.stages;
  std::string how = best.how;
  if (rq.shooting_intervals > 1) {
    how = "multiple shooting on " + std::to_string(rq.shooting_intervals) + " intervals, " + how;
  }
  if (starts.size() > 1) {
    how += "; best of " + std::to_string(starts.size()) + " default starts, " +
           std::to_string(converged_starts) + " converged";
  }

  plan.iterations = iterations;
  plan.initial_costate = p;
  std::ostringstream os;
  try {
    plan.trajectory =
        integrateDriftTwoInputExtremal(rq.g0, p, rq.duration, rq.steps, rq.weights, opts);
    plan.cost = plan.trajectory.cost;
    plan.terminal_error = so3::angleBetween(rq.g1, plan.trajectory.g.back());
  } catch (const StepTooLarge& e) {
    plan.converged = false;
    plan.terminal_error = INFINITY;
    plan.message = std::string("extremal could not be integrated: ") + e.what();
    return plan;
  }
  plan.converged = ok && plan.terminal_error <= rq.tolerance;
  os.precision(6);
  if (plan.converged) {
    os << "converged (" << how << ", " << iterations
       << " iterations): extremal with p(0) = " << vec(p) << ", cost " << plan.cost
       << ", terminal error " << plan.terminal_error << " rad";
  } else {
    os << "not converged after " << iterations << " iterations (" << how
       << "): best p(0) = " << vec(p) << ", terminal error " << plan.terminal_error
       << " rad; try another initial_costate, a smaller max_step or a shorter duration";
  }
  plan.message = os.str();
  return plan;
}

}  // namespace attitude_planner
