#include "attitude_planner/planning/plan_at_resolution.hpp"

#include <chrono>
#include <cmath>
#include <limits>
#include <sstream>

#include <Eigen/Eigenvalues>

#include "attitude_planner/dynamics/simulation.hpp"
#include "attitude_planner/errors.hpp"
#include "attitude_planner/planning/pointing.hpp"
#include "attitude_planner/planning/warm_start.hpp"
#include "planning/crosscheck/nlopt_solver.hpp"
#include "planning/drivers/constrained_recipe.hpp"
#include "planning/drivers/fourth_order.hpp"
#include "planning/drivers/pointing.hpp"
#include "planning/drivers/requests.hpp"
#include "planning/newton/newton_solver.hpp"
#include "planning/problem/message_notes.hpp"
#include "planning/problem/verdict.hpp"
#include "planning/strategies/starts.hpp"

namespace attitude_planner {

namespace {

/// The boundary steps F_0 (from Ω_0) and F_{N−1} (from Ω_{N−1}) are fixed by the data: if either
/// has no solution at h = T/N no solver can plan, so the request is refused up front, naming the
/// velocity (StepTooLarge: "step too large, increase steps: ...").
void requireBoundarySteps(const PlanningProblem& problem) {
  const DiscreteScheme scheme(problem.scheme, problem.inertia, problem.duration / problem.steps);
  const std::pair<const char*, const Vector3*> ends[] = {
      {"initial.angular_velocity", &problem.initial_velocity},
      {"final.angular_velocity", &problem.final_velocity}};
  for (const auto& [field, velocity] : ends) {
    try {
      scheme.stepFromVelocity(*velocity);
    } catch (const StepTooLarge& e) {
      std::ostringstream what;
      what << e.what() << " (N = " << problem.steps << ", T = " << problem.duration << " s)";
      throw StepTooLarge(field, what.str());
    }
  }
}

/// The NLopt cross-check (a direct method on τ_1..τ_{N−1}) knows only the schemes without end
/// torques.
void requireSchemeSupported(const PlanningProblem& problem, const SolverOptions& options) {
  if (schemeHasEndTorques(problem.scheme) && options.solver == SolverKind::Nlopt) {
    throw InvalidInput("scheme: '" + schemeName(problem.scheme) +
                       "' is not available with solver nlopt (use 'paper' or 'variational')");
  }
}

/// fourth_order: one Richardson extrapolation step of second_order (docs/design/fourth_order.md),
/// the combination of the two plans in richardsonCombination (drivers/fourth_order.hpp). Both
/// solves get the request's solver, constraints, effects and what is left of its time budget; the
/// coarse one its warm start, the fine one the homotopy class the coarse one ended in. The fine one
/// starts cold: its grid continuation (N/2, N/8, … with Richardson-extrapolated step rates) starts
/// it better than the coarse plan refined at the step midpoints (torques are second differences: an
/// O(h²) attitude guess is an O(1) torque guess; measured 9 Newton iterations instead of 2). The
/// result converges only if both do; its trail is the N solve's attempts (stage
/// fourth_order_coarse where they were the solver's own solve), then the 2N solve's
/// (fourth_order_fine), the 2N solve's kept one kept (the N solve's if it stopped).
PlanResult planFourthOrder(const PlanningProblem& problem, const SolveRequest& options,
                           SolveContext& context) {
  const int N = problem.steps;
  PlanningProblem sub = problem;
  sub.scheme = SchemeKind::SecondOrder;
  const frames::RichardsonPair pair{N};
  const PlanResult coarse = [&] {
    const SolveContext::Scope scope(context, AttemptStage::FourthOrderCoarse, homotopyClassOf(sub));
    return planAtResolution(sub, options, context);
  }();
  const auto failed = [&](PlanResult sub_result, int steps) {
    frameMessage(&sub_result, frames::PairSolveStopped{pair, steps});
    return sub_result;
  };
  if (!coarse.converged()) return failed(coarse, N);
  sub.steps = 2 * N;
  SolveRequest fine_options = options;
  fine_options.warm_start = nullptr;
  fine_options.start.from_constrained_plan = false;
  if (coarse.extremal_summary.known) {
    // Richardson combines two solutions of one extremal: the 2N solve in the class the N solve
    // chose (a class left free is enumerated once, at N).
    const HomotopyClass& chosen = coarse.extremal_summary.homotopy;
    sub.direction = chosen.long_way ? RotationDirection::LongWay : RotationDirection::Shortest;
    sub.extra_revolutions = chosen.extra_revolutions;
    fine_options.enumerate_classes = false;
  }
  const PlanResult fine = [&] {
    const SolveContext::Scope scope(context, AttemptStage::FourthOrderFine, homotopyClassOf(sub));
    return planAtResolution(sub, fine_options, context);
  }();
  if (!fine.converged()) return failed(fine, 2 * N);

  PlanResult result = richardsonCombination(problem, coarse, fine);
  takeReason(&result, coarse);
  frameMessage(&result, frames::PairCombined{pair, false, fine.clauses});
  return result;
}

/// The replay figures of a plan whose replay was not run: NaN, and said so by replay_measured.
void markReplayNotMeasured(PlanResult* result) {
  const double not_measured = std::numeric_limits<double>::quiet_NaN();
  result->replay_measured = false;
  result->dynamics_residual = result->terminal_attitude_error = not_measured;
  result->terminal_velocity_error = result->replay_miss = not_measured;
}

/// A rest-to-rest request that names its class (long_way, extra turns) is never answered with a
/// plan of another class: such a plan ends NotConverged, saying so (classInconsistency). With
/// spinning ends the lifts are counted from the coasting displacement, and a converged plan of a
/// class's basin may turn far less than its lift (measured: a spin handed over between axes,
/// 9.4 rad against a lift of 19.7): the rule is not applied there.
void refuseAnotherClass(const PlanningProblem& problem, PlanResult* result) {
  const bool class_named =
      problem.direction == RotationDirection::LongWay || problem.extra_revolutions > 0;
  if (!class_named || !result->converged() || hasSpinningEnds(problem)) return;
  const std::string why = classInconsistency(*result);
  if (why.empty()) return;
  result->termination = Termination::NotConverged;
  frameMessage(result, frames::OutsideRequestedClass{why});
}

}  // namespace

PlanResult planAtResolution(const PlanningProblem& problem, const SolverOptions& options) {
  SolveContext context(options);
  return planAtResolution(problem, SolveRequest(options), context);
}

PlanResult planAtResolution(const PlanningProblem& problem, const SolveRequest& requested,
                            SolveContext& context) {
  validateProblem(problem);
  validateOptions(requested);
  requireSchemeSupported(problem, requested);
  if (schemeIsDiscretization(problem.scheme)) requireBoundarySteps(problem);
  // A guess of another N is resampled to this grid (warm_start.hpp).
  SolveRequest options = requested;
  Maneuver on_grid;
  const bool guess_resampled =
      requested.warm_start && requested.warm_start->steps() != problem.steps;
  if (guess_resampled) {
    on_grid = initialGuessOnGrid(*requested.warm_start, problem);
    options.warm_start = &on_grid;
  }
  const auto start = std::chrono::steady_clock::now();
  const std::size_t first_attempt = context.attempts().size();
  PlanResult result;
  bool replayed_by_solver = false;
  // A pointing request is judged (replay, terminal errors) against the end attitude it chose.
  PlanningProblem judged = problem;
  if (problem.end_condition.pointing()) {
    result = planPointing(problem, options, context);
    judged.final_attitude = pointingAttitude(problem.end_condition, result.pointing.final_twist);
  } else if (problem.scheme == SchemeKind::FourthOrder) {
    result = planFourthOrder(problem, options, context);
  } else if (options.solver == SolverKind::Structured && problem.hasNodeConstraints() &&
             options.warm_start && !options.start.from_constrained_plan && !guess_resampled) {
    // A plan of this N given as the initial guess (e.g. the remainder of the plan being flown):
    // the interior point from it directly, its multipliers re-derived; if that stops, from it
    // through the usual continuation. A resampled guess (another N) is off the bounds it rode
    // on by O(h) and starts the unconstrained optimum instead, as below (measured: torque_limited
    // 64 → 256, 29 interior-point iterations from the guess, 25 cold).
    const SolveContext::IterationTally tally(context);  // from the guess, then the retry
    const std::size_t first_level = context.levels().size();
    result = solveWithInteriorPointFromGuess(problem, options, context);
    if (result.termination == Termination::NotConverged ||
        result.termination == Termination::Infeasible) {
      const PlanResult first = result;
      result = solveWithInteriorPoint(problem, options, context);
      result.iterations = tally.iterations();
      result.levels = context.levelsFrom(first_level);
      addNote(&result, notes::AfterGuessStopped{first.clauses});
    }
  } else if (options.solver == SolverKind::Structured && problem.hasNodeConstraints() &&
             options.start.from_constrained_plan && options.warm_start) {
    result = solveWithInteriorPoint(problem, options, context);
  } else if (options.solver == SolverKind::Structured && problem.hasNodeConstraints()) {
    result = planUnderConstraints(problem, options, context);
  } else if (options.solver == SolverKind::Structured) {
    result = solveWithNewton(problem, options, context, nullptr, &replayed_by_solver);
  } else {
    const SolveContext::Call call(context, options);
    result = solveWithNlopt(problem, context.remainingOptions());
  }
  const bool stopped = stoppedByRequest(result.termination);
  const bool replayable = options.solver == SolverKind::Structured &&
                          schemeIsDiscretization(problem.scheme) &&
                          result.maneuver.steps() == problem.steps;
  if (stopped && replayable) {
    // A stopped plan is handed over at once, without its open-loop replay (N implicit steps:
    // 0.10-0.14 s at N = 1e5, where a cancel waits 30 ms): its figures say "not measured".
    markReplayNotMeasured(&result);
  } else if (replayable && !replayed_by_solver) {
    // The Newton and interior-point plans are their own trajectories; their open-loop replay
    // (replay_miss, the terminal errors) is measured once, here, for the plan returned (the
    // Newton walk measures its own class's beside that plan's check).
    try {
      replayFigures(judged, &result);
    } catch (const StepTooLarge& e) {
      judgeFailedReplay(judged, e.what(), &result);
    }
  }
  if (result.solver.empty()) result.solver = solverName(options.solver);
  // The trail: every attempt the request's solves recorded in the context, in order.
  result.attempts = context.attemptsFrom(first_attempt);
  refuseAnotherClass(problem, &result);
  if (problem.hasNodeConstraints() && result.maneuver.steps() == problem.steps) {
    recordConstraintFigures(problem, &result);
  }
  result.solve_time_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

}  // namespace attitude_planner
