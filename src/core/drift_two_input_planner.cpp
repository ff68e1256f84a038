// Shooting for the drift + two-input BVP (seed 001, (3.8)–(3.10)); see the header.
#include "attitude_planner/drift_two_input_planner.hpp"

#include <Eigen/LU>
#include <Eigen/QR>
#include <cmath>
#include <sstream>
#include <vector>

#include "attitude_planner/dual.hpp"
#include "attitude_planner/errors.hpp"

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

// Newton with backtracking on ½|r|² for one target; updates p and counts iterations.
// Returns true when |r| ≤ tol.
bool newtonSolve(const DriftTwoInputRequest& rq, const Matrix3& target, int n_steps, double tol,
                 int max_iterations, Vector3& p, int& iterations, double& error) {
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
