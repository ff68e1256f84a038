#include "support/pointing_requests.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <stdexcept>

#include "attitude_planner/lie/so3.hpp"
#include "attitude_planner/planning/constraints.hpp"
#include "attitude_planner/planning/pointing.hpp"

namespace attitude_planner::test_support {

namespace {
Vector3 randomUnit(std::mt19937& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  return Vector3(n(rng), n(rng), n(rng)).normalized();
}
}  // namespace

PlanningProblem randomPointingRequest(unsigned seed, int steps, bool spinning, SchemeKind scheme) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  PlanningProblem p;
  const Vector3 moments(1.0 + u(rng), 1.0 + u(rng), 1.0 + u(rng));
  const Matrix3 Q = so3::exp(Vector3(3.0 * randomUnit(rng)));
  const Matrix3 J = Q * moments.asDiagonal() * Q.transpose();
  p.inertia = 0.5 * (J + J.transpose());
  p.duration = 8.0 + 4.0 * u(rng);
  p.steps = steps;
  p.scheme = scheme;
  p.initial_attitude = so3::exp(Vector3(3.0 * u(rng) * randomUnit(rng)));
  if (spinning) {
    p.initial_velocity = 0.2 * randomUnit(rng);
    p.final_velocity = 0.1 * randomUnit(rng);
  }
  p.end_condition.kind = EndConditionKind::Pointing;
  p.end_condition.body_axis = randomUnit(rng);
  p.end_condition.world_direction = randomUnit(rng);
  return p;
}

PlanningProblem randomConstrainedPointingRequest(unsigned seed, int steps, bool spinning,
                                                 SchemeKind scheme, PointingBinding binding) {
  if (binding != PointingBinding::KeepOut) {
    PlanningProblem p = randomPointingRequest(seed, steps, spinning, scheme);
    const PlanResult free = planManeuver(p);
    if (!free.converged()) throw std::runtime_error("unconstrained pointing: " + free.message());
    Vector3 largest = Vector3::Zero();
    for (const Vector3& tau : free.maneuver.torque) largest = largest.cwiseMax(tau.cwiseAbs());
    double largest_norm = 0.0;
    for (const Vector3& tau : free.maneuver.torque)
      largest_norm = std::max(largest_norm, tau.norm());
    if (binding == PointingBinding::TorqueBox) p.max_torque = 0.7 * largest;
    if (binding == PointingBinding::TorqueNorm) {
      p.constraints.push_back(PlanningConstraint::maxTorqueNorm(0.7 * largest_norm));
    }
    return p;
  }
  for (unsigned attempt = 0;; ++attempt) {
    PlanningProblem p = randomPointingRequest(seed + 1000 * attempt, steps, spinning, scheme);
    const Vector3 b = p.end_condition.body_axis, d = p.end_condition.world_direction;
    const Vector3 start = p.initial_attitude * b;
    const double angle = std::atan2(start.cross(d).norm(), start.dot(d));
    if (angle < 0.8 || angle > 2.6) continue;
    const Vector3 between = (start + d).normalized();
    p.constraints.push_back(PlanningConstraint::keepOut(b, between, 0.35 * angle));
    return p;
  }
}

PlanningProblem randomBettsPointingRequest(unsigned seed, int steps, SchemeKind scheme) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  PlanningProblem p;
  p.inertia = Vector3(5621.0, 4547.0, 2364.0).asDiagonal();
  p.max_torque = Vector3::Constant(50.0);
  p.objective = Objective::MinimumTime;
  p.duration = 0.0;
  p.steps = steps;
  p.scheme = scheme;
  p.initial_attitude = so3::exp(Vector3(3.0 * u(rng) * randomUnit(rng)));
  p.end_condition.kind = EndConditionKind::Pointing;
  p.end_condition.body_axis = randomUnit(rng);
  p.end_condition.world_direction = randomUnit(rng);
  return p;
}

PlanningProblem randomBettsConstrainedPointingRequest(unsigned seed, int steps, SchemeKind scheme) {
  for (unsigned attempt = 0;; ++attempt) {
    PlanningProblem p = randomBettsPointingRequest(seed + 1000 * attempt, steps, scheme);
    const Vector3 b = p.end_condition.body_axis, d = p.end_condition.world_direction;
    const Vector3 start = p.initial_attitude * b;
    const double angle = std::atan2(start.cross(d).norm(), start.dot(d));
    if (angle < 0.8 || angle > 2.6) continue;
    const PlanResult free = planManeuver(p);
    if (!free.converged()) throw std::runtime_error("pointing minimum time: " + free.message());
    double fastest = 0.0;
    for (const Vector3& w : free.maneuver.angular_velocity) fastest = std::max(fastest, w.norm());
    p.constraints.push_back(PlanningConstraint::keepOut(b, (start + d).normalized(), 0.35 * angle));
    p.constraints.push_back(PlanningConstraint::maxAngularRate(0.7 * fastest));
    return p;
  }
}

TwistSweep sweepTwist(const PlanningProblem& pointing) {
  PlanningProblem fixed = pointing;
  fixed.end_condition = EndCondition();
  const auto cost = [&](double twist) {
    fixed.final_attitude = pointingAttitude(pointing.end_condition, twist);
    for (const PlanningConstraint& c : fixed.constraints) {
      if (c.isCone() && coneMargin(c, fixed.final_attitude) < 0.0) {
        return std::numeric_limits<double>::infinity();  // no plan ends there
      }
    }
    const PlanResult r = planManeuver(fixed);
    if (!r.converged()) return std::numeric_limits<double>::infinity();
    return pointing.objective == Objective::MinimumTime ? r.minimum_duration : r.cost;
  };
  TwistSweep s;
  const double step = 5.0 * M_PI / 180.0;
  s.best = std::numeric_limits<double>::infinity();
  for (int k = 0; k < 72; ++k) {
    const double c = cost(k * step);
    s.twists.push_back(k * step);
    s.costs.push_back(std::isfinite(c) ? c : std::numeric_limits<double>::quiet_NaN());
    if (c < s.best) s.best = c, s.best_twist = k * step;
    if (std::isfinite(c)) s.worst = std::max(s.worst, c);
  }
  // Golden section on the bracket around the best sample.
  const double ratio = (std::sqrt(5.0) - 1.0) / 2.0;
  double a = s.best_twist - step, b = s.best_twist + step;
  double x1 = b - ratio * (b - a), x2 = a + ratio * (b - a), f1 = cost(x1), f2 = cost(x2);
  while (b - a > 1e-7) {
    if (f1 < f2) {
      b = x2, x2 = x1, f2 = f1, x1 = b - ratio * (b - a), f1 = cost(x1);
    } else {
      a = x1, x1 = x2, f1 = f2, x2 = a + ratio * (b - a), f2 = cost(x2);
    }
  }
  if (std::min(f1, f2) < s.best) {
    s.best = std::min(f1, f2);
    s.best_twist = f1 < f2 ? x1 : x2;
  }
  return s;
}

}  // namespace attitude_planner::test_support
