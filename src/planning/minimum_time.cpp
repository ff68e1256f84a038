#include "attitude_planner/planning/minimum_time.hpp"

#include <Eigen/Eigenvalues>
#include <chrono>
#include <cmath>
#include <sstream>

#include "attitude_planner/errors.hpp"

namespace attitude_planner {

namespace {

/// Each step of the downward continuation in T shortens it by 5 %.
constexpr double kContinuationFactor = 0.95;

/// The smallest torque every bound in force allows about any axis [N m].
double smallestAuthority(const PlanningProblem& problem) {
  double authority = std::numeric_limits<double>::infinity();
  if (problem.hasTorqueBounds()) authority = problem.max_torque.minCoeff();
  for (const PlanningConstraint& c : problem.constraints) {
    if (c.kind == ConstraintKind::MaxTorqueNorm) authority = std::min(authority, c.limit);
  }
  return authority;
}

void validateMinimumTime(const PlanningProblem& problem) {
  if (!std::isfinite(smallestAuthority(problem))) {
    throw InvalidInput(
        "objective: 'minimum_time' needs a torque bound (effects: [actuator_limits: ...] or "
        "constraints: [max_torque_norm: ...]); without one any duration > 0 is feasible");
  }
  if (problem.accuracy.active()) {
    throw InvalidInput(
        "objective: 'minimum_time' with an accuracy target is not supported (give steps)");
  }
}

}  // namespace

double eigenaxisDurationGuess(const PlanningProblem& problem) {
  const double largest_moment =
      Eigen::SelfAdjointEigenSolver<Matrix3>(problem.inertia).eigenvalues().maxCoeff();
  const double acceleration = smallestAuthority(problem) / largest_moment;  // [rad/s²]
  const double angle =
      std::max(so3::angleBetween(problem.initial_attitude, problem.final_attitude), 1e-3);
  // Rest to rest: accelerate half way, brake half way; boundary rates add the time to stop and
  // to spin up at the same acceleration.
  const double spin = (problem.initial_velocity.norm() + problem.final_velocity.norm()) /
                      std::max(acceleration, 1e-300);
  return 2.0 * std::sqrt(angle / acceleration) + spin;
}

PlanResult planMinimumTime(const PlanningProblem& problem, const SolverOptions& options) {
  validateProblem(problem);
  validateMinimumTime(problem);
  const auto start = std::chrono::steady_clock::now();
  const auto remaining = [&] {
    SolverOptions o = options;
    if (options.time_budget_s > 0) {
      const double used =
          std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
      o.time_budget_s = std::max(options.time_budget_s - used, 1e-300);
    }
    return o;
  };
  PlanningProblem effort = problem;
  effort.objective = Objective::MinimumEffort;
  effort.time_margin = 0.0;
  int solves = 0;
  PlanResult best;  // the plan at the least feasible T so far
  double T_hi = 0.0, T_lo = 0.0;
  bool timed_out = false;
  // One minimum-effort solve at T, warm-started from the last feasible plan (same N).
  const auto feasible = [&](double T) {
    effort.duration = T;
    SolverOptions o = remaining();
    if (best.converged()) {
      o.warm_start = &best.maneuver;
      o.constrained_from_warm_start = true;
    }
    PlanResult r = planAtResolution(effort, o);
    ++solves;
    if (r.termination == Termination::TimedOut) timed_out = true;
    if (!r.converged()) return false;
    best = std::move(r);
    return true;
  };
  const double guess = problem.duration > 0 ? problem.duration : eigenaxisDurationGuess(problem);
  // Bracket: double until feasible (at most 2^12), then halve until infeasible.
  double T = guess;
  int doublings = 0;
  while (!feasible(T) && !timed_out) {
    if (++doublings > 12) {
      PlanResult none;
      none.termination = Termination::Infeasible;
      none.message = "infeasible: no duration up to " + exactNumber(T) +
                     " s (2^12 times the first guess " + exactNumber(guess) +
                     " s) admits a plan under the bounds and constraints in force";
      return none;
    }
    T *= 2.0;
  }
  // Down from the first feasible T in small steps, each warm-started from the last feasible plan:
  // a large step left the interior point far outside the bounds (torques grow like 1/T²) and
  // its ℓ1 phase could end at a local minimum of the violation, a false "infeasible" (measured on
  // Betts's asymmetric body: halving from 68.6 s stopped at 36.6 s, stepping by 5 % reaches the
  // published 28.6 s).
  T_hi = T;
  T_lo = T * kContinuationFactor;
  while (!timed_out && feasible(T_lo)) {
    T_hi = T_lo;
    T_lo *= kContinuationFactor;
  }
  // Bisection on the bracket [T_lo infeasible, T_hi feasible].
  while (!timed_out && T_hi - T_lo > kMinimumTimeTolerance * T_hi) {
    const double mid = 0.5 * (T_lo + T_hi);
    if (feasible(mid)) {
      T_hi = mid;
    } else {
      T_lo = mid;
    }
  }
  if (timed_out && !best.converged()) {
    best.termination = Termination::TimedOut;
    best.message = "time budget exceeded before any duration was found feasible";
    return best;
  }
  const double T_star = T_hi;
  PlanResult result = best;
  if (problem.time_margin > 0.0) {
    effort.duration = (1.0 + problem.time_margin) * T_star;
    SolverOptions o = remaining();
    o.warm_start = &best.maneuver;
    result = planAtResolution(effort, o);
    ++solves;
  }
  result.minimum_duration = T_star;
  std::ostringstream note;
  // T* is the least duration the interior point found feasible: an upper bound on the true
  // minimum (a false "infeasible" below it cannot be told from a true one; docs/minimum_time.md).
  note << "; minimum time T* = " << T_star << " s, the least duration found feasible (bracket ["
       << T_lo << ", " << T_hi << "] s, " << solves << " minimum-effort solves"
       << (timed_out ? ", stopped by the time budget" : "") << ")";
  if (problem.time_margin > 0.0) {
    note << "; planned at (1 + " << problem.time_margin << ") T* = " << result.duration << " s";
  }
  result.message += note.str();
  result.solve_time_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

}  // namespace attitude_planner
