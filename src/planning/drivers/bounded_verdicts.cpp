#include "planning/drivers/bounded_verdicts.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <sstream>

#include <Eigen/Eigenvalues>

#include "attitude_planner/dynamics/effects.hpp"
#include "attitude_planner/errors.hpp"
#include "attitude_planner/lie/so3.hpp"
#include "attitude_planner/planning/constraints.hpp"
#include "attitude_planner/planning/pointing.hpp"
#include "planning/problem/duration_bound.hpp"
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

std::string lastFreeStepWithoutRoom(const PlanningProblem& problem);

/// A bounded minimum-effort request whose T lies where noRoomBeforeTheEnd proves no plan.
PlanResult noRoomAt(const PlanningProblem& problem, const DurationLowerBound& bound,
                    const NoRoomBeforeTheEnd& none) {
  PlanResult r;
  r.termination = Termination::Infeasible;
  r.scheme = problem.scheme;
  r.solver = solverName(SolverKind::Structured);
  recordLowerBound(bound, &r);
  recordNoRoom(none, &r);
  r.duration_verdict.proven_infeasible = true;
  recordVerdict(&r, verdicts::NoRoomAtDuration{problem.duration, none.from, none.to, problem.steps,
                                               lastFreeStepWithoutRoom(problem)});
  return r;
}

}  // namespace

std::optional<PlanResult> answerBeforeSolving(const PlanningProblem& problem,
                                              const DurationLowerBound& bound) {
  if (problem.objective == Objective::MinimumTime && problem.zeroManeuverReachesTheEnd()) {
    return alreadyThere(problem);
  }
  if (!(bound.seconds > 0.0) || !(problem.duration > 0.0) || problem.accuracy.active()) {
    return std::nullopt;
  }
  const double grid_bound = discreteDurationLowerBound(bound, problem.steps);
  if (problem.duration < grid_bound) return provenInfeasible(problem, bound, grid_bound);
  if (problem.objective == Objective::MinimumTime) return std::nullopt;
  const NoRoomBeforeTheEnd none = noRoomBeforeTheEnd(problem);
  if (!(problem.duration >= none.from && problem.duration <= none.to && none.to > none.from)) {
    return std::nullopt;
  }
  return noRoomAt(problem, bound, none);
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

std::string disturbanceBeyondItsAxisBound(const PlanningProblem& problem) {
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

/// The rate limit in force (the least of them), +∞ without.
double rateLimit(const PlanningProblem& problem) {
  double w = std::numeric_limits<double>::infinity();
  for (const PlanningConstraint& c : problem.constraints)
    if (c.kind == ConstraintKind::MaxAngularRate) w = std::min(w, c.limit);
  return w;
}

/// Samples of h before the intervals between them are proven, and the most evaluations of
/// leastRateBeforeTheEnd a proof may take (each a few 3x3 solves).
constexpr int kRoomSamples = 1024;
constexpr int kRoomEvaluations = 20000;
/// The least rate must clear the limit by this much (relative): by the plan check's own
/// tolerance, so that no plan it would accept as within the bounds lies where none is proven.
constexpr double kRoomRoundOff = kNodeConstraintTolerance;

/// Proves leastRateBeforeTheEnd > w on [h1, h2] from its values at the ends (Lipschitz constant
/// `K`), splitting the interval where they do not suffice; false where a split finds room or
/// the evaluations run out.
class RoomProof {
 public:
  RoomProof(const PlanningProblem& problem, double w, double K) : problem_(problem), w_(w), K_(K) {}

  double rate(double h) {
    ++evaluations_;
    return leastRateBeforeTheEnd(problem_, h * problem_.steps);
  }
  bool above(double r) const { return r > w_ * (1.0 + kRoomRoundOff); }

  bool noRoom(double h1, double r1, double h2, double r2) {
    if (!above(r1) || !above(r2) || evaluations_ > kRoomEvaluations) return false;
    if (std::min(r1, r2) - w_ * (1.0 + kRoomRoundOff) > 0.5 * K_ * (h2 - h1)) return true;
    const double mid = 0.5 * (h1 + h2);
    const double r_mid = rate(mid);
    return noRoom(h1, r1, mid, r_mid) && noRoom(mid, r_mid, h2, r2);
  }

 private:
  const PlanningProblem& problem_;
  double w_, K_;
  int evaluations_ = 0;
};

/// What has no room where noRoomBeforeTheEnd proves durations without a plan (verdict words).
std::string lastFreeStepWithoutRoom(const PlanningProblem& problem) {
  std::ostringstream why;
  why << "the final rate " << problem.final_velocity.norm() << " rad/s against max_angular_rate "
      << rateLimit(problem) << " rad/s: the paper scheme's last free step Omega_{N-2} (J "
      << "Omega_{N-2} = exp(h Omega_{N-1}^) J Omega_{N-1} - h tau_{N-1}, |tau| <= "
      << torqueAuthority(problem).largest_magnitude << " N m) exceeds the rate limit";
  return why.str();
}

}  // namespace

double leastRateBeforeTheEnd(const PlanningProblem& problem, double duration) {
  const double a = torqueAuthority(problem).largest_magnitude;
  if (problem.scheme != SchemeKind::Paper || !std::isfinite(a) ||
      (problem.effects && !problem.effects->empty())) {
    return std::numeric_limits<double>::infinity();
  }
  const double h = duration / problem.steps;
  const Matrix3 M = problem.inertia.inverse();
  const Matrix3 M2 = M * M;  // J symmetric
  const Vector3& omega = problem.final_velocity;
  const Vector3 c = so3::exp(h * omega) * (problem.inertia * omega);
  // min over |τ| ≤ a of f(τ) = ½|M(c − hτ)|². The Lagrangian's minimizer at λ ≥ 0 is
  // τ(λ) = (h²M² + λI)⁻¹ h M² c; its value f(τ(λ)) + λ(|τ(λ)|² − a²)/2 bounds the least f from
  // below at every λ (weak duality), and equals it where |τ(λ)| = a (or λ = 0 inside the ball).
  const auto tau = [&](double lambda) {
    return Vector3((h * h * M2 + lambda * Matrix3::Identity()).ldlt().solve(h * M2 * c));
  };
  const auto dual = [&](double lambda) {
    const Vector3 t = tau(lambda);
    return 0.5 * (M * (c - h * t)).squaredNorm() + 0.5 * lambda * (t.squaredNorm() - a * a);
  };
  if (tau(0.0).norm() <= a) return std::sqrt(2.0 * std::max(dual(0.0), 0.0));
  double lo = 0.0, hi = h * (M2 * c).norm() / a;  // |τ(hi)| ≤ h|M²c|/hi = a
  for (int i = 0; i < 100; ++i) {
    const double mid = 0.5 * (lo + hi);
    (tau(mid).norm() > a ? lo : hi) = mid;
  }
  return std::sqrt(2.0 * std::max(std::max(dual(lo), dual(hi)), 0.0));
}

NoRoomBeforeTheEnd noRoomBeforeTheEnd(const PlanningProblem& problem) {
  const double w = rateLimit(problem);
  const double a = torqueAuthority(problem).largest_magnitude;
  const double boundary_rate =
      std::max(problem.initial_velocity.norm(), problem.final_velocity.norm());
  // With N < 3 the step before the last is the first, whose rate is data (no rate row); with an
  // accuracy target the planner chooses N.
  if (!std::isfinite(w) || !std::isfinite(leastRateBeforeTheEnd(problem, 1.0)) ||
      !(boundary_rate > 0) || problem.steps < 3 || problem.accuracy.active()) {
    return {};
  }
  const int N = problem.steps;
  const Vector3& omega = problem.final_velocity;
  const double K =
      1.0 / Eigen::SelfAdjointEigenSolver<Matrix3>(problem.inertia).eigenvalues().minCoeff() *
      (omega.norm() * (problem.inertia * omega).norm() + a);
  // The planner's steps at the boundary rates turn less than π (validateProblem's step check).
  const double h_top = M_PI / boundary_rate * (1.0 - 1e-12);
  const double h_floor = std::max(discreteDurationLowerBound(problem) / N, 1e-9 * h_top);
  if (!(h_floor < h_top)) return {};
  RoomProof proof(problem, w, K);
  // The samples from the top down while the step has no room; the intervals between them proven.
  const double step = (h_top - h_floor) / kRoomSamples;
  double h2 = h_top, r2 = proof.rate(h_top);
  double proven_from = h_top;
  for (int i = kRoomSamples - 1; i >= 0; --i) {
    const double h1 = h_floor + i * step;
    const double r1 = proof.rate(h1);
    if (!proof.noRoom(h1, r1, h2, r2)) break;
    proven_from = h1;
    h2 = h1;
    r2 = r1;
  }
  if (!(proven_from < h_top)) return {};
  return {proven_from * N, h_top * N, proven_from == h_floor};
}

std::string infeasibleAtEveryDuration(const PlanningProblem& problem) {
  const std::string disturbance = disturbanceBeyondItsAxisBound(problem);
  if (!disturbance.empty()) return disturbance;
  const NoRoomBeforeTheEnd none = noRoomBeforeTheEnd(problem);
  if (!none.everywhere) return "";
  std::ostringstream why;
  why << lastFreeStepWithoutRoom(problem) << " at every step h from the proven least duration on "
      << "the grid, T = " << none.from
      << " s, up to the largest step the planner takes, T = " << none.to
      << " s (N = " << problem.steps << "; proven over intervals of h)";
  return why.str();
}

verdicts::ProvenDurations provenDurations(const PlanningProblem& problem,
                                          const NoRoomBeforeTheEnd& none) {
  verdicts::ProvenDurations proven;
  proven.steps = problem.steps;
  proven.least = discreteDurationLowerBound(problem);
  if (proven.least > 0.0) proven.least_basis = durationLowerBound(problem).basis;
  if (none.to > none.from) {
    proven.no_plan_from = none.from;
    proven.no_plan_to = none.to;
  }
  return proven;
}

void recordNoRoom(const NoRoomBeforeTheEnd& none, PlanResult* result) {
  if (!(none.to > none.from)) return;
  result->duration_verdict.no_plan_from = none.from;
  result->duration_verdict.no_plan_to = none.to;
}

}  // namespace attitude_planner
