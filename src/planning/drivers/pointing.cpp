#include "planning/drivers/pointing.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <sstream>

#include "attitude_planner/errors.hpp"
#include "attitude_planner/planning/newton_parameters.hpp"
#include "attitude_planner/planning/pointing.hpp"
#include "planning/drivers/constrained_recipe.hpp"
#include "planning/drivers/requests.hpp"
#include "planning/interior_point/constrained_system.hpp"
#include "planning/newton/newton_solver.hpp"
#include "planning/newton/twist_newton.hpp"
#include "planning/problem/message_notes.hpp"
#include "planning/problem/verdict.hpp"
#include "planning/strategies/starts.hpp"

namespace attitude_planner {

namespace {

/// The ways round each start twist is solved in (a whole turn of ψ joins the two, so extra
/// revolutions are reached through ψ itself).
constexpr HomotopyClass kPointingClasses[] = {{false, 0}, {true, 0}};

/// One start's or refinement's outcome: the iterate it ended at and how.
struct TwistRun {
  HomotopyClass homotopy;
  double start_twist = 0.0;
  int steps = 0;
  TwistSolve solve;
  ReducedProblem::StepVectors iterate;
  Lift lift;
  std::vector<IterationInfo> history;
  /// A constrained request's interior-point plan (on `steps`) and its multipliers and slacks.
  std::optional<PlanResult> plan;
  /// A constrained start's converged fixed-twist optimum (fromFixedTwistPlan): the answer's
  /// fallback where no free-twist solve converges (fixedTwistFallback).
  std::optional<PlanResult> fixed_plan;
  LevelDuals duals;
  /// The interior point's formulation of its plan (Unconstrained: a twist Newton run).
  Formulation formulation = Formulation::Unconstrained;
  /// Where its iterate started (a constrained start: the fixed-twist solve's plan, the attempts
  /// just before it, else the unconstrained optimum or the geodesic).
  AttemptStart start = AttemptStart::Hermite;
  bool converged() const { return solve.termination == Termination::Converged; }
};

/// `problem` on `steps` steps with R_N at `twist` (its way round left free).
PlanningProblem posedAt(const PlanningProblem& problem, int steps, double twist) {
  PlanningProblem at = problem;
  at.steps = steps;
  at.final_attitude = pointingAttitude(problem.end_condition, twist);
  return at;
}

/// `problem` on `steps` steps with R_N at `twist`, in `homotopy`.
PlanningProblem posedAt(const PlanningProblem& problem, int steps, double twist,
                        const HomotopyClass& homotopy) {
  PlanningProblem at = pinnedToClass(problem, homotopy);
  at.steps = steps;
  at.final_attitude = pointingAttitude(problem.end_condition, twist);
  return at;
}

/// The survey grid: the coarsest 16·4^k < N whose boundary steps h|Ω| stay small, else N.
int surveySteps(const PlanningProblem& problem, const NewtonParameters& p) {
  const double rate = std::max(problem.initial_velocity.norm(), problem.final_velocity.norm());
  for (int n = p.class_survey_min_steps; n < problem.steps; n *= p.coarsening_factor) {
    if (problem.duration / n * rate <= p.coarse_max_step_angle) return n;
  }
  return problem.steps;
}

/// The interior point's outcome as a twist run: ψ, cost and stationarity from its plan.
void takeInteriorPoint(GridOutcome outcome, TwistRun* run) {
  const PlanResult& r = outcome.result;
  run->solve.termination = r.termination;
  run->solve.reason = renderMessage(r);
  run->solve.iterations = r.iterations;
  run->solve.twist = r.pointing.active ? r.pointing.final_twist : run->solve.twist;
  run->solve.cost = r.cost;
  run->solve.twist_gradient = r.pointing.twist_gradient;
  run->solve.relative_gradient = r.max_residual;
  run->solve.relative_decrement = r.newton_decrement;
  run->history = r.history;
  run->iterate = std::move(outcome.steps);
  run->duals = std::move(outcome.duals);
  run->formulation = outcome.formulation;
  run->plan = std::move(outcome.result);
}

/// The fixed-attitude constrained plan at `at`'s end attitude (the request's own driver: its
/// classes enumerated under the constraints), if it converged.
std::optional<PlanResult> fixedTwistPlan(const PlanningProblem& at, const SolverOptions& options,
                                         SolveContext& context) {
  PlanningProblem fixed = at;
  fixed.end_condition = EndCondition();
  PlanResult plan = planAtResolution(fixed, SolveRequest(options), context);
  if (!plan.converged() || plan.maneuver.steps() != at.steps) return std::nullopt;
  return plan;
}

/// A constrained request's start (stage constraints, torque bounds): the interior point with ψ
/// free on `at`'s grid, from `coarse` (a coarser level's run: its iterate and duals, `at` posed
/// at its twist), else from the fixed-attitude constrained optimum at `twist` (fixedTwistPlan)
/// and, where that has no plan or does not converge, from the unconstrained twist Newton's answer
/// on this grid (`at` re-posed at its twist; the geodesic if it did not converge).
TwistRun runConstrainedTwist(const PlanningProblem& at, double twist, const HomotopyClass& homotopy,
                             const TwistRun* coarse, double tolerance, SolveContext& context,
                             const NewtonParameters& p);

/// One twist Newton solve on `at` from `coarse` (a coarser grid's iterate) or the Hermite curve,
/// ended early where `watch` says so (`raise_guess`: solveTwistNewton's).
TwistRun runTwist(const PlanningProblem& at, double twist, const HomotopyClass& homotopy,
                  const ReducedProblem::StepVectors* coarse, double tolerance,
                  SolveContext& context, const NewtonParameters& p,
                  const TwistWatch* watch = nullptr, int raise_guess = 1) {
  TwistRun run;
  run.homotopy = homotopy;
  run.start_twist = twist;
  run.steps = at.steps;
  try {
    ReducedProblem np(at);
    run.lift = startOnHermiteCurve(at, &np);
    if (coarse) np.initializeFromCoarser(*coarse);
    run.solve = solveTwistNewton(np, twist, context, tolerance, context.options().max_iterations, p,
                                 &run.history, watch, raise_guess);
    run.iterate = np.current();
  } catch (const StepTooLarge& e) {
    run.solve.termination = Termination::StepTooLarge;
    run.solve.reason = std::string("boundary velocity: ") + e.what();
  }
  return run;
}

/// The interior point with ψ free on `at`'s grid from `unconstrained` (a twist Newton run on that
/// grid: `at` re-posed at its twist), else, where that did not converge, from the geodesic at
/// `at`'s twist; stopped where `watch` (if given) says so.
void fromUnconstrainedRun(const PlanningProblem& at, const TwistRun& unconstrained,
                          const SolverOptions& options, SolveContext& context, TwistRun* run,
                          const FeasibleIterateWatch* watch = nullptr) {
  run->lift = unconstrained.lift;
  const bool from_optimum = unconstrained.converged();
  run->start = from_optimum ? AttemptStart::UnconstrainedOptimum : AttemptStart::Hermite;
  PlanningProblem posed = at;
  if (from_optimum) {
    posed.final_attitude = pointingAttitude(at.end_condition, unconstrained.solve.twist);
    run->solve.twist = unconstrained.solve.twist;
  }
  takeInteriorPoint(
      solveInteriorPointOnGrid(posed, options, context,
                               from_optimum ? &unconstrained.iterate : nullptr, nullptr, watch),
      run);
}

/// The interior point with ψ free from the unconstrained twist Newton's answer on `at`'s grid,
/// solved here from `twist` (fromUnconstrainedRun).
void fromUnconstrainedOptimum(const PlanningProblem& at, double twist,
                              const HomotopyClass& homotopy, const SolverOptions& options,
                              SolveContext& context, const NewtonParameters& p, TwistRun* run) {
  const TwistRun unconstrained =
      runTwist(at, twist, homotopy, nullptr, options.tolerance, context, p);
  fromUnconstrainedRun(at, unconstrained, options, context, run);
}

/// The interior point with ψ free from the constrained optimum at `at`'s twist (every class tried
/// there): its attitudes, and multipliers re-derived from stationarity (it carries none), as an
/// initial guess starts. False (run untouched) where that fixed-twist solve has no plan.
bool fromFixedTwistPlan(const PlanningProblem& at, const SolverOptions& options,
                        SolveContext& context, TwistRun* run) {
  const std::optional<PlanResult> fixed = fixedTwistPlan(at, options, context);
  if (!fixed) return false;
  run->fixed_plan = fixed;
  ReducedProblem np(at);
  np.setInteriorFromAttitudes(fixed->maneuver.attitude);
  const InteriorPointParameters parameters;
  const LevelDuals duals =
      ConstrainedSystem(at, &np, Formulation::FreeSlacks, parameters).estimatedDuals();
  const ReducedProblem::StepVectors steps = np.current();
  run->solve.twist = twistOf(at.final_attitude, at.end_condition);
  takeInteriorPoint(solveInteriorPointOnGrid(at, options, context, &steps, &duals), run);
  run->start = AttemptStart::PreviousAttempt;
  return true;
}

TwistRun runConstrainedTwist(const PlanningProblem& at, double twist, const HomotopyClass& homotopy,
                             const TwistRun* coarse, double tolerance, SolveContext& context,
                             const NewtonParameters& p) {
  SolverOptions options = context.options();
  options.tolerance = tolerance;
  TwistRun run;
  run.homotopy = homotopy;
  run.start_twist = twist;
  run.steps = at.steps;
  run.solve.twist = twist;
  const int counted_before = context.iterations();
  if (coarse) {
    takeInteriorPoint(solveInteriorPointOnGrid(at, options, context, &coarse->iterate,
                                               coarse->duals.empty() ? nullptr : &coarse->duals),
                      &run);
    run.lift = coarse->lift;
  } else {
    // From the fixed-twist constrained optimum first: its solve enumerates the ways round under
    // the constraints (the free-ψ interior point keeps the class it starts in, and from the
    // unconstrained optimum it ended in a costlier class on seeded requests: 0.1059 against the
    // swept 0.1031, 0.2916 against 0.2466). The unconstrained optimum where that has no plan.
    const bool fixed = fromFixedTwistPlan(at, options, context, &run);
    if ((!fixed || !run.converged()) && !context.stopReason()) {
      TwistRun again = run;
      fromUnconstrainedOptimum(at, twist, homotopy, options, context, p, &again);
      if (!fixed || again.converged()) run = std::move(again);
    }
  }
  run.solve.iterations = context.iterations() - counted_before;
  return run;
}

/// Records `run` as an attempt in the trail; returns its index there.
std::size_t record(const TwistRun& run, AttemptStage stage, AttemptStart start, int coarse_steps,
                   SolveContext& context) {
  Attempt a;
  a.stage = stage;
  a.start = start;
  a.globalization = Globalization::LineSearch;
  a.formulation = run.formulation;
  a.homotopy = run.homotopy;
  a.steps = run.steps;
  a.termination = run.solve.termination;
  a.iterations = run.solve.iterations;
  a.cost = run.converged() ? run.solve.cost : std::numeric_limits<double>::quiet_NaN();
  a.start_detail.twist = run.start_twist;
  a.start_detail.coarse_steps = coarse_steps;
  context.record(a);
  return context.attempts().size() - 1;
}

/// Survey answers (solved to the coarse tolerance, ~1e-6 relative in the torques) within these of
/// each other in cost (relative) and twist [rad] are one extremal: refining both would repeat it.
constexpr double kSameSurveyCost = 1e-6, kSameSurveyTwist = 1e-4;

/// Whether two converged answers are one extremal: the same cost and R_N (ψ modulo 2π).
bool sameAnswer(const TwistRun& a, const TwistRun& b) {
  const double dpsi = std::remainder(a.solve.twist - b.solve.twist, 2.0 * M_PI);
  return std::abs(a.solve.cost - b.solve.cost) <=
             kSameSurveyCost * std::max(a.solve.cost, b.solve.cost) &&
         std::abs(dpsi) < kSameSurveyTwist;
}

/// The survey's converged answers worth refining: distinct, cheapest first, within `margin`
/// (relative) of the cheapest.
std::vector<const TwistRun*> worthRefining(const std::vector<TwistRun>& survey, double margin) {
  std::vector<const TwistRun*> sorted;
  for (const TwistRun& r : survey) {
    if (r.converged()) sorted.push_back(&r);
  }
  std::sort(sorted.begin(), sorted.end(),
            [](const TwistRun* a, const TwistRun* b) { return a->solve.cost < b->solve.cost; });
  std::vector<const TwistRun*> out;
  for (const TwistRun* r : sorted) {
    if (r->solve.cost > (1.0 + margin) * sorted.front()->solve.cost) break;
    const bool repeated =
        std::any_of(out.begin(), out.end(), [&](const TwistRun* o) { return sameAnswer(*o, *r); });
    if (!repeated) out.push_back(r);
  }
  return out;
}

/// A survey answer carried to the requested grid through factor-4 levels (each level's solve to
/// the coarse tolerance but the last), under the request's node constraints unless
/// `unconstrained`; the attempt is the last level's solve.
TwistRun refine(const PlanningProblem& problem, const TwistRun& from, SolveContext& context,
                const NewtonParameters& p, bool unconstrained = false) {
  TwistRun run = from;
  // The refinement's own levels, as the context counted them (the survey is its own attempt).
  const int counted_before = context.iterations();
  run.history.clear();
  int steps = from.steps;
  while (steps < problem.steps && !context.stopReason()) {
    steps = std::min(problem.steps, steps * p.coarsening_factor);
    const bool last = steps == problem.steps;
    const double tolerance = last ? context.options().tolerance
                                  : std::max(context.options().tolerance, p.coarse_tolerance_floor);
    const PlanningProblem at = posedAt(problem, steps, run.solve.twist, from.homotopy);
    TwistRun next =
        at.hasNodeConstraints() && !unconstrained
            ? runConstrainedTwist(at, run.solve.twist, from.homotopy, &run, tolerance, context, p)
            : runTwist(at, run.solve.twist, from.homotopy, &run.iterate, tolerance, context, p);
    next.start_twist = from.start_twist;
    next.history.insert(next.history.begin(), run.history.begin(), run.history.end());
    run = std::move(next);
    run.solve.iterations = context.iterations() - counted_before;
    if (!run.converged()) break;
  }
  return run;
}

/// A constrained run's plan (the interior point's, judged against the end attitude it chose) with
/// the pointing part of its message.
PlanResult constrainedResultOf(const TwistRun& run) {
  PlanResult result = *run.plan;
  result.iterations = run.solve.iterations;
  result.history = run.history;
  result.extremal_summary = extremalOf(run.lift);
  addNote(&result, notes::PointingTwist{result.pointing.final_twist, result.pointing.twist_gradient,
                                        true, result.pointing.twist_stationarity});
  return result;
}

/// The plan of `run` (on the requested grid) with its figures, the pointing summary and the
/// message.
PlanResult resultOf(const PlanningProblem& problem, const TwistRun& run) {
  if (run.plan) return constrainedResultOf(run);
  PlanResult result;
  PlanningProblem chosen = posedAt(problem, problem.steps, run.solve.twist, run.homotopy);
  ReducedProblem np(chosen);
  np.setCurrent(run.iterate);
  const Maneuver planned = np.maneuver(run.iterate);
  evaluatePlan(chosen, planned.torque, &result, &planned);
  result.termination = run.solve.termination;
  std::string reason = run.solve.reason;
  if (result.converged()) {
    const std::string inconsistent = planInconsistency(chosen, result, false);
    if (!inconsistent.empty()) {
      result.termination = Termination::NotConverged;
      reason = inconsistent;
    }
  }
  result.iterations = run.solve.iterations;
  result.history = run.history;
  result.max_residual = run.solve.relative_gradient;
  result.newton_decrement = run.solve.relative_decrement;
  result.extremal_summary = extremalOf(run.lift);
  summarizePointingEnd(planned.attitude.back(), problem.end_condition, &result.pointing);
  result.pointing.twist_gradient = run.solve.twist_gradient;
  double scale = 0.0;
  Eigen::VectorXd gradient;
  np.evaluateWithTwist(&gradient, nullptr, nullptr, nullptr, &scale);
  result.pointing.twist_stationarity = std::abs(gradient(np.unknowns())) / scale;
  recordVerdict(&result,
                verdicts::NewtonEnded{reason, run.solve.iterations, run.solve.relative_gradient,
                                      run.solve.relative_decrement});
  addNote(&result, notes::PointingTwist{result.pointing.final_twist, run.solve.twist_gradient});
  if (problem.hasNodeConstraints()) addNote(&result, notes::ConstraintsInactive{});
  return result;
}

/// A survey start in Newton's region (an unshifted step of relative decrement d at most
/// kJoinDecrement) whose model minimum (the full step's predicted cost and ψ) lies within
/// max(kJoinCost, kJoinCostPerCube d³) (relative) and max(kJoinTwist, kJoinTwistPerSquare d²)
/// [rad] of an answer the survey already holds, and whose cost is not below that answer's (the
/// start descends: from below it would end cheaper, elsewhere), is converging to that answer,
/// which the survey ranks once (sameAnswer): its remaining iterations are not run. The
/// tolerances widen with d as the quadratic model's error does (its step's error ~ d², its cost's
/// ~ d³). Measured on seed 41028: 7 of its 8 starts end in one basin, and the model's cost was
/// within 5e-4 of that answer's at d <= 0.08 on each of the 6 later ones; the widened tolerances
/// leave every answer of seeds 41, 43, 47, 53, 59, 61, 67, 71 (352 requests) bit for bit the same
/// and end the later starts 1-2 iterations sooner each (53006: 40 -> 37 iterations).
constexpr double kJoinDecrement = 0.3, kJoinCost = 1e-3, kJoinTwist = 1e-2;
constexpr double kJoinCostPerCube = 2.0, kJoinTwistPerSquare = 1.0;

/// The watch of a survey start (kJoinDecrement): a reason naming the earlier start of `runs` it
/// joins, else empty.
TwistWatch joinsAnEarlierAnswer(const std::vector<TwistRun>& runs) {
  return [&runs](double cost, double twist, double decrement) {  // the model's cost and ψ
    if (decrement > kJoinDecrement) return std::string();
    const double d = decrement;
    const double now = cost / (1.0 - d * d);  // the model's decrease is d² C
    const double cost_tolerance = std::max(kJoinCost, kJoinCostPerCube * d * d * d);
    const double twist_tolerance = std::max(kJoinTwist, kJoinTwistPerSquare * d * d);
    for (std::size_t i = 0; i < runs.size(); ++i) {
      const TwistSolve& s = runs[i].solve;
      const bool joins = runs[i].converged() && now >= s.cost &&
                         std::abs(cost - s.cost) <= cost_tolerance * s.cost &&
                         std::abs(std::remainder(twist - s.twist, 2.0 * M_PI)) <= twist_tolerance;
      if (joins) return "converging to start " + std::to_string(i + 1) + "'s answer: not run on";
    }
    return std::string();
  };
}

/// Every start (kPointingStartTwists twists from the one of least rotation × the ways round) solved
/// on `steps` steps, each recorded as a `stage` attempt; with `finals`, each appended there too (a
/// plan on the requested grid). Under the request's node constraints (each twist from its
/// fixed-twist constrained optimum, runConstrainedTwist) unless `unconstrained` (the twist Newton,
/// the constraints not seen; on a class survey, a start joining an earlier answer is stopped:
/// joinsAnEarlierAnswer). Stops at a cancel or the deadline.
std::vector<TwistRun> runStarts(const PlanningProblem& problem, int steps, double tolerance,
                                AttemptStage stage, SolveContext& context,
                                const NewtonParameters& p,
                                std::vector<std::pair<TwistRun, std::size_t>>* finals,
                                bool unconstrained = false) {
  const double base = nearestTwist(problem.initial_attitude, problem.end_condition);
  std::vector<TwistRun> runs;
  const TwistWatch join = joinsAnEarlierAnswer(runs);
  const TwistWatch* watch = stage == AttemptStage::ClassSurvey ? &join : nullptr;
  int raise_guess = 1;  // the starts' Hessians share a scale: the last one's least shift
  for (int i = 0; i < kPointingStartTwists; ++i) {
    const double twist = std::remainder(base + 2.0 * M_PI * i / kPointingStartTwists, 2.0 * M_PI);
    for (const HomotopyClass& c : kPointingClasses) {
      if (context.stopReason()) return runs;
      if (problem.hasNodeConstraints() && !unconstrained) {
        // The fixed-twist solve enumerates the ways round under the constraints itself.
        if (&c != &kPointingClasses[0]) continue;
        runs.push_back(runConstrainedTwist(posedAt(problem, steps, twist), twist, c, nullptr,
                                           tolerance, context, p));
      } else {
        runs.push_back(runTwist(posedAt(problem, steps, twist, c), twist, c, nullptr, tolerance,
                                context, p, watch, raise_guess));
        if (runs.back().solve.fresh_raises > 0) raise_guess = runs.back().solve.fresh_raises;
      }
      const std::size_t at = record(runs.back(), stage, runs.back().start, 0, context);
      if (finals) finals->emplace_back(runs.back(), at);
    }
  }
  return runs;
}

/// A constrained request none of whose free-twist runs converged: the cheapest converged
/// fixed-attitude plan among the starts' fixed-twist optima and one fixed-attitude request
/// at the twist of `unconverged` (the run that would be answered, not converged), labelled (the
/// twist not optimized: its stationarity not measured, NaN). Empty where none converged.
std::optional<PlanResult> fixedTwistFallback(
    const PlanningProblem& problem, const std::vector<std::pair<TwistRun, std::size_t>>& finals,
    const TwistRun* unconverged, SolveContext& context) {
  if (!problem.hasNodeConstraints() || context.stopReason()) return std::nullopt;
  std::optional<PlanResult> best;
  std::string reason;
  const auto consider = [&](const PlanResult& plan, const std::string& why) {
    if (plan.converged() && (!best || plan.cost < best->cost)) best = plan, reason = why;
  };
  for (const auto& f : finals) {
    if (f.first.fixed_plan) consider(*f.first.fixed_plan, f.first.solve.reason);
  }
  if (unconverged && std::isfinite(unconverged->solve.twist) && !context.stopReason()) {
    // The fixed-attitude request at that twist, without a minimum-time phase of its own: minimum
    // time over the twist follows this request where a torque bound is present (the bounded
    // driver), backs its verdict and restarts from its plan where T* <= T. Measured on the six
    // infeasible torque-box requests of seeds 41, 43, 47 and 53: the fixed-twist T* exceeded T in
    // each, and that phase took a quarter to a third of the request.
    PlanningProblem at = posedAt(problem, problem.steps, unconverged->solve.twist);
    at.end_condition = EndCondition();
    const PlanResult plan = planAtResolution(at, SolveRequest(context.options()), context);
    if (plan.maneuver.steps() == problem.steps) consider(plan, unconverged->solve.reason);
  }
  if (!best) return std::nullopt;
  summarizePointingEnd(best->maneuver.attitude.back(), problem.end_condition, &best->pointing);
  best->pointing.twist_gradient = std::numeric_limits<double>::quiet_NaN();
  best->pointing.twist_stationarity = std::numeric_limits<double>::quiet_NaN();
  addNote(&*best, notes::FixedTwistFallback{best->pointing.final_twist, reason});
  return best;
}

/// The kept answer: the cheapest converged plan on the requested grid (else, constrained, the
/// fixed-twist fallback, else the first with an iterate there, not converged), with the request's
/// trail and totals.
PlanResult finishPointing(const PlanningProblem& problem, const std::vector<TwistRun>& survey,
                          const std::vector<std::pair<TwistRun, std::size_t>>& finals,
                          std::size_t first_recorded, SolveContext& context) {
  const std::pair<TwistRun, std::size_t>* kept = nullptr;
  for (const auto& f : finals) {
    const bool cheaper =
        !kept || (f.first.converged() &&
                  (!kept->first.converged() || f.first.solve.cost < kept->first.solve.cost));
    if (f.first.iterate.size() == std::size_t(problem.steps) && cheaper) kept = &f;
  }
  PlanResult result;
  std::optional<PlanResult> fallback;
  if (!kept || !kept->first.converged()) {
    fallback = fixedTwistFallback(problem, finals, kept ? &kept->first : nullptr, context);
  }
  if (fallback) {
    result = std::move(*fallback);
  } else if (kept) {
    result = resultOf(problem, kept->first);
    context.markKept(kept->second);
  } else {
    result.termination = context.stopReason().value_or(Termination::NotConverged);
    recordVerdict(&result, verdicts::NoPointingStartConverged{static_cast<int>(survey.size())});
    if (!survey.empty()) addNote(&result, notes::LastPointingStart{survey.back().solve.reason});
    result.cost = std::numeric_limits<double>::quiet_NaN();
  }
  result.attempts.assign(context.attempts().begin() + first_recorded, context.attempts().end());
  result.pointing.starts = static_cast<int>(survey.size());
  if (kept && !fallback) {
    frames::PointingWalk walk;
    walk.none_converged = !kept->first.converged();
    walk.starts = survey.size();
    walk.kept_at = kept->second - first_recorded;
    walk.attempts = result.attempts.size();
    walk.survey = !survey.empty();
    walk.constrained = problem.hasNodeConstraints();
    walk.start_twists = kPointingStartTwists;
    walk.ways_round = std::size(kPointingClasses);
    frameMessage(&result, walk);
  }
  return result;
}

/// Whether any of `finals` converged.
bool anyConverged(const std::vector<std::pair<TwistRun, std::size_t>>& finals) {
  return std::any_of(finals.begin(), finals.end(),
                     [](const auto& f) { return f.first.converged(); });
}

/// The survey's tolerance: the request's on the requested grid, else the coarse levels' floor.
double surveyTolerance(const PlanningProblem& problem, int survey_steps, SolveContext& context,
                       const NewtonParameters& p) {
  const double tolerance = context.options().tolerance;
  return survey_steps == problem.steps ? tolerance : std::max(tolerance, p.coarse_tolerance_floor);
}

/// An unconstrained request: the starts on the survey grid, the distinct converged answers within
/// the class survey's margin of the cheapest carried to the requested grid (appended to `finals`),
/// and where none reached it, the starts on the requested grid. Returns the survey.
std::vector<TwistRun> unconstrainedStarts(const PlanningProblem& problem, SolveContext& context,
                                          const NewtonParameters& p,
                                          std::vector<std::pair<TwistRun, std::size_t>>* finals) {
  const int survey_steps = surveySteps(problem, p);
  const bool on_requested = survey_steps == problem.steps;
  const std::vector<TwistRun> survey =
      runStarts(problem, survey_steps, surveyTolerance(problem, survey_steps, context, p),
                on_requested ? AttemptStage::Solve : AttemptStage::ClassSurvey, context, p,
                on_requested ? finals : nullptr);
  if (on_requested) return survey;
  for (const TwistRun* r : worthRefining(survey, p.class_refine_margin)) {
    if (context.stopReason()) break;
    TwistRun refined = refine(problem, *r, context, p);
    const std::size_t at = record(refined, AttemptStage::ClassRefine, AttemptStart::CoarseLevel,
                                  survey_steps, context);
    finals->emplace_back(std::move(refined), at);
  }
  if (!anyConverged(*finals) && !context.stopReason()) {
    // Nothing of the survey grid's reached the requested one: the starts on the requested grid.
    runStarts(problem, problem.steps, context.options().tolerance, AttemptStage::Solve, context, p,
              finals);
  }
  return survey;
}

/// The unconstrained fixed-attitude optimum at `twist` in `way` on the requested grid (Newton on
/// that problem, its class pinned), as a run posed at `twist`; not converged where it has no plan.
TwistRun fixedTwistOptimum(const PlanningProblem& problem, double twist, const HomotopyClass& way,
                           SolveContext& context) {
  SolverOptions options = context.options();
  options.enumerate_classes = false;
  PlanningProblem fixed = posedAt(problem, problem.steps, twist, way);
  fixed.end_condition = EndCondition();
  const PlanResult plan = solveWithNewton(fixed, SolveRequest(options), context);
  TwistRun run;
  run.homotopy = way;
  run.start_twist = twist;
  run.steps = problem.steps;
  run.solve.twist = twist;
  run.solve.termination =
      plan.maneuver.steps() == problem.steps ? plan.termination : Termination::NotConverged;
  run.solve.cost = plan.cost;
  if (run.converged()) {
    ReducedProblem np(posedAt(problem, problem.steps, twist));
    np.setInteriorFromAttitudes(plan.maneuver.attitude);
    run.iterate = np.current();
  }
  return run;
}

/// Two plans' costs within this (relative) are one extremal (cf. NewtonParameters::
/// same_extremal_cost).
constexpr double kSameCost = 1e-9;

/// The unconstrained optimum `optimum` (ψ* on the requested grid) the other way round: the
/// fixed-attitude optimum at ψ* in the way round `optimum` did not end in (the one whose cost
/// differs from its own: the free-ψ twist Newton slides from either way round to the cheaper one
/// through a whole turn of ψ, where a cone may block the interior point). Not converged where
/// neither has another plan.
TwistRun otherWayRound(const PlanningProblem& problem, const TwistRun& optimum,
                       SolveContext& context) {
  TwistRun run;
  for (const HomotopyClass& way : kPointingClasses) {
    if (context.stopReason()) break;
    run = fixedTwistOptimum(problem, optimum.solve.twist, way, context);
    const bool same = std::abs(run.solve.cost - optimum.solve.cost) <=
                      kSameCost * std::max(run.solve.cost, optimum.solve.cost);
    if (run.converged() && !same) return run;
  }
  run.solve.termination = Termination::NotConverged;
  return run;
}

/// `runs` cheapest first, the converged before the others.
void sortByCost(std::vector<TwistRun>* runs) {
  std::stable_sort(runs->begin(), runs->end(), [](const TwistRun& a, const TwistRun& b) {
    return a.converged() && (!b.converged() || a.solve.cost < b.solve.cost);
  });
}

/// The twist Newton's distinct converged answers (ψ free; the starts on `survey_steps`) carried
/// to the requested grid (each refinement recorded), cheapest first.
std::vector<TwistRun> freeTwistOptima(const PlanningProblem& problem, int survey_steps,
                                      const std::vector<TwistRun>& survey, SolveContext& context,
                                      const NewtonParameters& p) {
  std::vector<TwistRun> optima;
  for (const TwistRun* r : worthRefining(survey, std::numeric_limits<double>::infinity())) {
    if (context.stopReason()) break;
    TwistRun refined = *r;
    if (survey_steps != problem.steps) {
      refined = refine(problem, *r, context, p, true);
      record(refined, AttemptStage::ClassRefine, AttemptStart::CoarseLevel, survey_steps, context);
    }
    if (refined.converged()) optima.push_back(std::move(refined));
  }
  sortByCost(&optima);
  return optima;
}

/// The unconstrained optima that start a constrained request where none from `optima` (the
/// free-ψ ones) converged under the constraints: each of those the other way round at its ψ
/// (otherWayRound), and the fixed-attitude optimum at each start twist the nearest way round
/// (fixedTwistOptimum: a cone across the free-ψ optimum's path leaves the twists whose paths pass
/// it, and the interior point keeps the side of a cone its start passes). Cheapest first.
std::vector<TwistRun> fixedTwistOptima(const PlanningProblem& problem,
                                       const std::vector<TwistRun>& optima, SolveContext& context) {
  std::vector<TwistRun> starts;
  for (const TwistRun& optimum : optima) {
    if (!context.stopReason()) starts.push_back(otherWayRound(problem, optimum, context));
  }
  const double base = nearestTwist(problem.initial_attitude, problem.end_condition);
  for (int i = 0; i < kPointingStartTwists && !context.stopReason(); ++i) {
    const double twist = std::remainder(base + 2.0 * M_PI * i / kPointingStartTwists, 2.0 * M_PI);
    starts.push_back(fixedTwistOptimum(problem, twist, kPointingClasses[0], context));
  }
  sortByCost(&starts);
  return starts;
}

/// Whether the interior point's runs in `finals` (each with ψ free from an unconstrained optimum)
/// hold its certificate of local infeasibility (its elastic form's violation stopped decreasing:
/// Termination::Infeasible) from at least kPointingStartTwists distinct starts (twist and way
/// round); runs that stopped otherwise certify nothing either way. Called where none converged:
/// each start twist's fixed-twist constrained optimum (a whole fixed-attitude request per twist)
/// is then not tried. On the seeded requests of seeds 41, 43 and 47 (72 with one binding
/// constraint) those never gave the answer, and on the infeasible ones they took a third of the
/// request's iterations. The verdict stays local to the starts tried.
bool locallyInfeasibleFromEnoughStarts(
    const std::vector<std::pair<TwistRun, std::size_t>>& finals) {
  std::vector<const TwistRun*> certified;
  for (const auto& [run, index] : finals) {
    if (run.solve.termination != Termination::Infeasible) continue;
    const auto same = [&run = run](const TwistRun* o) {
      return o->homotopy.long_way == run.homotopy.long_way &&
             std::abs(std::remainder(o->start_twist - run.start_twist, 2.0 * M_PI)) <
                 kSameSurveyTwist;
    };
    if (std::none_of(certified.begin(), certified.end(), same)) certified.push_back(&run);
  }
  return certified.size() >= static_cast<std::size_t>(kPointingStartTwists);
}

/// Whether `optimum` (an unconstrained twist optimum on the requested grid) meets every node
/// constraint: then it is the constrained optimum of its basin too (planUnderConstraints' rule at
/// a fixed attitude), and no interior point is run from it.
bool meetsEveryNodeConstraint(const PlanningProblem& problem, const TwistRun& optimum) {
  const PlanningProblem at = posedAt(problem, problem.steps, optimum.solve.twist);
  ReducedProblem np(at);
  np.setCurrent(optimum.iterate);
  return checkConstraints(at, np.maneuver(optimum.iterate)).max_node_bound_violation <= 0.0;
}

/// The least relative cone margin over the nodes of `run`'s plan (on the requested grid, posed at
/// its twist) against the node bounds the planner imposes: (coneMargin less the cone's margin)
/// over its node half angle, −1 on the cone's axis; +∞ without cones.
double leastConeMargin(const PlanningProblem& problem, const TwistRun& run) {
  const PlanningProblem at = posedAt(problem, problem.steps, run.solve.twist);
  ReducedProblem np(at);
  np.setCurrent(run.iterate);
  const Maneuver plan = np.maneuver(run.iterate);
  double least = std::numeric_limits<double>::infinity();
  for (const PlanningConstraint& c : problem.constraints) {
    if (!c.isCone()) continue;
    for (const Matrix3& R : plan.attitude) {
      least = std::min(least, (coneMargin(c, R) - c.margin) / c.nodeHalfAngle());
    }
  }
  return least;
}

/// Where `optimum` (an unconstrained twist optimum that crosses a cone) sits on a ridge of the
/// constrained cost over ψ: its path crosses the cone deeper than the fixed-twist unconstrained
/// optima kPointingRidgeOffset either side of its twist (fixedTwistOptimum, its way round) do. The
/// plan around the cone then passes it on one side or the other, each side's optimum at another
/// twist, and the interior point with ψ free started on the ridge stalls between them (measured:
/// held-out requests 53506 and 53518, 225 and 124 iterations against 49 for the fixed request at
/// the answer's twist). Checked only where the path comes near the cone's axis
/// (kPointingRidgeDepth). The two sides cheapest first; empty where `optimum` is no ridge.
std::vector<TwistRun> ridgeSides(const PlanningProblem& problem, const TwistRun& optimum,
                                 SolveContext& context) {
  const double deepest = leastConeMargin(problem, optimum);
  if (!(deepest < -kPointingRidgeDepth)) return {};
  std::vector<TwistRun> sides;
  for (const double offset : {-kPointingRidgeOffset, kPointingRidgeOffset}) {
    if (context.stopReason()) return {};
    const double twist = std::remainder(optimum.solve.twist + offset, 2.0 * M_PI);
    TwistRun side = fixedTwistOptimum(problem, twist, optimum.homotopy, context);
    if (!side.converged() || leastConeMargin(problem, side) <= deepest) return {};
    sides.push_back(std::move(side));
  }
  sortByCost(&sides);
  return sides;
}

/// The watch of an interior point with ψ free (FeasibleIterateWatch): a reason where the solve
/// can no longer end below `least` (cannotEndBelow: a constrained answer already held, or one
/// that will be, an optimum meeting every node constraint); else empty.
FeasibleIterateWatch endingBelow(double least) {
  return [least](const FeasibleIterate& at) {
    return cannotEndBelow(at.bound(), least, "the least constrained cost held");
  };
}

/// The interior point with ψ free from `start` (fromUnconstrainedRun; stopped where it can no
/// longer end below `least`: cannotEndBelow), or `start` itself where `as_it_is` (an optimum
/// meeting every node constraint), recorded and appended to `finals`; `*cheapest` updated.
void solveFrom(const PlanningProblem& problem, const TwistRun& start, bool as_it_is, double least,
               SolveContext& context, double* cheapest,
               std::vector<std::pair<TwistRun, std::size_t>>* finals) {
  TwistRun run = start;  // its way round, start twist and grid
  const int counted_before = context.iterations();
  if (as_it_is) {
    run.start = AttemptStart::UnconstrainedOptimum;
  } else {
    const FeasibleIterateWatch watch = endingBelow(least);
    fromUnconstrainedRun(posedAt(problem, problem.steps, start.solve.twist), start,
                         context.options(), context, &run, std::isfinite(least) ? &watch : nullptr);
  }
  run.solve.iterations = context.iterations() - counted_before;
  const std::size_t at = record(run, AttemptStage::Constrained, run.start, 0, context);
  if (run.converged()) *cheapest = std::min(*cheapest, run.solve.cost);
  finals->emplace_back(std::move(run), at);
}

/// The interior point with ψ free (fromUnconstrainedRun) from each of `starts` (cheapest first) in
/// turn, each run appended to `finals` (where `twist_optimal`, the starts optimal in ψ too, a start
/// meeting every node constraint itself: meetsEveryNodeConstraint; one on a cone's ridge from
/// both its sides instead: ridgeSides), until `finals` hold certificates of local infeasibility
/// from enough starts (locallyInfeasibleFromEnoughStarts) or a start's unconstrained cost is at
/// least `*cheapest` (the least converged constrained cost so far, updated): constraints only add
/// cost to the plans of a start's basin, and the interior point keeps the way round it starts in
/// (a bound as long as the solve stays in that basin; a class's cost is no bound across classes).
void solveFromOptima(const PlanningProblem& problem, const std::vector<TwistRun>& starts,
                     SolveContext& context, double* cheapest,
                     std::vector<std::pair<TwistRun, std::size_t>>* finals, bool twist_optimal) {
  // Which starts are answers as they are (twist_optimal), and the least of their costs: an
  // interior point that can no longer end below it is stopped (cannotEndBelow) even where that
  // start comes later in the order.
  std::vector<bool> as_it_is(starts.size(), false);
  double least_as_it_is = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < starts.size() && twist_optimal; ++i) {
    as_it_is[i] = starts[i].converged() && meetsEveryNodeConstraint(problem, starts[i]);
    if (as_it_is[i]) least_as_it_is = std::min(least_as_it_is, starts[i].solve.cost);
  }
  for (std::size_t i = 0; i < starts.size(); ++i) {
    const TwistRun& start = starts[i];
    if (!start.converged() || start.solve.cost >= *cheapest || context.stopReason()) return;
    if (!anyConverged(*finals) && locallyInfeasibleFromEnoughStarts(*finals)) return;
    const double least = std::min(least_as_it_is, *cheapest);
    if (as_it_is[i]) {
      solveFrom(problem, start, true, least, context, cheapest, finals);
      continue;
    }
    const std::vector<TwistRun> sides =
        twist_optimal ? ridgeSides(problem, start, context) : std::vector<TwistRun>();
    if (sides.empty()) solveFrom(problem, start, false, least, context, cheapest, finals);
    for (const TwistRun& side : sides) {
      if (!context.stopReason()) {
        solveFrom(problem, side, false, std::min(least, *cheapest), context, cheapest, finals);
      }
    }
  }
}

/// A constrained request (stage constraints, torque bounds) as one problem: the interior point
/// with ψ free from the unconstrained twist optima (the twist Newton's survey, the constraints not
/// seen: freeTwistOptima), and where none of those converged, from the fixed-twist ones
/// (fixedTwistOptima), each set cheapest first and pruned by its unconstrained cost
/// (solveFromOptima). Returns the survey.
std::vector<TwistRun> constrainedFromTwistOptima(
    const PlanningProblem& problem, SolveContext& context, const NewtonParameters& p,
    std::vector<std::pair<TwistRun, std::size_t>>* finals) {
  const int survey_steps = surveySteps(problem, p);
  const std::vector<TwistRun> survey =
      runStarts(problem, survey_steps, surveyTolerance(problem, survey_steps, context, p),
                AttemptStage::ClassSurvey, context, p, nullptr, true);
  double cheapest = std::numeric_limits<double>::infinity();
  const std::vector<TwistRun> optima = freeTwistOptima(problem, survey_steps, survey, context, p);
  solveFromOptima(problem, optima, context, &cheapest, finals, true);
  if (!anyConverged(*finals) && !context.stopReason()) {
    solveFromOptima(problem, fixedTwistOptima(problem, optima, context), context, &cheapest, finals,
                    false);
  }
  return survey;
}

/// Whether `request` holds a plan on the request's grid strictly inside every bound (a plan at T*
/// time-scaled to a longer T: StartSpec::strictly_inside), which the interior point with ψ free
/// starts from (fromPlanInside).
bool startsInsideOnItsGrid(const PlanningProblem& problem, const SolveRequest& options) {
  return options.warm_start && options.start.from_constrained_plan &&
         options.start.strictly_inside && problem.hasNodeConstraints() &&
         options.warm_start->steps() == problem.steps;
}

/// The interior point with ψ free from `plan` (startsInsideOnItsGrid) at its own twist, its
/// multipliers re-derived from stationarity (as fromFixedTwistPlan), appended to `finals`.
void fromPlanInside(const PlanningProblem& problem, const Maneuver& plan, SolveContext& context,
                    std::vector<std::pair<TwistRun, std::size_t>>* finals) {
  const double twist = twistOf(plan.attitude.back(), problem.end_condition);
  const PlanningProblem at = posedAt(problem, problem.steps, twist);
  TwistRun run;
  run.homotopy = kPointingClasses[0];
  run.start_twist = run.solve.twist = twist;
  run.steps = problem.steps;
  run.start = AttemptStart::PreviousAttempt;
  const int counted_before = context.iterations();
  try {
    ReducedProblem np(at);
    np.setInteriorFromAttitudes(plan.attitude);
    const InteriorPointParameters parameters;
    const LevelDuals duals =
        ConstrainedSystem(at, &np, Formulation::FreeSlacks, parameters).estimatedDuals();
    const ReducedProblem::StepVectors steps = np.current();
    takeInteriorPoint(solveInteriorPointOnGrid(at, context.options(), context, &steps, &duals),
                      &run);
  } catch (const StepTooLarge& e) {
    run.solve.termination = Termination::StepTooLarge;
    run.solve.reason = std::string("boundary velocity: ") + e.what();
  }
  run.solve.iterations = context.iterations() - counted_before;
  const std::size_t index = record(run, AttemptStage::Solve, run.start, 0, context);
  finals->emplace_back(std::move(run), index);
}

}  // namespace

PlanResult planPointing(const PlanningProblem& problem, const SolveRequest& options,
                        SolveContext& context) {
  if (options.solver != SolverKind::Structured) {
    throw InvalidInput("solver: " + solverName(options.solver) +
                       " does not serve final.pointing (the twist is an unknown of the newton "
                       "solver only)");
  }
  if (options.warm_start && !startsInsideOnItsGrid(problem, options)) {
    throw InvalidInput("final.pointing: not supported with a warm start (initial_guess) yet");
  }
  SolverOptions cold = options;  // the starts' own solves take no warm start (nor its start)
  cold.warm_start = nullptr;
  const SolveContext::Call call(context, cold);
  const NewtonParameters& p = options.advanced.newton;
  const std::size_t first_recorded = context.attempts().size();
  const int counted_at_start = context.iterations();
  std::vector<std::pair<TwistRun, std::size_t>> finals;  // on the requested grid, trail index
  if (options.warm_start) {
    const SolveContext::Call inside(context, options);
    fromPlanInside(problem, *options.warm_start, context, &finals);
  }
  std::vector<TwistRun> survey;
  if (!anyConverged(finals) && !context.stopReason()) {
    survey = problem.hasNodeConstraints() ? constrainedFromTwistOptima(problem, context, p, &finals)
                                          : unconstrainedStarts(problem, context, p, &finals);
  }
  if (problem.hasNodeConstraints() && !anyConverged(finals) && !context.stopReason() &&
      !locallyInfeasibleFromEnoughStarts(finals)) {
    // No interior point from an unconstrained optimum converged: each twist from its fixed-twist
    // constrained optimum, every way round solved under the constraints there (on the requested
    // grid: coarse grids tighten the cones' margins and change which torque bounds are feasible).
    const std::vector<TwistRun> fixed = runStarts(problem, problem.steps, options.tolerance,
                                                  AttemptStage::Solve, context, p, &finals);
    survey.insert(survey.end(), fixed.begin(), fixed.end());
  }
  PlanResult result = finishPointing(problem, survey, finals, first_recorded, context);
  result.iterations = context.iterations() - counted_at_start;  // every start, as reported
  return result;
}

}  // namespace attitude_planner
