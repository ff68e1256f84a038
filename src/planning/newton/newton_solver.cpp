// The unconstrained solver's order of attempts, as data (kNewtonRecipe): the request's own solve
// through the grids, then — each behind a named gate — the continuation in the boundary rates
// and the coasting start for a spinning request that stalled, the other way round where the two
// lifts are about equally near, and more starts for a slow spinning solve. Every attempt runs in
// the request's SolveContext (one clock and deadline, one cancel flag, iterations numbered
// across attempts) and is recorded in its trail; the cheapest converged plan is kept.
#include "planning/newton/newton_solver.hpp"

#include <cmath>
#include <limits>
#include <optional>
#include <sstream>

#include "attitude_planner/errors.hpp"
#include "planning/newton/grid_solve.hpp"
#include "planning/newton/newton_parameters.hpp"
#include "planning/strategies/grid_continuation.hpp"
#include "planning/strategies/staged_continuation.hpp"
#include "planning/strategies/starts.hpp"

namespace attitude_planner {

namespace {

using Steps = ReducedProblem::Steps;

// --- Grid continuation for Newton ----------------------------------------------------------------

/// A coarse level helps only while its boundary steps stay small: at h·|Ω| ≳ 1 rad the coarse
/// problem is a different (and much harder) one.
bool coarseStepsStaySmall(const PlanningProblem& coarse, const NewtonParameters& p) {
  const double h = coarse.duration / coarse.steps;
  return h * std::max(coarse.initial_velocity.norm(), coarse.final_velocity.norm()) <=
         p.coarse_max_step_angle;
}

GridLevelRule newtonGridRule(const NewtonParameters& p) {
  GridLevelRule rule;
  rule.coarsest_steps = p.coarsest_steps;
  rule.coarsening_factor = p.coarsening_factor;
  rule.coarse_tolerance_floor = p.coarse_tolerance_floor;
  rule.level_helps = [&p](const PlanningProblem& coarse) {
    return coarseStepsStaySmall(coarse, p);
  };
  return rule;
}

/// Newton on the requested grid, through the coarser levels first unless warm-started.
PlanResult solveThroughGrids(const PlanningProblem& problem, SolveContext& context,
                             const GridSettings& settings, const Maneuver* warm_start,
                             const NewtonParameters& p) {
  if (warm_start) return solveOnGrid(problem, context, settings, {warm_start}, nullptr, p);
  const LevelSolver<Steps> level = [&](const LevelRequest<Steps>& r, Steps* final_steps) {
    GridSettings at_level = settings;
    at_level.tolerance = r.tolerance;
    if (r.replay_only) at_level.max_iterations = 0;
    return solveOnGrid(r.problem, context, at_level, {nullptr, r.coarse, r.coarser}, final_steps,
                       p);
  };
  return solveByGridContinuation(problem, context, newtonGridRule(p), settings.tolerance, level);
}

// --- The recipe --------------------------------------------------------------------------------

/// How an attempt reaches a plan for the requested grid.
enum class Method {
  ThroughGrids,       ///< grid continuation from the Hermite curve (or the warm start)
  RequestedGridOnly,  ///< the Hermite curve on the requested grid, no coarser level
  RateContinuation,   ///< from rest to rest, the boundary rates raised in stages
  InertiaHomotopy,    ///< from the sphere of the same mean inertia, J reached in stages
  Coasting,           ///< from the coasting start, with a longer iteration limit
};

/// Which homotopy class an attempt's problem asks for.
enum class Variant { Request, OtherWay, ExtraRevolution };

/// What the gates read: the request and the attempts so far.
struct RecipeState {
  const PlanningProblem& problem;
  const SolverOptions& options;
  const NewtonParameters& p;
  const PlanResult* kept = nullptr;  ///< the plan kept so far
  int iterations = 0;                ///< over the attempts so far
  bool other_way_solved = false;
  bool lifts_about_equally_near = false;
};

using Gate = bool (*)(const RecipeState&);

bool always(const RecipeState&) {
  return true;
}

/// The request asks for the default homotopy class (shortest way, no extra turns) from no
/// guess of its own: only then may other classes compete.
bool defaultClassFromScratch(const RecipeState& s) {
  return s.problem.direction == RotationDirection::Shortest && s.problem.extra_revolutions == 0 &&
         !s.options.warm_start;
}

/// A spinning request that stalled from the Hermite start: fast rates over long horizons end at
/// the iteration limit; easier problems (rest to rest, or the coasting motion) lead to it.
bool stalledWithSpinningEnds(const RecipeState& s) {
  return s.kept->termination == Termination::NotConverged && hasSpinningEnds(s.problem) &&
         !s.options.warm_start;
}

/// The two nearest lifts are about equally near the coasting displacement (rest to rest: an
/// angle near π): which way is cheaper depends on the inertia, so both are solved.
bool liftsAboutEquallyNear(const RecipeState& s) {
  return defaultClassFromScratch(s) && s.lifts_about_equally_near;
}

/// A converged spinning solve that took many iterations wandered far from its start: the
/// extremal it reached may not be the cheapest, so more starts compete.
bool slowSpinningSolve(const RecipeState& s) {
  return s.kept->converged() && hasSpinningEnds(s.problem) && defaultClassFromScratch(s) &&
         s.iterations > s.p.more_starts_above_iterations;
}

bool slowSpinningSolveOtherWayUnsolved(const RecipeState& s) {
  return slowSpinningSolve(s) && !s.other_way_solved;
}

/// The first start came through coarser grids: on the requested grid directly Newton may reach
/// another extremal.
bool slowSpinningSolveThroughGrids(const RecipeState& s) {
  return slowSpinningSolve(s) && usesCoarserLevel(s.problem, newtonGridRule(s.p));
}

struct RecipeEntry {
  AttemptStage stage;
  Method method;
  Variant variant;
  Globalization globalization;
  Gate when;
};

/// The order of attempts. The first is the request's own solve; each further one runs when its
/// gate holds and the solve was neither cancelled nor out of time.
constexpr RecipeEntry kNewtonRecipe[] = {
    {AttemptStage::Solve, Method::ThroughGrids, Variant::Request, Globalization::TrustRegion,
     always},
    {AttemptStage::RateContinuation, Method::RateContinuation, Variant::Request,
     Globalization::TrustRegion, stalledWithSpinningEnds},
    {AttemptStage::CoastingRetry, Method::Coasting, Variant::Request, Globalization::TrustRegion,
     stalledWithSpinningEnds},
    {AttemptStage::BothWays, Method::ThroughGrids, Variant::OtherWay, Globalization::TrustRegion,
     liftsAboutEquallyNear},
    {AttemptStage::MoreStarts, Method::ThroughGrids, Variant::OtherWay, Globalization::TrustRegion,
     slowSpinningSolveOtherWayUnsolved},
    {AttemptStage::MoreStarts, Method::ThroughGrids, Variant::ExtraRevolution,
     Globalization::TrustRegion, slowSpinningSolve},
    {AttemptStage::MoreStarts, Method::RequestedGridOnly, Variant::Request,
     Globalization::TrustRegion, slowSpinningSolveThroughGrids},
    {AttemptStage::MoreStarts, Method::ThroughGrids, Variant::Request, Globalization::LineSearch,
     slowSpinningSolve},
    {AttemptStage::MoreStarts, Method::InertiaHomotopy, Variant::Request,
     Globalization::TrustRegion, slowSpinningSolve},
    {AttemptStage::MoreStarts, Method::Coasting, Variant::Request, Globalization::TrustRegion,
     slowSpinningSolve},
};

/// The lifts' distances differ by less than 2ε_π (false if the boundary steps have no solution:
/// the first solve reports that).
bool liftsAmbiguous(const PlanningProblem& problem, const NewtonParameters& p) {
  try {
    const ReducedProblem reduced(problem);
    const std::vector<Lift> lifts = nearestLifts(problem, reduced);
    return std::abs(lifts[1].distance - lifts[0].distance) < 2 * p.both_ways_below_pi;
  } catch (const StepTooLarge&) {
    return false;
  }
}

PlanningProblem variantOf(const PlanningProblem& problem, Variant variant) {
  PlanningProblem out = problem;
  if (variant == Variant::OtherWay) out.direction = RotationDirection::LongWay;
  if (variant == Variant::ExtraRevolution) out.extra_revolutions = 1;
  return out;
}

/// A staged continuation that did not reach the request: no plan for it.
PlanResult unfinished(const StagedOutcome& staged, const std::string& what) {
  PlanResult r;
  r.termination = staged.stopped.value_or(Termination::NotConverged);
  r.iterations = staged.iterations;
  std::ostringstream msg;
  msg << what << " reached s = " << std::max(staged.reached, 0.0) << " of 1 (" << staged.stages
      << " stages): " << staged.plan.message;
  r.message = msg.str();
  r.cost = std::numeric_limits<double>::quiet_NaN();
  return r;
}

PlanResult byRateContinuation(const PlanningProblem& problem, SolveContext& context,
                              const GridSettings& settings, const NewtonParameters& p) {
  const StageProblem at = [&problem](double s) {
    PlanningProblem stage = problem;
    stage.initial_velocity = s * problem.initial_velocity;
    stage.final_velocity = s * problem.final_velocity;
    return stage;
  };
  const AdaptiveSchedule schedule{
      p.rate_continuation_first_increment, p.rate_continuation_max_increment,
      p.rate_continuation_min_increment, p.rate_continuation_max_stages};
  const StagedOutcome staged = solveByAdaptiveStages(
      context, at, schedule, [&](const PlanningProblem& stage, const Maneuver* from) {
        return solveThroughGrids(stage, context, settings, from, p);
      });
  if (!staged.complete()) return unfinished(staged, "continuation in the boundary rates");
  PlanResult r = staged.plan;
  r.iterations = staged.iterations;
  return r;
}

PlanResult byInertiaHomotopy(const PlanningProblem& problem, SolveContext& context,
                             const GridSettings& settings, const NewtonParameters& p) {
  // A convex combination with a sphere keeps J's axes, and the triangle inequality if J meets it.
  const Matrix3 sphere = (problem.inertia.trace() / 3.0) * Matrix3::Identity();
  const StageProblem at = [&](double s) {
    PlanningProblem stage = problem;
    stage.inertia = (1.0 - s) * sphere + s * problem.inertia;
    return stage;
  };
  const StagedOutcome staged = solveByFixedStages(
      at, p.inertia_homotopy_stages, [&](const PlanningProblem& stage, const Maneuver* from) {
        return solveThroughGrids(stage, context, settings, from, p);
      });
  if (!staged.complete()) return unfinished(staged, "the inertia homotopy");
  PlanResult r = staged.plan;
  r.iterations = staged.iterations;
  return r;
}

/// The iteration limit of the coasting start's solve (factor × the per-level limit, saturated).
int coastingIterationLimit(int max_iterations, const NewtonParameters& p) {
  return max_iterations > std::numeric_limits<int>::max() / p.coasting_iteration_factor
             ? std::numeric_limits<int>::max()
             : p.coasting_iteration_factor * max_iterations;
}

/// Runs one entry of the recipe; nothing if it has no start (no coasting motion at this h).
std::optional<PlanResult> runEntry(const RecipeEntry& entry, const PlanningProblem& request,
                                   SolveContext& context, const NewtonParameters& p) {
  const SolverOptions& options = context.options();
  const PlanningProblem problem = variantOf(request, entry.variant);
  GridSettings settings{options.tolerance, options.max_iterations, entry.globalization};
  switch (entry.method) {
    case Method::ThroughGrids:
      return solveThroughGrids(problem, context, settings,
                               entry.stage == AttemptStage::Solve ? options.warm_start : nullptr,
                               p);
    case Method::RequestedGridOnly:
      return solveOnGrid(problem, context, settings, {}, nullptr, p);
    case Method::RateContinuation:
      return byRateContinuation(problem, context, settings, p);
    case Method::InertiaHomotopy:
      return byInertiaHomotopy(problem, context, settings, p);
    case Method::Coasting: {
      const std::optional<Maneuver> coasting = coastingStart(problem);
      if (!coasting) return std::nullopt;
      settings.max_iterations = coastingIterationLimit(options.max_iterations, p);
      return solveThroughGrids(problem, context, settings, &*coasting, p);
    }
  }
  return std::nullopt;
}

AttemptStart startOf(const RecipeEntry& entry, const PlanningProblem& problem,
                     const SolverOptions& options, const NewtonParameters& p) {
  switch (entry.method) {
    case Method::RequestedGridOnly:
      return AttemptStart::Hermite;
    case Method::RateContinuation:
      return AttemptStart::PreviousAttempt;
    case Method::InertiaHomotopy:
      return AttemptStart::InertiaHomotopy;
    case Method::Coasting:
      return AttemptStart::Coasting;
    case Method::ThroughGrids:
      break;
  }
  if (entry.stage == AttemptStage::Solve && options.warm_start) return AttemptStart::WarmStart;
  return usesCoarserLevel(problem, newtonGridRule(p)) ? AttemptStart::CoarseLevel
                                                      : AttemptStart::Hermite;
}

Attempt attemptOf(const RecipeEntry& entry, const PlanningProblem& request,
                  const SolverOptions& options, const PlanResult& r, const NewtonParameters& p) {
  const PlanningProblem problem = variantOf(request, entry.variant);
  Attempt a;
  a.stage = entry.stage;
  a.start = startOf(entry, problem, options, p);
  a.globalization = entry.globalization;
  a.homotopy = {problem.direction == RotationDirection::LongWay, problem.extra_revolutions};
  a.steps = problem.steps;
  a.termination = r.termination;
  a.iterations = r.iterations;
  a.cost = r.maneuver.steps() == problem.steps ? r.cost : std::numeric_limits<double>::quiet_NaN();
  return a;
}

/// The one-line brief: how the kept attempt ended, what stopped the walk, which attempt it was.
std::string briefOf(const PlanResult& kept, const std::vector<Attempt>& trail, std::size_t kept_at,
                    std::optional<Termination> stop) {
  std::ostringstream brief;
  if (stop && trail[kept_at].termination != *stop) {
    brief << (*stop == Termination::Cancelled ? "cancelled" : "time budget exceeded")
          << " during the " << attemptStageName(trail.back().stage)
          << " attempt; the plan returned: ";
  }
  brief << kept.message;
  if (trail.size() > 1) {
    brief << "; attempt " << kept_at + 1 << " of " << trail.size() << " kept ("
          << attemptStageName(trail[kept_at].stage) << " from "
          << attemptStartName(trail[kept_at].start) << ")";
  }
  return brief.str();
}

/// The kept plan with the request's totals, the structured extremal and the brief.
PlanResult keptResult(PlanResult kept, const std::vector<Attempt>& trail, std::size_t kept_at,
                      std::optional<Termination> stop) {
  int iterations = 0;
  for (const Attempt& a : trail) iterations += a.iterations;
  kept.iterations = iterations;
  for (std::size_t i = 0; i < trail.size(); ++i) {
    if (i != kept_at) kept.extremal_summary.others.push_back(trail[i]);
  }
  kept.extremal = describeExtremal(kept.extremal_summary);
  kept.message = briefOf(kept, trail, kept_at, stop);
  if (stop && !kept.converged()) kept.termination = *stop;
  return kept;
}

}  // namespace

std::vector<Vector3> newtonInitialSteps(const PlanningProblem& problem) {
  ReducedProblem np(problem);
  startOnHermiteCurve(problem, &np);
  return np.current();
}

PlanResult solveWithNewton(const PlanningProblem& problem, SolveContext& context) {
  const NewtonParameters& p = newtonDefaults();
  RecipeState state{problem, context.options(), p};
  state.lifts_about_equally_near = liftsAmbiguous(problem, p);
  const std::size_t first_recorded = context.attempts().size();
  std::vector<Attempt> trail;
  PlanResult kept;
  std::size_t kept_at = 0;
  for (const RecipeEntry& entry : kNewtonRecipe) {
    if (!trail.empty()) {
      if (context.stopReason()) break;
      if (!entry.when(state)) continue;
    }
    std::optional<PlanResult> r = runEntry(entry, problem, context, p);
    if (!r) continue;
    trail.push_back(attemptOf(entry, problem, context.options(), *r, p));
    context.record(trail.back());
    state.iterations += r->iterations;
    state.other_way_solved |= entry.variant == Variant::OtherWay;
    // The cheaper converged plan; ties go to the earlier attempt (deterministic at exactly π).
    const bool cheaper = r->converged() && (trail.size() == 1 || !kept.converged() ||
                                            r->cost < kept.cost * (1 - p.cheaper_tie));
    if (trail.size() == 1 || cheaper) {
      kept = std::move(*r);
      kept_at = trail.size() - 1;
      state.kept = &kept;
    }
  }
  // An attempt cancelled or out of time ends the walk; after a converged plan it only spared
  // further attempts, otherwise the request ends with its termination.
  std::optional<Termination> stop;
  const Termination last = trail.back().termination;
  if (last == Termination::Cancelled || last == Termination::TimedOut) stop = last;
  if (kept.converged()) stop.reset();
  trail[kept_at].kept = true;
  context.markKept(first_recorded + kept_at);
  PlanResult out = keptResult(std::move(kept), trail, kept_at, stop);
  out.attempts = context.attempts();
  return out;
}

PlanResult solveWithNewton(const PlanningProblem& problem, const SolverOptions& options) {
  SolveContext context(options);
  return solveWithNewton(problem, context);
}

}  // namespace attitude_planner
