#include "planning/drivers/bounded_verdicts.hpp"

#include <cmath>
#include <optional>
#include <sstream>

#include "attitude_planner/dynamics/effects.hpp"
#include "attitude_planner/errors.hpp"
#include "attitude_planner/lie/so3.hpp"
#include "attitude_planner/planning/constraints.hpp"
#include "attitude_planner/planning/pointing.hpp"
#include "planning/problem/message_notes.hpp"

namespace attitude_planner {

namespace {

/// The body at rest at R_0 for the request's N steps over `T` (zero torques and rates).
Maneuver restingPlan(const PlanningProblem& problem, double T) {
  Maneuver plan;
  const int N = problem.steps;
  plan.time_step = T / N;
  for (int k = 0; k <= N; ++k) {
    plan.time.push_back(k * plan.time_step);
    plan.attitude.push_back(problem.initial_attitude);
    plan.angular_velocity.push_back(Vector3::Zero());
    plan.torque.push_back(Vector3::Zero());
  }
  return plan;
}

bool identicalRestStates(const PlanningProblem& problem) {
  // A pointing end is reached where R_0 b = d (its final_attitude is no datum of the request).
  const bool there =
      problem.end_condition.pointing()
          ? pointingError(problem.initial_attitude, problem.end_condition) == 0.0
          : so3::angleBetween(problem.initial_attitude, problem.final_attitude) == 0.0;
  return problem.initial_velocity.isZero(0.0) && problem.final_velocity.isZero(0.0) && there &&
         problem.direction == RotationDirection::Shortest && problem.extra_revolutions == 0 &&
         (!problem.effects || problem.effects->empty());
}

/// Minimum time between identical rest states: T* = 0, the body is already there; the plan at
/// (1 + margin) T* = 0 s is the body at rest (every node at t = 0, zero torques).
PlanResult alreadyThere(const PlanningProblem& problem) {
  PlanResult r;
  r.termination = Termination::Converged;
  r.scheme = problem.scheme;
  r.solver = solverName(SolverKind::Structured);
  r.maneuver = restingPlan(problem, 0.0);
  r.duration = 0.0;
  r.minimum_duration = 0.0;
  recordVerdict(&r, verdicts::AlreadyAtRest{});
  return r;
}

/// "actuator_limits [0.1, 0.1, 0.1] N m, max_angular_rate 0.05 rad/s": the bounds in force.
std::string boundsInForce(const PlanningProblem& problem) {
  std::ostringstream out;
  const char* separator = "";
  if (problem.hasTorqueBounds()) {
    out << "actuator_limits [" << problem.max_torque(0) << ", " << problem.max_torque(1) << ", "
        << problem.max_torque(2) << "] N m";
    separator = ", ";
  }
  for (const PlanningConstraint& c : problem.constraints) {
    if (c.isCone()) continue;
    out << separator << describeConstraint(c);
    separator = ", ";
  }
  return out.str();
}

PlanResult provenInfeasible(const PlanningProblem& problem, const DurationLowerBound& bound,
                            double grid_bound) {
  PlanResult r;
  r.termination = Termination::Infeasible;
  r.scheme = problem.scheme;
  r.solver = solverName(SolverKind::Structured);
  recordLowerBound(bound, &r);
  r.duration_verdict.proven_infeasible = true;
  recordVerdict(&r, verdicts::BelowProvenBound{bound.seconds, bound.basis, boundsInForce(problem),
                                               problem.steps, grid_bound, problem.duration,
                                               problem.objective == Objective::MinimumTime});
  return r;
}

}  // namespace

std::optional<PlanResult> answerBeforeSolving(const PlanningProblem& problem,
                                              const DurationLowerBound& bound) {
  if (problem.objective == Objective::MinimumTime && identicalRestStates(problem)) {
    return alreadyThere(problem);
  }
  if (!(bound.seconds > 0.0) || !(problem.duration > 0.0) || problem.accuracy.active()) {
    return std::nullopt;
  }
  const double grid_bound = discreteDurationLowerBound(bound, problem.steps);
  if (problem.duration >= grid_bound) return std::nullopt;
  return provenInfeasible(problem, bound, grid_bound);
}

PlanResult runInternalPhase(const std::string& phase, const std::function<PlanResult()>& solve) {
  try {
    return solve();
  } catch (const FieldError& e) {  // InvalidInput or StepTooLarge of a problem built here
    PlanResult r;
    r.termination = Termination::NotConverged;
    recordVerdict(&r, verdicts::InternalPhaseFailed{phase, e.what()});
    return r;
  }
}

void recordLowerBound(const DurationLowerBound& bound, PlanResult* result) {
  result->duration_verdict.lower_bound = bound.seconds;
  result->duration_verdict.lower_bound_basis = bound.basis;
  result->duration_verdict.rate_limit = bound.rate_limit;
  result->duration_verdict.torque_limit = bound.torque_limit;
}

verdicts::LocallyInfeasible localInfeasibility(double requested, double least_found,
                                               const std::string& what_found,
                                               const DurationLowerBound& bound,
                                               bool solved_at_requested) {
  return {requested,
          least_found,
          what_found,
          bound.seconds,
          bound.seconds > 0.0 ? bound.basis : "",
          solved_at_requested};
}

namespace {

/// Whether the gyroscopic torque −Ω × JΩ has no component about body axis i for every Ω: the
/// axis is principal and the other two moments are equal (to round-off of J's entries).
bool gyroscopicFreeAxis(const Matrix3& J, int i) {
  const int j = (i + 1) % 3, k = (i + 2) % 3;
  const double tolerance = 1e-12 * J.cwiseAbs().maxCoeff();
  return std::abs(J(i, j)) <= tolerance && std::abs(J(i, k)) <= tolerance &&
         std::abs(J(j, k)) <= tolerance && std::abs(J(j, j) - J(k, k)) <= tolerance;
}

}  // namespace

std::string infeasibleAtEveryDuration(const PlanningProblem& problem) {
  if (!problem.effects || !problem.hasTorqueBounds()) return "";
  const std::optional<Vector3> d = problem.effects->constantBodyTorque();
  if (!d) return "";
  static const char* const kAxis[] = {"x", "y", "z"};
  for (int i = 0; i < 3; ++i) {
    const double excess = std::abs((*d)(i)) - problem.max_torque(i);
    if (!(excess > 0) || !gyroscopicFreeAxis(problem.inertia, i)) continue;
    // The rate about the axis must change by sign(d_i) (|d_i| − a_i) T / J_i or more.
    const double change =
        std::copysign(1.0, (*d)(i)) * (problem.final_velocity(i) - problem.initial_velocity(i));
    if (change > 0) continue;  // then only durations above a bound are excluded
    std::ostringstream why;
    why << "disturbance_torque about body " << kAxis[i] << " (" << (*d)(i)
        << " N m in all, body frame) exceeds actuator_limits max_torque " << kAxis[i] << " ("
        << problem.max_torque(i) << " N m): on this body (its " << kAxis[i]
        << " axis principal, the other two moments equal: no gyroscopic torque about it) the net "
        << "torque about " << kAxis[i] << " keeps the sign of the disturbance, at least " << excess
        << " N m, at every instant, so the rate about body " << kAxis[i] << " cannot go from "
        << problem.initial_velocity(i) << " to " << problem.final_velocity(i)
        << " rad/s in any duration";
    return why.str();
  }
  return "";
}

}  // namespace attitude_planner
