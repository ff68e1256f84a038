// The constrained recipe: the order of the fixed-h interior point's attempts on a request with
// node constraints, each a stage behind a named gate (the method itself is interior_point/:
// constrained_system.hpp derives it, grid_solve.cpp runs it on one grid). Three layers:
// - per grid, a formulation recipe (kRequestRecipe, kProbeRecipe): the first form, and the other
//   form from the same start where mayRetryInOtherForm holds;
// - per request, the levels of the shared grid continuation (strategies/grid_continuation.hpp):
//   a level starts from the coarser level's iterate and duals, else from its own unconstrained
//   optimum; a 4× refinement that stops goes once more through the level in between where
//   mayRefineThroughMiddle holds;
// - the attempts (kConstrainedRecipe): every constraint from the request's start; the cones
//   alone where stuckBetweenConesAndBounds holds; every constraint from the cones' path where
//   pathAroundCones holds.
#include "planning/drivers/constrained_recipe.hpp"

#include <algorithm>
#include <limits>
#include <string>
#include <vector>

#include "planning/interior_point/grid_solve.hpp"
#include "planning/newton/newton_solver.hpp"
#include "planning/problem/message_notes.hpp"
#include "planning/problem/verdict.hpp"
#include "planning/strategies/grid_continuation.hpp"

namespace attitude_planner {

namespace {

/// One grid's solve in one formulation and barrier rule.
struct GridForm {
  Formulation formulation;
  BarrierRule barrier;
  const char* name;  ///< for messages
};

/// The order of formulations on one grid: the first, and the retry when the first ends
/// infeasible or unconverged (from the same start).
struct FormulationRecipe {
  GridForm first, retry;
};

/// A request's own solve: free slacks with Mehrotra's predictor–corrector first (fewer iterations
/// and the same or lower optima), the elastic form (LOQO's barrier) as the retry: it certifies
/// infeasibility where the free-slack form's line search fails, while the free-slack form
/// converges where the elastic form's curvature (z → ρ on violated constraints) stalls.
constexpr FormulationRecipe kRequestRecipe = {
    {Formulation::FreeSlacks, BarrierRule::Mehrotra, "free slacks"},
    {Formulation::Elastic, BarrierRule::Loqo, "the elastic form"},
};
/// The minimum-time search's feasibility probes (started from its last feasible plan,
/// StartSpec::from_constrained_plan): the elastic form first (an infeasible probe then
/// pays one form), the free slacks with a monotone barrier as the retry. Not for a start strictly
/// inside every bound (StartSpec::strictly_inside: the plan at T* time-scaled to
/// (1 + m) T*), which takes kRequestRecipe: from such a well-centred start LOQO's σ = 0.1 (0.05
/// (1 − ξ)/ξ)³ is ~1e-8 (ξ ≈ 0.9), μ fell from 0.43 to 6e-9 (× f/m) in one step with the
/// decrement still 0.1, and the elastic solve crawled with steps cut to 1/64 … 1/128 to the
/// iteration limit (Bilimoria–Wie N = 128 at 1.02 T*; the monotone retry likewise, at μ = 8e-8).
/// Mehrotra's predictor–corrector from the same start converges in 12 iterations to the same
/// plan (docs/results/near_minimum_time.md).
constexpr FormulationRecipe kProbeRecipe = {
    {Formulation::Elastic, BarrierRule::Loqo, "the elastic form"},
    {Formulation::FreeSlacks, BarrierRule::Monotone, "free slacks"},
};

/// What a solve of the interior point needs besides the problem.
struct Solve {
  const InteriorPointParameters& parameters;
  SolveContext& context;
};

/// The gate of a formulation recipe's retry: the first form ended infeasible or unconverged, and
/// neither the caller's watch (its bound: no other formulation wanted) nor the context (cancelled
/// or out of time) stopped it.
bool mayRetryInOtherForm(const GridOutcome& first, const SolveContext& context) {
  const Termination t = first.result.termination;
  return (t == Termination::Infeasible || t == Termination::NotConverged) &&
         !first.stopped_by_watch && !context.stopReason();
}

/// One grid in the recipe's first formulation, retried once in the other from the same start
/// when it ends infeasible or unconverged. The answer: a converged solve, else an
/// infeasibility certificate, else a stopped solve whose plan is within the bounds where the
/// first's is not (an "infeasible" or an iterate outside a bound is no answer beside a plan),
/// else the first solve's reason; every solve's iterations are kept and its levels recorded in
/// the context as it ends.
GridOutcome solveGridWithRetry(const PlanningProblem& problem, const SolveRequest& options,
                               const Solve& solve, const ReducedProblem::StepVectors* coarse_steps,
                               const LevelDuals* coarse_duals, bool final_grid = true,
                               const FeasibleIterateWatch* watch = nullptr) {
  const FormulationRecipe& recipe =
      options.start.from_constrained_plan && !options.start.strictly_inside ? kProbeRecipe
                                                                            : kRequestRecipe;
  const SolveContext::IterationTally tally(solve.context);  // both solves'
  GridOutcome first = solveOnGrid(problem, options, solve.parameters, solve.context,
                                  {recipe.first.formulation, recipe.first.barrier, coarse_steps,
                                   coarse_duals, final_grid, watch});
  first.formulation = recipe.first.formulation;
  solve.context.recordLevels(first.result.levels);
  if (!mayRetryInOtherForm(first, solve.context)) return first;
  const Termination t = first.result.termination;
  GridOutcome second = solveOnGrid(
      problem, options, solve.parameters, solve.context,
      {recipe.retry.formulation, recipe.retry.barrier, coarse_steps, nullptr, final_grid});
  second.formulation = recipe.retry.formulation;
  solve.context.recordLevels(second.result.levels);
  const bool second_within = !second.result.converged() && provesFeasible(problem, second.result) &&
                             !provesFeasible(problem, first.result);
  const bool take_second =
      second.result.converged() ||
      (t != Termination::Infeasible && second.result.termination == Termination::Infeasible) ||
      second_within;
  GridOutcome answer = take_second ? std::move(second) : std::move(first);
  const PlanResult& other = take_second ? first.result : second.result;
  answer.result.iterations = tally.iterations();
  addNote(&answer.result, notes::FormulationRetry{recipe.retry.name, recipe.first.name, take_second,
                                                  other.clauses, second_within});
  answer.duals = LevelDuals{};  // the retry's are not carried
  return answer;
}

/// What a level of the interior point's continuation hands the next: its iterate, the
/// formulation that reached it and, when it converged, its multipliers and slacks (free slacks).
struct LevelIterate {
  ReducedProblem::StepVectors steps;
  LevelDuals duals;
  Formulation formulation = Formulation::FreeSlacks;
  bool empty() const { return steps.empty(); }
};

/// The interior point's levels: 4× coarser while above parameters.coarsest_grid, each solved to
/// the request's tolerance; a level that ends infeasible answers for the finer ones.
GridLevelRule interiorPointGridRule(const InteriorPointParameters& parameters) {
  GridLevelRule rule;
  rule.coarsening_factor = parameters.coarsening_factor;
  rule.direct_up_to = parameters.coarsest_grid;
  rule.coarse_tolerance_floor = 0.0;
  rule.infeasible_ends = true;
  return rule;
}

/// The coarsest level starts from its own unconstrained optimum; Newton reaches it from the warm
/// start (the requested grid's unconstrained optimum) resampled, instead of repeating the grid
/// continuation that found the warm start. A warm start that is to start the interior point itself
/// (StartSpec::from_constrained_plan) starts the level resampled where the problem has
/// cones: only a cone has sides that the level's unconstrained optimum could drop. Under torque and
/// rate bounds alone the warm start resampled starts Newton on the level, as an unconstrained warm
/// start does (measured on the bounded suite's seed-45 #33, N = 540 under a torque box: with every
/// constrained warm start starting its coarsest level, the minimum-time search's probes ended
/// elsewhere and T* rose from 59.62 s to 64.62 s, above the requested 61.38 s). Sets
/// level_options->warm_start to null.
PlanResult unconstrainedStart(const PlanningProblem& problem, const PlanningProblem& at,
                              const SolveRequest& options, SolveContext& context,
                              SolveRequest* level_options, Maneuver* resampled) {
  if (options.warm_start && options.warm_start->steps() == problem.steps) {
    resampled->attitude = resampleAttitudes(*options.warm_start, at.steps);
    level_options->warm_start = resampled;
    if (options.start.from_constrained_plan && problem.hasCones()) {
      // A plan under the constraints starts the level itself: its unconstrained optimum would
      // drop which side of each cone the plan passes.
      PlanResult start;
      start.termination = Termination::Converged;
      start.maneuver = *resampled;
      level_options->warm_start = nullptr;
      return start;
    }
  }
  PlanResult unconstrained = solveWithNewton(at, *level_options, context);
  level_options->warm_start = nullptr;
  return unconstrained;
}

/// Without a coarser iterate a level starts from its unconstrained optimum (unconstrainedStart):
/// *level_options warm-start from that plan where it converged (the plan and the resampled warm
/// start they may point at are kept in *start).
struct OwnStart {
  PlanResult plan;
  Maneuver resampled;
};
void startFromOwnOptimum(const PlanningProblem& problem, const SolveRequest& options,
                         const Solve& solve, const LevelRequest<LevelIterate>& r,
                         SolveRequest* level_options, OwnStart* start) {
  if (r.coarse) return;
  start->plan = unconstrainedStart(problem, r.problem, options, solve.context, level_options,
                                   &start->resampled);
  level_options->warm_start = start->plan.converged() ? &start->plan.maneuver : nullptr;
}

/// The gate of a level's second way: a 4× refinement (from a coarser level, to an even N) that
/// stopped by itself can start too far from the fine optimum where bounds bind near the ends.
bool mayRefineThroughMiddle(const GridOutcome& direct, const LevelRequest<LevelIterate>& r) {
  return !direct.result.converged() && !stoppedByRequest(direct.result.termination) && r.coarse &&
         r.problem.steps % 2 == 0;
}

/// Once more through the level in between. Replaces *direct if that converges (the level's tally
/// counts every solve's iterations, the context records their levels).
void refineThroughMiddle(const PlanningProblem& at, const SolveRequest& options, const Solve& solve,
                         const ReducedProblem::StepVectors& coarse, GridOutcome* direct) {
  PlanningProblem half = at;
  half.steps = at.steps / 2;
  SolveRequest from_coarse = options;
  from_coarse.warm_start = nullptr;  // both start from the coarse steps
  const GridOutcome middle =
      solveGridWithRetry(half, from_coarse, solve, &coarse, nullptr, /*final_grid=*/false);
  if (!middle.result.converged()) return;
  GridOutcome fine = solveGridWithRetry(at, from_coarse, solve, &middle.steps, nullptr);
  if (!fine.result.converged()) return;
  addNote(&fine.result, notes::ReachedThroughMiddle{half.steps, direct->result.clauses});
  direct->result = fine.result;
  direct->steps = fine.steps;
  direct->formulation = fine.formulation;
}

/// Where a stopped continuation's answer comes from: the stopping level's reason, said on it.
std::vector<MessageClause> onLevel(const ContinuationStop& stop) {
  PlanResult said;
  takeReason(&said, stop.level.clauses);
  frameMessage(&said, frames::OnContinuationLevel{stop.level.steps});
  return said.clauses;
}

/// A level after a stop. Cancelled or out of time: the finer levels are skipped and the last
/// accepted iterate goes to the requested N at once. Infeasible: each finer level evaluates
/// the carried iterate without iterating and reports the coarse level's certificate. Its last
/// level recorded ends as the stop did.
GridOutcome replayLevel(const PlanningProblem& problem, const SolveRequest& options,
                        const Solve& solve, const LevelRequest<LevelIterate>& r) {
  const ContinuationStop& stop = *r.stop;
  const SolveContext::IterationTally tally(solve.context);  // the start's and the level's
  const std::size_t first_level = solve.context.levels().size();
  const auto endsAsTheStop = [&] {
    if (solve.context.levels().size() > first_level) solve.context.endLastLevelAs(stop.termination);
  };
  if (stoppedByRequest(stop.termination)) {
    GridOutcome carried;
    if (r.coarse) carried.steps = r.coarse->steps;
    if (r.coarse) carried.formulation = r.coarse->formulation;
    if (!r.finest) return carried;  // handed on as it is
    GridOutcome outcome = carryToGrid(r.problem, carried.steps, stop.termination, onLevel(stop));
    outcome.formulation = carried.formulation;
    solve.context.recordLevels(outcome.result.levels);
    endsAsTheStop();
    return outcome;
  }
  SolveRequest level_options = options;
  level_options.warm_start = nullptr;
  level_options.max_iterations = 0;
  OwnStart start;
  startFromOwnOptimum(problem, options, solve, r, &level_options, &start);
  GridOutcome outcome = solveGridWithRetry(
      r.problem, level_options, solve, r.coarse ? &r.coarse->steps : nullptr, nullptr, r.finest);
  outcome.result.iterations = tally.iterations();
  takeReason(&outcome.result, onLevel(stop));
  endsAsTheStop();
  return outcome;
}

/// One level of the continuation: from the coarser level's iterate and duals, else from its own
/// unconstrained optimum; a 4× refinement that stops is tried once more through the level in
/// between. The result carries every solve's iterations (the context records their levels).
GridOutcome solveLevel(const PlanningProblem& problem, const SolveRequest& options,
                       const Solve& solve, const LevelRequest<LevelIterate>& r) {
  if (r.replay_only) return replayLevel(problem, options, solve, r);
  SolveRequest level_options = options;
  level_options.warm_start = nullptr;
  level_options.tolerance = r.tolerance;
  const SolveContext::IterationTally tally(solve.context);  // the iterations of every solve on it
  OwnStart start;
  startFromOwnOptimum(problem, options, solve, r, &level_options, &start);
  const LevelDuals no_duals;
  GridOutcome outcome =
      solveGridWithRetry(r.problem, level_options, solve, r.coarse ? &r.coarse->steps : nullptr,
                         r.coarse ? &r.coarse->duals : &no_duals, r.finest);
  const LevelDuals direct_duals = outcome.duals;
  if (mayRefineThroughMiddle(outcome, r)) {
    refineThroughMiddle(r.problem, level_options, solve, r.coarse->steps, &outcome);
  }
  outcome.duals = direct_duals;  // the direct solve's: a refinement's are not carried
  outcome.result.iterations = tally.iterations();
  return outcome;
}

/// A level's verdict is the continuation's, with one exception: a finer level that ends
/// "infeasible" after a coarser grid met every constraint is its solver stopping (the ℓ1
/// violation stalled at a local minimum), not a certificate about the request.
void finishContinuation(const ContinuationRecord& record, PlanResult* result) {
  if (result->termination == Termination::Infeasible) {
    const std::size_t last = record.stop ? record.stopped_at : record.levels.size() - 1;
    int feasible_level = 0;  // the finest coarser level that met every constraint
    for (std::size_t i = 0; i < last; ++i) {
      if (record.levels[i].termination == Termination::Converged) {
        feasible_level = record.levels[i].steps;
      }
    }
    if (feasible_level > 0) {
      result->termination = Termination::NotConverged;
      frameMessage(result, frames::FinerLevelStopped{feasible_level});
    }
  }
  addNote(result, notes::GridContinuation{record.levels.front().steps});
}

/// A warm start on the requested grid strictly inside every bound (the time-scaled T* plan):
/// the requested grid's own start, which a coarser level's (its unconstrained optimum) is not.
bool startsInsideOnThisGrid(const PlanningProblem& problem, const SolveRequest& options) {
  return options.start.from_constrained_plan && options.start.strictly_inside &&
         options.warm_start && options.warm_start->steps() == problem.steps;
}

/// The interior point on the requested grid, through the grid continuation above
/// parameters.coarsest_grid (strategies/grid_continuation.hpp), except from a start strictly
/// inside on this grid: the continuation's coarsest level starts from its unconstrained optimum,
/// not from that plan (Bilimoria–Wie at 1.02 T*, N = 512 and 1024: "infeasible" on the N = 128
/// level, 0.43 beyond |τ_z| ≤ 1; from the plan, converged).
GridOutcome solveContinued(const PlanningProblem& problem, const SolveRequest& options,
                           const Solve& solve) {
  const GridLevelRule rule = interiorPointGridRule(solve.parameters);
  if (!usesCoarserLevel(problem, rule) || startsInsideOnThisGrid(problem, options)) {
    return solveGridWithRetry(problem, options, solve, nullptr, nullptr);
  }
  Formulation finest = Formulation::FreeSlacks;
  const LevelSolver<LevelIterate> level = [&](const LevelRequest<LevelIterate>& r,
                                              LevelIterate* handed_on) {
    GridOutcome outcome = solveLevel(problem, options, solve, r);
    if (handed_on) {
      const bool converged = outcome.result.converged();
      *handed_on = {std::move(outcome.steps), converged ? std::move(outcome.duals) : LevelDuals{},
                    outcome.formulation};
    } else {
      finest = outcome.formulation;
    }
    return std::move(outcome.result);
  };
  GridOutcome out;
  out.result = solveByGridContinuation(problem, solve.context, rule, options.tolerance, level,
                                       finishContinuation);
  out.formulation = finest;
  return out;
}

/// Where the interior point's iterate starts (for the trail).
AttemptStart startOf(const SolveRequest& options) {
  if (!options.warm_start) return AttemptStart::Hermite;
  return options.start.from_constrained_plan ? AttemptStart::PreviousAttempt
                                             : AttemptStart::UnconstrainedOptimum;
}

/// The trail's entry for one solve of `problem` (not kept).
Attempt attemptOf(const PlanningProblem& problem, const GridOutcome& outcome, AttemptStage stage,
                  AttemptStart start) {
  Attempt a;
  a.stage = stage;
  a.start = start;
  a.formulation = outcome.formulation;
  a.homotopy = homotopyClassOf(problem);
  a.steps = problem.steps;
  a.termination = outcome.result.termination;
  a.iterations = outcome.result.iterations;
  if (!outcome.result.maneuver.torque.empty()) a.cost = outcome.result.cost;
  return a;
}

/// Runs one continuation and records it in the context as one attempt (not kept); the levels'
/// unconstrained starts are parts of it. Returns its index in the context's trail.
GridOutcome attempt(const PlanningProblem& problem, const SolveRequest& options, const Solve& solve,
                    AttemptStage stage, AttemptStart start, std::size_t* recorded_at) {
  GridOutcome outcome = [&] {
    const SolveContext::Aside parts(solve.context);
    const SolveContext::Scope scope(solve.context, stage, homotopyClassOf(problem));
    return solveContinued(problem, options, solve);
  }();
  *recorded_at = solve.context.attempts().size();
  solve.context.record(attemptOf(problem, outcome, stage, start));
  return outcome;
}

/// Where a solve began in the context's trail and levels.
struct Begun {
  std::size_t attempts, levels;
  explicit Begun(const SolveContext& context)
      : attempts(context.attempts().size()), levels(context.levels().size()) {}
};

/// The solve's answer: the attempt at `kept` marked as the one returned, the solve's trail and
/// levels (since `begun`) from the context.
void keepAttempt(SolveContext& context, const Begun& begun, std::size_t kept, PlanResult* result) {
  context.markKept(kept);
  result->attempts = context.attemptsFrom(begun.attempts);
  result->levels = context.levelsFrom(begun.levels);
}

/// How an attempt of the constrained recipe poses the request and where it starts.
enum class Posed {
  AsRequested,    ///< every constraint, from the request's start
  ConesAlone,     ///< the cones alone (torque and rate bounds dropped), from the request's start
  FromConesPath,  ///< every constraint, from the cones-alone plan
};

/// What the attempts' gates read: the request and the answers so far.
struct RecipeState {
  const PlanningProblem& problem;
  const PlanResult* first = nullptr;   ///< the attempt as requested
  const PlanResult* around = nullptr;  ///< the cones alone
};

using Gate = bool (*)(const RecipeState&);

bool always(const RecipeState&) {
  return true;
}

/// Pointing cones together with torque or rate limits, from a start inside a cone: the iterate
/// can leave the cone with torques far beyond their bounds and never recover. A path around the
/// cones alone may lead to the request.
bool stuckBetweenConesAndBounds(const RecipeState& s) {
  const Termination t = s.first->termination;
  const bool stuck = t == Termination::Infeasible || t == Termination::NotConverged;
  const bool others = s.problem.hasTorqueBounds() ||
                      std::any_of(s.problem.constraints.begin(), s.problem.constraints.end(),
                                  [](const PlanningConstraint& c) { return !c.isCone(); });
  return stuck && s.problem.hasCones() && others;
}

/// The cones alone were met: their plan starts every constraint.
bool pathAroundCones(const RecipeState& s) {
  return s.around && s.around->converged();
}

struct RecipeEntry {
  AttemptStage stage;
  Posed posed;
  Gate when;
};

/// The attempts in order, each when its gate holds; a closed gate ends the recipe.
constexpr RecipeEntry kConstrainedRecipe[] = {
    {AttemptStage::Constrained, Posed::AsRequested, always},
    {AttemptStage::ConstrainedRetry, Posed::ConesAlone, stuckBetweenConesAndBounds},
    {AttemptStage::ConstrainedRetry, Posed::FromConesPath, pathAroundCones},
};

/// The request with its cones alone.
PlanningProblem conesOnly(const PlanningProblem& problem) {
  PlanningProblem cones_only = problem;
  cones_only.max_torque = Vector3::Constant(std::numeric_limits<double>::infinity());
  cones_only.constraints.clear();
  for (const PlanningConstraint& c : problem.constraints)
    if (c.isCone()) cones_only.constraints.push_back(c);
  return cones_only;
}

/// One entry's attempt, recorded in the context (its index in *recorded_at).
PlanResult runEntry(const RecipeEntry& entry, const RecipeState& s, const SolveRequest& options,
                    const Solve& solve, std::size_t* recorded_at) {
  if (entry.posed == Posed::ConesAlone) {
    return attempt(conesOnly(s.problem), options, solve, entry.stage, startOf(options), recorded_at)
        .result;
  }
  if (entry.posed == Posed::FromConesPath) {
    SolveRequest staged = options;
    staged.warm_start = &s.around->maneuver;
    return attempt(s.problem, staged, solve, entry.stage, AttemptStart::PreviousAttempt,
                   recorded_at)
        .result;
  }
  return attempt(s.problem, options, solve, entry.stage, startOf(options), recorded_at).result;
}

}  // namespace

PlanResult solveWithInteriorPoint(const PlanningProblem& problem, const SolveRequest& options,
                                  SolveContext& context) {
  const Solve solve{options.advanced.interior_point, context};
  const Begun begun(context);
  const SolveContext::IterationTally tally(context);  // every attempt's
  PlanResult answers[std::size(kConstrainedRecipe)];
  std::size_t recorded_at[std::size(kConstrainedRecipe)] = {};
  RecipeState state{problem};
  std::size_t ran = 0;
  for (const RecipeEntry& entry : kConstrainedRecipe) {
    if (!entry.when(state)) break;
    answers[ran] = runEntry(entry, state, options, solve, &recorded_at[ran]);
    if (entry.posed == Posed::AsRequested) state.first = &answers[ran];
    if (entry.posed == Posed::ConesAlone) state.around = &answers[ran];
    ++ran;
  }
  PlanResult& first = answers[0];
  if (ran < std::size(kConstrainedRecipe)) {  // the request's own attempt answers
    keepAttempt(context, begun, recorded_at[0], &first);
    return first;
  }
  // The staged answer replaces the first unless it did no better (then the first is kept: its
  // reason is the one measured from the requested start).
  const PlanResult& second = answers[ran - 1];
  const bool take_second = second.converged() || second.termination == Termination::Infeasible;
  const std::vector<MessageClause> first_said = first.clauses;
  PlanResult result = take_second ? second : first;
  keepAttempt(context, begun, recorded_at[take_second ? ran - 1 : 0], &result);
  result.iterations = tally.iterations();
  addNote(&result, notes::RetriedInTwoStages{first_said});
  return result;
}

GridOutcome solveInteriorPointOnGrid(const PlanningProblem& problem, const SolverOptions& options,
                                     SolveContext& context,
                                     const ReducedProblem::StepVectors* start_steps,
                                     const LevelDuals* start_duals,
                                     const FeasibleIterateWatch* watch) {
  SolveRequest from(options);
  from.warm_start = nullptr;  // the start is start_steps
  from.start.from_constrained_plan = false;
  const std::size_t first_level = context.levels().size();
  GridOutcome outcome =
      solveGridWithRetry(problem, from, {options.advanced.interior_point, context}, start_steps,
                         start_duals, true, watch);
  outcome.result.levels = context.levelsFrom(first_level);
  return outcome;
}

PlanResult solveWithInteriorPointFromGuess(const PlanningProblem& problem,
                                           const SolveRequest& options, SolveContext& context) {
  // The guess (a plan of this N, e.g. the remainder of the plan being flown) starts the
  // requested grid directly, as a converged coarser level starts a finer one: its steps, its
  // multipliers re-derived from stationarity (the guess carries none) and a small barrier.
  LevelDuals duals;
  ReducedProblem::StepVectors steps;
  try {
    ReducedProblem np(problem);
    np.setInteriorFromAttitudes(options.warm_start->attitude);
    const InteriorPointParameters& parameters = options.advanced.interior_point;
    duals = ConstrainedSystem(problem, &np, Formulation::FreeSlacks, parameters).estimatedDuals();
    steps = np.current();
  } catch (const StepTooLarge&) {
    return solveWithInteriorPoint(problem, options, context);  // reports it
  }
  const Solve solve{options.advanced.interior_point, context};
  SolveRequest from = options;
  from.warm_start = nullptr;  // the guess's steps start the grid
  from.start.from_constrained_plan = false;
  const Begun begun(context);
  GridOutcome outcome = solveGridWithRetry(problem, from, solve, &steps, &duals);
  PlanResult result = std::move(outcome.result);
  context.record(attemptOf(problem, outcome, AttemptStage::Constrained, AttemptStart::WarmStart));
  keepAttempt(context, begun, begun.attempts, &result);
  addNote(&result, notes::FromInitialGuess{});
  return result;
}

}  // namespace attitude_planner
