// Minimum effort's drivers. Under node constraints at one N (planUnderConstraints): the
// unconstrained optimum, the interior point in its class, the other classes. Under torque bounds
// (planBoundedMinimumEffort, declared in attitude_planner/planning/minimum_time.hpp): minimum
// effort at the requested T, and where its first answer is no answer (a local "infeasible", a stop,
// a plan outside a bound) minimum time under the same bounds backs the verdict (T* > T) or starts
// the plan at T from the plan at T*, through a duration ladder where that start is stuck.
#include <chrono>
#include <cmath>
#include <limits>
#include <optional>
#include <string>
#include <vector>

#include "attitude_planner/planning/minimum_time.hpp"
#include "planning/drivers/bounded_verdicts.hpp"
#include "planning/drivers/constrained_classes.hpp"
#include "planning/drivers/constrained_recipe.hpp"
#include "planning/drivers/minimum_time_phase.hpp"
#include "planning/drivers/requests.hpp"
#include "planning/newton/newton_solver.hpp"
#include "planning/problem/duration_bound.hpp"
#include "planning/problem/message_notes.hpp"
#include "planning/problem/verdict.hpp"
#include "planning/strategies/staged_continuation.hpp"

namespace attitude_planner {

PlanResult planUnderConstraints(const PlanningProblem& problem, const SolveRequest& options,
                                SolveContext& context) {
  // The unconstrained optimum, already solved (StartSpec::unconstrained_optimum): polished from
  // it, the Newton attempt named as started from that earlier attempt's plan.
  SolveRequest newton_options = options;
  const Maneuver* solved = options.start.unconstrained_optimum;
  const bool solved_before = solved && solved->steps() == problem.steps;
  if (solved_before) newton_options.warm_start = solved;
  std::vector<ClassPlan> survey_plans;
  const std::size_t first_recorded = context.attempts().size();
  const std::size_t first_level = context.levels().size();
  const SolveContext::IterationTally tally(context);  // Newton, then the interior point
  PlanResult result = solveWithNewton(problem, newton_options, context, &survey_plans);
  const ConstraintCheck unconstrained = result.maneuver.steps() == problem.steps
                                            ? checkConstraints(problem, result.maneuver)
                                            : ConstraintCheck{};
  if (result.converged() && unconstrained.max_node_bound_violation <= 0.0) {
    addNote(&result, notes::ConstraintsInactive{});
    return result;
  }
  SolveRequest constrained = options;
  const int newton_iterations = result.iterations;
  const notes::UnconstrainedStart started{result.cost, unconstrained.worst,
                                          unconstrained.worst_where, newton_iterations};
  const bool started_from_optimum = result.converged();
  const Maneuver unconstrained_plan = result.maneuver;
  constrained.warm_start = result.converged() ? &unconstrained_plan : options.warm_start;
  // The interior point keeps the class it starts in: the unconstrained optimum's.
  ExtremalSummary survey = result.extremal_summary;
  result = solveWithInteriorPoint(problem, constrained, context);
  result.iterations = tally.iterations();
  result.levels = context.levelsFrom(first_level);  // Newton's, then the interior point's
  if (started_from_optimum) addNote(&result, started);
  if (survey.known && constrained.warm_start == &unconstrained_plan) {
    result.extremal_summary = survey;
    result.extremal_summary.others.clear();
    result.extremal = describeExtremal(result.extremal_summary);
  }
  if (classLeftFree(problem, options)) {
    result = cheapestConstrainedClass(
        problem, options, context, survey, survey_plans, std::move(result),
        started_from_optimum ? started.cost : std::numeric_limits<double>::quiet_NaN(),
        first_recorded);
  }
  return result;
}

namespace {

/// Why a bounded minimum-effort answer needs the minimum-time phase (empty: it does not): it
/// ended infeasible (a local verdict), stopped (near T* the feasible set is thin and a cold start
/// may not find it), or converged outside a bound (fourth_order's Richardson combination of two
/// cold sub-solves: up to 33 N m beyond on Betts with gravity gradient at 1.02 T*).
std::string needsMinimumTimeStart(const PlanningProblem& problem, const PlanResult& result) {
  if (result.termination == Termination::Infeasible) return "ended infeasible";
  if (result.termination == Termination::NotConverged) return "did not converge";
  if (!result.converged() || !problem.hasNodeConstraints()) return "";
  const ConstraintCheck check = checkConstraints(problem, result.maneuver);
  if (check.withinBounds()) return "";
  return "left a bound by " + exactNumber(check.max_relative_violation) + " (relative)";
}

/// One rule for a bounded minimum-effort answer's plan: whether it proves the requested T feasible
/// (provesFeasible: the dynamics, the ends and every bound, step by step), as data, and said where
/// the answer stopped short of optimality (a plan at T, not shown optimal).
void recordPlanWithinBounds(const PlanningProblem& problem, PlanResult* result) {
  result->duration_verdict.plan_within_bounds = provesFeasible(problem, *result);
  if (result->duration_verdict.plan_within_bounds && !result->converged()) {
    addNote(result, notes::PlanWithinBounds{problem.duration});
  }
}

/// The duration ladder's rungs: a first step of 15 % in T, up to 30 % after converged rungs,
/// a failed rung's step halved down to 0.4 % and held for one converged rung, at most 24 rungs.
constexpr double kLadderFirstRatio = 1.15;
constexpr double kLadderLargestRatio = 1.3;
constexpr double kLadderLeastRatio = 1.004;
constexpr int kLadderRungs = 24;
constexpr int kLadderHoldAfterFailure = 1;

/// Where the duration ladder got: the plan at the requested T if it converged there, else the
/// last solve's; `reached` the longest duration at which a rung converged within the bounds;
/// `solves` its rungs' solves (each recorded in the context, stage duration_ladder).
struct LadderClimb {
  PlanResult plan;
  double reached = 0.0;
  int solves = 0;
};

/// One rung: minimum effort at the stage's T from the last rung's plan, continued once from its
/// own iterate where the iteration limit stopped it at a plan of the rung (provesFeasible: the
/// dynamics step by step, the ends and every bound), so such an iterate is a start.
PlanResult ladderRung(const PlanningProblem& rung, const Maneuver& from, SolveContext& context,
                      int* solves) {
  const auto solve = [&](const Maneuver& start) {
    const SolveContext::Scope scope(context, AttemptStage::DurationLadder, homotopyClassOf(rung),
                                    SolveContext::Nested::ScopeStage);
    context.restoreKept(std::nullopt);  // only the last rung's plan can be kept
    ++*solves;
    return runInternalPhase("a rung of the duration ladder", [&] {
      return planFromMinimumTimePlan(rung, rung.duration, start, context);
    });
  };
  PlanResult r = solve(from);
  if (r.termination == Termination::NotConverged && provesFeasible(rung, r)) {
    const Maneuver inside = r.maneuver;
    r = solve(inside);
  }
  return r;
}

/// Minimum effort at T from the minimum-time plan at T* < T by a continuation in the duration,
/// T(s) = T* (T/T*)^s (solveByAdaptiveStages; s = 0 is the minimum-time plan itself), each rung
/// started from the last converged one (time-scaled). With spinning ends the plan at T* scaled
/// to a T several times longer is no start: its end rates are off by T/T*; near each rung the
/// last plan is.
LadderClimb climbDurationLadder(const PlanningProblem& problem, const PlanResult& minimum_time,
                                SolveContext& context) {
  const double T_star = minimum_time.minimum_duration;
  const double log_ratio = std::log(problem.duration / T_star);
  const auto share = [&](double ratio) { return std::min(1.0, std::log(ratio) / log_ratio); };
  AdaptiveSchedule schedule;
  // The ladder climbs where the start at T itself failed, so its first rung is below T: where
  // 15 % above T* would reach T, halfway (in log T).
  const double first_share = share(kLadderFirstRatio);
  schedule.first_increment = first_share < 1.0 ? first_share : 0.5;
  schedule.max_increment = share(kLadderLargestRatio);
  schedule.min_increment = share(kLadderLeastRatio);
  schedule.max_stages = kLadderRungs;
  schedule.hold_after_failure = kLadderHoldAfterFailure;
  const auto duration = [&](double s) {
    return s >= 1.0 ? problem.duration : T_star * std::exp(s * log_ratio);
  };
  LadderClimb climb;
  const StagedOutcome staged = solveByAdaptiveStages(
      context,
      [&](double s) {
        PlanningProblem rung = problem;
        rung.duration = duration(s);
        return rung;
      },
      schedule,
      [&](const PlanningProblem& rung, const Maneuver* from) {
        return from ? ladderRung(rung, *from, context, &climb.solves) : minimum_time;
      });
  climb.plan = staged.plan;
  climb.reached = staged.reached > 0.0 ? duration(staged.reached) : 0.0;
  return climb;
}

/// The ladder when the direct start did not converge (nothing climbed otherwise).
LadderClimb climbIfStuck(const PlanningProblem& problem, const PlanResult& direct,
                         const PlanResult& minimum_time, SolveContext& context) {
  if (direct.converged() || problem.scheme == SchemeKind::FourthOrder ||
      !(minimum_time.minimum_duration > 0.0)) {
    return {};
  }
  return climbDurationLadder(problem, minimum_time, context);
}

bool restToRest(const PlanningProblem& problem) {
  return problem.initial_velocity.isZero(0.0) && problem.final_velocity.isZero(0.0);
}

/// The answer when neither the direct start nor the ladder converged at T and the last solve
/// ended at a local minimum of the violation. Rest to rest the plan at T* followed by rest is a
/// plan at T: not converged, never "infeasible". With spinning ends a longer duration need not
/// be feasible in the class of the plan at T* (the ladder's plans stop where the class folds):
/// a local verdict naming the durations where plans were found.
void labelStuckAnswer(const PlanningProblem& problem, double T_star, const LadderClimb& climb,
                      PlanResult* again) {
  const bool rest_to_rest = restToRest(problem);
  if (rest_to_rest || !(climb.reached > 0.0)) again->termination = Termination::NotConverged;
  frameMessage(
      again, frames::StuckAtMinimumTimePlan{rest_to_rest, T_star, problem.duration, climb.reached});
}

/// Where plans were found is data, not only words: an answer without a plan at T after a
/// ladder that found plans from T* up to some duration carries T* and that duration, whichever
/// way it ended (infeasible, not converged, or the first answer kept).
void recordLadderReach(double T_star, const LadderClimb& climb, PlanResult* answer) {
  if (answer->converged() || !(climb.reached > 0.0)) return;
  answer->duration_verdict.least_duration_found = T_star;
  answer->duration_verdict.longest_duration_found = climb.reached;
}

/// A bounded minimum-effort answer from the minimum-time plan at T* ≤ T (`first` the solve
/// that needed it, `why` how it ended): the plan from T*'s, else the duration ladder's from
/// there, else `first` with what was tried.
PlanResult fromMinimumTimePlan(const PlanningProblem& problem, const PlanResult& first,
                               const std::string& why, const PlanResult& minimum_time,
                               const RichardsonPair& pair, std::optional<std::size_t> first_kept,
                               SolveContext& context) {
  const double T_star = minimum_time.minimum_duration;
  context.restoreKept(std::nullopt);  // the plans at T follow
  const std::size_t direct_first = context.attempts().size();
  const PlanResult direct = [&] {
    const SolveContext::Scope scope(context, AttemptStage::ConstrainedRetry,
                                    homotopyClassOf(problem), SolveContext::Nested::ScopeStage);
    return planFromMinimumTime(problem, problem.duration, minimum_time.maneuver, pair, context);
  }();
  const std::optional<std::size_t> direct_kept = context.keptSince(direct_first);
  const LadderClimb climb = climbIfStuck(problem, direct, minimum_time, context);
  const bool from_ladder = climb.plan.converged() && climb.reached == problem.duration;
  PlanResult again = from_ladder ? climb.plan : direct;
  const notes::MinimumTimeRestart restart{
      T_star, why, from_ladder, direct.termination, climb.solves > 0, climb.reached};
  const bool was_infeasible = first.termination == Termination::Infeasible;
  if (!again.converged() && !was_infeasible) {
    // Nothing better than the first answer: it stays, with what was tried.
    context.restoreKept(first_kept);
    PlanResult kept = first;
    recordLadderReach(T_star, climb, &kept);  // the first answer stands
    addNote(&kept, restart);
    addNote(&kept, notes::RestartEnded{again.termination, again.clauses});
    return kept;
  }
  if (again.termination == Termination::Infeasible)
    labelStuckAnswer(problem, T_star, climb, &again);
  recordLadderReach(T_star, climb, &again);
  addNote(&again, restart);
  if (!from_ladder) context.restoreKept(direct_kept);  // else the last rung's is kept
  return again;
}

}  // namespace

PlanResult planBoundedMinimumEffort(const PlanningProblem& problem, const SolverOptions& options) {
  SolveContext context(options);
  return planBoundedMinimumEffort(problem, context);
}

PlanResult planBoundedMinimumEffort(const PlanningProblem& problem, SolveContext& context) {
  validateProblem(problem);
  const DurationLowerBound bound = durationLowerBound(problem);
  if (std::optional<PlanResult> answer = answerBeforeSolving(problem, bound)) return *answer;
  const auto start = std::chrono::steady_clock::now();
  const std::size_t first = context.attempts().size();
  PlanResult result = planAtResolution(problem, SolveRequest(context.options()), context);
  const std::optional<std::size_t> first_kept = context.keptSince(first);
  const NoRoomBeforeTheEnd no_room = noRoomBeforeTheEnd(problem);
  recordLowerBound(bound, &result);
  recordNoRoom(no_room, &result);
  const std::string why = needsMinimumTimeStart(problem, result);
  if (why.empty() || !std::isfinite(torqueAuthority(problem).smallest_about_any_axis) ||
      problem.accuracy.active()) {
    recordPlanWithinBounds(problem, &result);
    return result;
  }
  // The interior point's "infeasible" is local (its elastic form stopped at a minimum of the
  // violation), and a stop or a plan outside a bound is no answer: the minimum-time problem
  // under the same bounds backs the verdict or gives a start strictly inside.
  PlanningProblem fastest = problem;
  fastest.objective = Objective::MinimumTime;
  fastest.time_margin = 0.0;
  fastest.duration = 0.0;
  RichardsonPair pair;
  const PlanResult minimum_time = runInternalPhase(
      "the minimum-time phase", [&] { return minimumTimeOverTwists(fastest, context, &pair); });
  context.restoreKept(first_kept);  // the first answer's, until a plan from T* replaces it
  // Every answer below has the whole trail: the first solve's, the minimum-time phase's, the
  // plans from T*'s (the context's from `first`), the first solve's attempt kept unless a later
  // plan is returned.
  const auto finish = [&](PlanResult r) {
    r.attempts = context.attemptsFrom(first);
    recordLowerBound(bound, &r);
    recordNoRoom(no_room, &r);
    r.minimum_duration = minimum_time.converged() ? minimum_time.minimum_duration : 0.0;
    recordPlanWithinBounds(problem, &r);
    r.solve_time_s =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return r;
  };
  if (!minimum_time.converged()) {
    if (result.termination == Termination::Infeasible) {
      recordVerdict(&result, verdicts::MinimumTimeFoundNone{minimum_time.termination});
    } else {
      addNote(&result, notes::MinimumTimeUnsolved{why, minimum_time.termination});
    }
    return finish(result);
  }
  const double T_star = minimum_time.minimum_duration;
  // A first solve stopped at a plan within every bound at T answers with it (not converged, a
  // plan at T): T is feasible, and a T* above it is a local minimum, not a requirement (the
  // spinning study's #109 at 0.97 T*: its interior point stops at its iteration limit there).
  if (T_star > problem.duration && provesFeasible(problem, result)) return finish(result);
  if (T_star > problem.duration) {
    result.termination = Termination::Infeasible;
    result.duration_verdict.least_duration_found = T_star;
    recordVerdict(&result, localInfeasibility(problem.duration, T_star, tStarKind(minimum_time),
                                              bound, true));
    return finish(result);
  }
  PlanResult again = runInternalPhase("the restart from the minimum-time plan", [&] {
    return fromMinimumTimePlan(problem, result, why, minimum_time, pair, first_kept, context);
  });
  // To a pointing target the restart is the interior point with the twist free from the T* plan
  // (planPointing from a plan inside every bound). T* over the twist <= T: a plan exists at some
  // twist, so the answer is never "infeasible".
  if (problem.end_condition.pointing() && again.termination == Termination::Infeasible)
    again.termination = Termination::NotConverged;
  return finish(again);
}

}  // namespace attitude_planner
