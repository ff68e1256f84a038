#include "attitude_planner/planning/minimum_time.hpp"

#include <chrono>
#include <cmath>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "attitude_planner/errors.hpp"
#include "planning/drivers/minimum_time_free_time.hpp"
#include "planning/drivers/minimum_time_search.hpp"
#include "planning/drivers/minimum_time_starts.hpp"
#include "planning/interior_point/free_time_solver.hpp"

namespace attitude_planner {

namespace {

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

/// What T* is, for messages.
std::string tStarKind(const PlanResult& r) {
  return r.minimum_time.kkt_point
             ? "minimum time, a KKT point of the discrete minimum-time problem: a local minimum"
             : "minimum time, the least duration found feasible: an upper bound";
}

/// `before`, none kept, then `after`: one trail in the order the attempts ran.
std::vector<Attempt> joined(std::vector<Attempt> before, const std::vector<Attempt>& after) {
  for (Attempt& a : before) a.kept = false;
  before.insert(before.end(), after.begin(), after.end());
  return before;
}

/// T* and its plan: the free-time interior point where it applies (freeTimeUnsupported), else,
/// or if none of its solves converged, the search (searchMinimumTime, an upper bound) with what is
/// left of the time budget; where the free-time problem applies, the search's plan starts one more
/// free-time solve (a KKT point). The trail keeps every stage in order: the free-time solves that
/// did not give the answer, the search's starts, the solve from the search's plan.
PlanResult minimumTimePlan(const PlanningProblem& problem, const SolverOptions& options) {
  const auto started = std::chrono::steady_clock::now();
  const std::string unsupported = freeTimeUnsupported(problem);
  std::string why;
  std::vector<Attempt> free_time_trail;
  if (unsupported.empty()) {
    std::optional<PlanResult> free_time = freeTimeMinimumTime(problem, options, &free_time_trail);
    if (free_time && free_time->converged()) return *free_time;
    if (free_time) free_time_trail = free_time->attempts;
    why = free_time ? "the free-time plan's replay failed" : "no free-time solve converged";
  } else {
    why = "the free-time interior point does not take " + unsupported + " yet";
  }
  PlanResult result = searchMinimumTime(problem, withRemainingBudget(options, started));
  result.message += "; searched on T (" + why + ")";
  result.attempts = joined(free_time_trail, result.attempts);
  if (!unsupported.empty() || !result.converged() ||
      result.maneuver.attitude.size() != static_cast<std::size_t>(problem.steps) + 1) {
    return result;
  }
  // The search's plan meets every bound at its T (an upper bound on T*): started from it, one
  // free-time solve can reach a KKT point at or below it where the structured starts did not.
  std::vector<Attempt> sharpening_trail;
  std::optional<PlanResult> sharpened =
      freeTimeFromPlan(problem, result.maneuver, result.minimum_duration,
                       withRemainingBudget(options, started), &sharpening_trail);
  if (sharpened && !sharpened->converged()) sharpening_trail = sharpened->attempts;
  if (!sharpened || !sharpened->converged()) {
    // The search's answer stands; its kept probe stays kept, the solve from its plan follows.
    for (Attempt a : sharpening_trail) {
      a.kept = false;
      result.attempts.push_back(a);
    }
    return result;
  }
  sharpened->attempts = joined(result.attempts, sharpened->attempts);
  sharpened->message += "; the structured starts did not converge (" + why +
                        "), the search found T = " + exactNumber(result.minimum_duration) + " s";
  return *sharpened;
}

/// `problem` as a minimum-effort problem at T from the plan `at_minimum_time` (attitudes at
/// T*): slower than the bang–bang plan, every node constraint is met with room (torques scale
/// like (T*/T)², rates like T*/T for rest-to-rest motions), so the interior point starts
/// strictly inside instead of from the unconstrained optimum.
PlanResult planFromMinimumTimePlan(const PlanningProblem& problem, double T,
                                   const Maneuver& at_minimum_time, const SolverOptions& options) {
  PlanningProblem effort = problem;
  effort.objective = Objective::MinimumEffort;
  effort.time_margin = 0.0;
  effort.duration = T;
  SolverOptions o = options;
  o.warm_start = &at_minimum_time;
  o.constrained_from_warm_start = true;
  return planAtResolution(effort, o);
}

}  // namespace

PlanResult planMinimumTime(const PlanningProblem& problem, const SolverOptions& options) {
  validateProblem(problem);
  validateMinimumTime(problem);
  const std::string impossible = infeasibleAtEveryDuration(problem);
  if (!impossible.empty()) {
    PlanResult none;
    none.termination = Termination::Infeasible;
    none.message = "infeasible: " + impossible;
    return none;
  }
  const auto start = std::chrono::steady_clock::now();
  PlanResult result = minimumTimePlan(problem, options);
  if (!result.converged()) return result;
  const double T_star = result.minimum_duration;
  if (problem.duration > 0 && T_star > problem.duration * (1.0 + kMinimumTimeTolerance)) {
    // `duration` is an upper bound: the request asked for T ≤ duration.
    result.termination = Termination::Infeasible;
    std::ostringstream why;
    why << "infeasible: needs T >= " << T_star << " s under these bounds (" << tStarKind(result)
        << "), requested duration <= " << problem.duration << " s";
    result.message = why.str() + result.message;
    return result;
  }
  if (problem.time_margin > 0.0) {
    const std::vector<Attempt> search_trail = result.attempts;
    const Maneuver at_minimum_time = result.maneuver;
    result = planFromMinimumTimePlan(problem, (1.0 + problem.time_margin) * T_star, at_minimum_time,
                                     withRemainingBudget(options, start));
    std::vector<Attempt> attempts = search_trail;
    for (Attempt& a : attempts) a.kept = false;
    for (Attempt a : result.attempts) {
      a.stage = AttemptStage::MinimumTimeMargin;
      attempts.push_back(a);
    }
    result.attempts = attempts;
    std::ostringstream note;
    note << "; planned at (1 + " << problem.time_margin << ") T* = " << result.duration
         << " s from the T* plan (minimum time T* = " << T_star << " s)";
    result.message += note.str();
  }
  result.minimum_duration = T_star;
  result.solve_time_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

PlanResult planBoundedMinimumEffort(const PlanningProblem& problem, const SolverOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  PlanResult result = planAtResolution(problem, options);
  if (result.termination != Termination::Infeasible || !std::isfinite(smallestAuthority(problem)) ||
      problem.accuracy.active()) {
    return result;
  }
  // The interior point's "infeasible" is local (its elastic form stopped at a minimum of the
  // violation): the minimum-time problem under the same bounds backs it or refutes it.
  PlanningProblem fastest = problem;
  fastest.objective = Objective::MinimumTime;
  fastest.time_margin = 0.0;
  fastest.duration = 0.0;
  const PlanResult minimum_time = minimumTimePlan(fastest, withRemainingBudget(options, start));
  const auto finish = [&](PlanResult r) {
    r.minimum_duration = minimum_time.converged() ? minimum_time.minimum_duration : 0.0;
    r.solve_time_s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return r;
  };
  std::ostringstream why;
  if (!minimum_time.converged()) {
    why << "infeasible (a local verdict: the minimum-time problem under the same bounds found "
           "no feasible duration either, "
        << terminationName(minimum_time.termination) << "): " << result.message;
    result.message = why.str();
    return finish(result);
  }
  const double T_star = minimum_time.minimum_duration;
  if (T_star > problem.duration) {
    why << "infeasible: needs T >= " << T_star << " s under these bounds ("
        << tStarKind(minimum_time) << "), requested " << problem.duration << " s";
    result.message = why.str();
    return finish(result);
  }
  PlanResult again = planFromMinimumTimePlan(problem, problem.duration, minimum_time.maneuver,
                                             withRemainingBudget(options, start));
  why << "; started from the minimum-time plan (T* = " << T_star
      << " s) after the first solve ended infeasible";
  if (again.termination == Termination::Infeasible) {
    // Feasible at T* ≤ T, yet not reached from T*'s plan: not a proof of infeasibility.
    again.termination = Termination::NotConverged;
    again.message = "not converged (feasible: T* = " + exactNumber(T_star) +
                    " s <= the requested duration, but the minimum-effort solve from the "
                    "minimum-time plan ended at an infeasible point): " +
                    again.message;
  }
  again.message += why.str();
  std::vector<Attempt> attempts = result.attempts;
  for (Attempt a : minimum_time.attempts) {
    a.kept = false;
    attempts.push_back(a);
  }
  for (Attempt a : again.attempts) {
    a.stage = AttemptStage::ConstrainedRetry;
    a.start = AttemptStart::WarmStart;
    attempts.push_back(a);
  }
  again.attempts = attempts;
  return finish(again);
}

}  // namespace attitude_planner
