#include "planning/problem/duration_bound.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/SVD>
#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include "attitude_planner/errors.hpp"
#include "attitude_planner/lie/so3.hpp"

namespace attitude_planner {

namespace {

/// The least rate limit w (+∞: none).
double smallestRateLimit(const PlanningProblem& problem) {
  double w = std::numeric_limits<double>::infinity();
  for (const PlanningConstraint& c : problem.constraints) {
    if (c.kind == ConstraintKind::MaxAngularRate) w = std::min(w, c.limit);
  }
  return w;
}

/// The data of g(T): ∫₀ᵀ min(w, min(p0 + a t, pT + a (T − t)) / λ) dt.
struct PathLengthBound {
  double a, w, lambda, p0, pT;

  /// Midpoint rule on a concave integrand: never below the integral, so the T it gives stays a
  /// lower bound.
  double operator()(double T) const {
    constexpr int kPanels = 4096;
    const double dt = T / kPanels;
    double sum = 0.0;
    for (int i = 0; i < kPanels; ++i) {
      const double t = (i + 0.5) * dt;
      const double momentum = std::min(p0 + a * t, pT + a * (T - t));
      sum += std::min(w, momentum / lambda);
    }
    return sum * dt;
  }
};

/// The least T with g(T) ≥ θ (bisection on the increasing g), or 0 for θ = 0.
double leastDurationForAngle(const PathLengthBound& g, double theta) {
  if (!(theta > 0.0)) return 0.0;
  double lo = 0.0, hi = 1.0;
  // g(T) ≥ T·min(w, max(p0, pT)/λ) grows at least linearly once the rates are bounded away
  // from 0, and like T² from rest: doubling reaches θ in a few dozen steps at any scale.
  for (int i = 0; i < 4000 && std::isfinite(hi) && g(hi) < theta; ++i) {
    lo = hi;
    hi *= 2.0;
  }
  for (int i = 0; i < 200 && hi - lo > 1e-15 * hi; ++i) {
    const double mid = 0.5 * (lo + hi);
    (g(mid) >= theta ? hi : lo) = mid;
  }
  return lo;
}

}  // namespace

TorqueAuthority torqueAuthority(const PlanningProblem& problem) {
  constexpr double kUnbounded = std::numeric_limits<double>::infinity();
  TorqueAuthority authority{kUnbounded, kUnbounded};
  if (problem.hasTorqueBounds()) {
    authority.largest_magnitude = problem.max_torque.norm();
    authority.smallest_about_any_axis = problem.max_torque.minCoeff();
  }
  const ReactionWheels& wheels = problem.reaction_wheels;
  if (wheels.present()) {
    // About every axis the array makes at least σ_min(A) min U_i (a guess's figure only: the
    // body torque −A u − Ω × A h_w has no bound from the wheels' limits alone, so
    // largest_magnitude, which the proof of T_c needs, is left to the body-torque bounds).
    const WheelArray array = wheelArray(wheels);
    double least = std::numeric_limits<double>::infinity();
    for (int i = 0; i < wheels.count(); ++i) least = std::min(least, wheels.torqueLimit(i));
    const double sigma = Eigen::JacobiSVD<Eigen::MatrixXd>(array.axes).singularValues().minCoeff();
    authority.smallest_about_any_axis = std::min(authority.smallest_about_any_axis, sigma * least);
  }
  for (const PlanningConstraint& c : problem.constraints) {
    if (c.kind != ConstraintKind::MaxTorqueNorm) continue;
    authority.largest_magnitude = std::min(authority.largest_magnitude, c.limit);
    authority.smallest_about_any_axis = std::min(authority.smallest_about_any_axis, c.limit);
  }
  return authority;
}

DurationLowerBound durationLowerBound(const PlanningProblem& problem) {
  DurationLowerBound bound;
  if (problem.effects && !problem.effects->empty()) return bound;
  const double a = torqueAuthority(problem).largest_magnitude, w = smallestRateLimit(problem);
  if (!std::isfinite(a) && !std::isfinite(w)) return bound;
  const double lambda =
      Eigen::SelfAdjointEigenSolver<Matrix3>(problem.inertia).eigenvalues().minCoeff();
  const Vector3 pi0 = problem.initial_attitude * problem.inertia * problem.initial_velocity;
  const Vector3 piT = problem.final_attitude * problem.inertia * problem.final_velocity;
  double theta = so3::angleBetween(problem.initial_attitude, problem.final_attitude);
  double momentum_change = (piT - pi0).norm();
  if (problem.end_condition.pointing()) {
    // R_N is any R_N(ψ): every one turns R_0 b onto d (at least their angle), and |R_N JΩ(T)| is
    // the same for every ψ (the change at least the difference of the norms).
    const Vector3 from = problem.initial_attitude * problem.end_condition.body_axis.normalized();
    const Vector3 to = problem.end_condition.world_direction.normalized();
    theta = std::atan2(from.cross(to).norm(), from.dot(to));
    momentum_change = std::abs(piT.norm() - pi0.norm());
  }
  const PathLengthBound g{a, w, lambda, pi0.norm(), piT.norm()};
  const double for_angle = leastDurationForAngle(g, theta);
  const double for_momentum = std::isfinite(a) ? momentum_change / a : 0.0;
  bound.seconds = std::max(for_angle, for_momentum);
  if (!(bound.seconds > 0.0)) return bound;
  bound.rate_limit = std::isfinite(w) ? w : 0.0;
  bound.torque_limit = std::isfinite(a) ? a : 0.0;
  std::ostringstream basis;
  basis << "proven: ";
  if (std::isfinite(a)) {
    basis << "the spatial momentum R J Omega changes at most at the rate " << exactNumber(a)
          << " N m the torque bounds allow, the rate |Omega| is at most |R J Omega| / "
          << exactNumber(lambda) << " kg m^2 (the least principal moment)";
  }
  if (std::isfinite(w)) {
    basis << (std::isfinite(a) ? " and " : "the rate |Omega| is at most ") << exactNumber(w)
          << " rad/s";
  }
  basis << ", and the body must turn " << exactNumber(theta) << " rad"
        << (for_momentum > for_angle
                ? " and change its momentum by " + exactNumber(momentum_change) + " N m s"
                : "");
  bound.basis = basis.str();
  return bound;
}

double discreteDurationLowerBound(const DurationLowerBound& bound, int steps) {
  return bound.seconds / (1.0 + kDiscreteMargin / std::max(steps, 1));
}

double discreteDurationLowerBound(const PlanningProblem& problem) {
  return discreteDurationLowerBound(durationLowerBound(problem), problem.steps);
}

}  // namespace attitude_planner
