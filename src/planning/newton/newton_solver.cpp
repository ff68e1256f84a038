// The unconstrained solver's order of attempts. A request that leaves the homotopy class free
// (direction shortest, no extra revolutions, no warm start) is solved in every class of
// kEnumeratedClasses on a coarse grid of its grid continuation (the class survey), the classes
// within a margin of the cheapest survey cost are refined to the requested grid, and the cheapest
// converged plan is kept; the surveys, then the refinements, run at once on the request's threads.
// A request that names its class, or is warm-started, is solved in that class only. Then, as data
// (kNewtonRecipe), each behind a named gate: the continuation in the boundary rates and the
// coasting start for a spinning request that stalled, and more starts in the kept class for a slow
// spinning solve (independent solves: at once, on the request's threads). Every attempt runs in the
// request's SolveContext (one clock and deadline, one cancel flag, iterations numbered across
// attempts) and is recorded in its trail. A plan's check (planInconsistency) is deferred and run
// only where the walk's choice reads it (kept_plan.hpp): the kept plan's always.
#include "planning/newton/newton_solver.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <sstream>

#include "attitude_planner/errors.hpp"
#include "attitude_planner/planning/newton_parameters.hpp"
#include "planning/newton/grid_solve.hpp"
#include "planning/newton/kept_plan.hpp"
#include "planning/problem/message_notes.hpp"
#include "planning/strategies/grid_continuation.hpp"
#include "planning/strategies/staged_continuation.hpp"
#include "planning/strategies/starts.hpp"

namespace attitude_planner {

namespace {

using StepVectors = ReducedProblem::StepVectors;

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
  const LevelSolver<StepVectors> level = [&](const LevelRequest<StepVectors>& r,
                                             StepVectors* final_steps) {
    GridSettings at_level = settings;
    at_level.tolerance = r.tolerance;
    if (r.replay_only) at_level.max_iterations = 0;
    return solveOnGrid(r.problem, context, at_level, {nullptr, r.coarse, r.coarser}, final_steps,
                       p);
  };
  return solveByGridContinuation(problem, context, newtonGridRule(p), settings.tolerance, level);
}

// --- The class survey ----------------------------------------------------------------------------

/// The classes a request that leaves its class free is solved in: the two lifts nearest the
/// coasting displacement, each with no and with one extra revolution. Measured on spinning
/// problems (docs/results/extremal_classes.md): the cheapest extremal is in one of them.
constexpr HomotopyClass kEnumeratedClasses[] = {{false, 0}, {true, 0}, {false, 1}, {true, 1}};

/// The lift a class's start turns through (nothing if a boundary step has no solution).
std::optional<Vector3> liftOf(const PlanningProblem& in_class) {
  try {
    const ReducedProblem reduced(in_class);
    const std::vector<Lift> lifts = nearestLifts(in_class, reduced);
    return lifts[in_class.direction == RotationDirection::LongWay ? 1 : 0].rotation;
  } catch (const StepTooLarge&) {
    return std::nullopt;
  }
}

/// The enumerated classes with distinct lifts on `start_grid` (the grid whose Hermite curve starts
/// them): where both nearest lifts turn the same sense, the farther one is the nearer one plus a
/// revolution, and its solve would repeat the other's.
std::vector<HomotopyClass> distinctClasses(const PlanningProblem& start_grid) {
  std::vector<HomotopyClass> out;
  std::vector<Vector3> lifts;
  for (const HomotopyClass& c : kEnumeratedClasses) {
    const std::optional<Vector3> lift = liftOf(pinnedToClass(start_grid, c));
    const bool repeated =
        lift && std::any_of(lifts.begin(), lifts.end(), [&](const Vector3& other) {
          return (other - *lift).norm() <= 1e-9 * (1.0 + lift->norm());
        });
    if (repeated) continue;
    if (lift) lifts.push_back(*lift);
    out.push_back(c);
  }
  return out;
}

/// One class solved on the survey grid, and what carrying it to the requested grid needs.
struct Surveyed {
  HomotopyClass homotopy;
  PlanResult result;  ///< on the survey grid; its cost is C at that N (NaN unless converged)
  bool on_requested_grid = false;  ///< the survey grid is the requested one: result is a plan
  StepVectors steps;               ///< the survey grid's final iterate (coarser survey grid)
  StepVectors below;               ///< the level below it, for extrapolation ...
  bool below_converged = false;    ///< ... if it converged
};

/// The levels of the request's grid continuation (coarsest first) and the survey grid among
/// them: the coarsest level with at least class_survey_min_steps steps, else the request's own.
struct SurveyPlan {
  std::vector<PlanningProblem> levels;
  std::size_t survey = 0;
};

SurveyPlan surveyPlan(const PlanningProblem& problem, const NewtonParameters& p) {
  SurveyPlan plan{gridLevels(problem, newtonGridRule(p)), 0};
  while (plan.survey + 1 < plan.levels.size() &&
         plan.levels[plan.survey].steps < p.class_survey_min_steps) {
    ++plan.survey;
  }
  return plan;
}

/// The class through the grid continuation up to the survey grid, solved there to the coarse
/// levels' tolerance (it only ranks the classes and starts the next level); on the requested
/// grid, the class's whole solve.
Surveyed surveyClass(const HomotopyClass& homotopy, const SurveyPlan& plan, SolveContext& context,
                     const GridSettings& settings, const NewtonParameters& p) {
  Surveyed s;
  s.homotopy = homotopy;
  const PlanningProblem at = pinnedToClass(plan.levels[plan.survey], homotopy);
  if (plan.survey + 1 == plan.levels.size()) {
    s.on_requested_grid = true;
    s.result = solveThroughGrids(at, context, settings, nullptr, p);
    return s;
  }
  const LevelSolver<StepVectors> level = [&](const LevelRequest<StepVectors>& r,
                                             StepVectors* final_steps) {
    GridSettings at_level = settings;
    at_level.tolerance = std::max(r.tolerance, p.coarse_tolerance_floor);
    if (r.replay_only) at_level.max_iterations = 0;
    PlanResult out = solveOnGrid(r.problem, context, at_level, {nullptr, r.coarse, r.coarser},
                                 r.finest ? &s.steps : final_steps, p);
    if (!r.finest) {
      s.below = *final_steps;
      s.below_converged = out.converged();
    }
    return out;
  };
  s.result = solveByGridContinuation(at, context, newtonGridRule(p), settings.tolerance, level);
  s.result.cost = s.result.converged() && !s.steps.empty()
                      ? ReducedProblem(at).cost(s.steps)
                      : std::numeric_limits<double>::quiet_NaN();
  return s;
}

/// A converged surveyed class's plan on the survey grid (on a coarser one only its iterate is
/// kept).
Maneuver surveyedPlan(const Surveyed& s, const PlanningProblem& survey_grid) {
  if (s.on_requested_grid) return s.result.maneuver;
  return ReducedProblem(pinnedToClass(survey_grid, s.homotopy)).maneuver(s.steps);
}

/// A class carried to the requested grid, and its plan's deferred check.
struct Refined {
  PlanResult result;
  /// Its solver converged and its check was deferred: the step residual it measured.
  std::optional<StepResidual> unchecked;
  /// Its open-loop replay's figures are measured (replayFigures, beside its check).
  bool replayed = false;
};

/// A surveyed class carried from the survey grid through the finer levels to the requested one:
/// the grid continuation resumed from the survey grid's iterate. A finer level that does not
/// converge ends it with no plan (a fresh start there would be another attempt); stopped
/// (cancel, deadline), the iterate is carried over without iterating. `defer_check`: the plan's
/// check is left to the walk (Refined::unchecked).
Refined refineClass(const Surveyed& s, const SurveyPlan& plan, SolveContext& context,
                    const GridSettings& settings, const NewtonParameters& p, bool defer_check) {
  Refined out;
  std::vector<PlanningProblem> levels;
  for (const PlanningProblem& level : plan.levels) {
    levels.push_back(pinnedToClass(level, s.homotopy));
  }
  GridLevelRule rule = newtonGridRule(p);
  rule.unconverged_ends = true;
  const LevelSolver<StepVectors> level = [&](const LevelRequest<StepVectors>& r,
                                             StepVectors* final_steps) {
    GridSettings at_level = settings;
    at_level.tolerance = r.tolerance;
    if (r.replay_only) at_level.max_iterations = 0;
    if (r.finest && defer_check) at_level.deferred_check = &out.unchecked;
    return solveOnGrid(r.problem, context, at_level, {nullptr, r.coarse, r.coarser}, final_steps,
                       p);
  };
  const ContinuationFinish finish = [&](const ContinuationRecord& record, PlanResult* r) {
    if (record.stop) {
      frameMessage(
          r, frames::CarriedOverAfterStop{record.stop->termination, plan.levels[plan.survey].steps,
                                          plan.levels.back().steps, true});
      return;
    }
    if (record.reached < record.levels.size()) {
      r->cost = std::numeric_limits<double>::quiet_NaN();  // no plan on the requested grid
    }
    addNote(r, notes::RefinedFromSurvey{plan.levels[plan.survey].steps});
  };
  const SolvedLevel<StepVectors> survey{plan.survey, s.result.termination, s.steps, s.below,
                                        s.below_converged};
  out.result =
      resumeGridContinuation(levels, survey, context, rule, settings.tolerance, level, finish);
  return out;
}

/// The pieces the refined plan's stepwise replay (its check's) is measured in beside its
/// open-loop replay: the calling thread begins the open-loop replay, which steps in sequence, and
/// the other thread, which wakes later (40-90 us on the loaded 2-core machine), takes the pieces
/// in turn, the calling thread those left when its replay ends. The two cost the same (seed
/// request: 0.85 M instructions each), so the request waits about half a wake less.
constexpr int kStepwisePieces = 8;

/// The refined plan's deferred check beside its open-loop replay (replayFigures, what
/// planAtResolution measures for the plan it returns), in branches of `context`: most requests
/// keep this plan, and the replay then costs no time after the walk. The replay's figures are the
/// plan's only where its check passed; a replay that fails is left to the caller.
void checkBesideReplay(const PlanningProblem& problem, const HomotopyClass& homotopy,
                       SolveContext& context, Refined* refined) {
  PlanResult& plan = refined->result;
  const StepResidual residual = *refined->unchecked;
  refined->unchecked.reset();
  PlanResult replay;  // the replay's figures, apart from the plan its check may change
  replay.maneuver.torque = plan.maneuver.torque;
  bool replayed = false;
  const PlanningProblem in_class = pinnedToClass(problem, homotopy);
  const int steps = plan.maneuver.steps();
  std::vector<double> apart(steps);  // the stepwise replay's angles, each piece its own steps
  runBranches(context, 1 + kStepwisePieces, [&](int i, SolveContext&) {
    if (i > 0) {
      stepReplayAngles(in_class, plan.maneuver, steps * (i - 1) / kStepwisePieces,
                       steps * i / kStepwisePieces, &apart);
      return;
    }
    try {
      replayFigures(problem, &replay);
      replayed = true;
    } catch (const StepTooLarge&) {  // judged by the caller's own replay
    }
  });
  const StepwiseReplay stepwise = worstStepReplay(apart);
  checkDeferredPlan(in_class, residual, &plan, &stepwise);
  if (!replayed || !plan.converged()) return;
  plan.dynamics_residual = replay.dynamics_residual;
  plan.terminal_attitude_error = replay.terminal_attitude_error;
  plan.terminal_velocity_error = replay.terminal_velocity_error;
  plan.replay_miss = replay.replay_miss;
  refined->replayed = true;
}

// --- The walk: every attempt recorded, the cheapest converged plan kept --------------------------

/// A class's own solve on the requested grid (surveyed there, refined, or the request's solve).
struct ClassSolve {
  HomotopyClass homotopy;
  int iterations = 0;    ///< its own: survey and refinement, or the whole solve
  std::size_t plan = 0;  ///< its plan among the walk's
};

/// An attempt's plan on the requested grid, and its check where deferred.
struct WalkPlan {
  std::size_t at = 0;  ///< its attempt in the walk's trail
  PlanResult result;
  int own_iterations = 0;
  /// Its solver converged and its check was deferred (GridSettings::deferred_check): the step
  /// residual measured for its figures.
  std::optional<StepResidual> unchecked;
  /// Its open-loop replay's figures are measured (checkBesideReplay).
  bool replayed = false;
};

class Walk {
 public:
  Walk(const PlanningProblem& problem, SolveContext& context, const NewtonParameters& p)
      : problem_(problem),
        context_(context),
        p_(p),
        first_recorded_(context.attempts().size()),
        tally_(context) {}

  /// Records an attempt; its plan competes if it is on the requested grid. `own_iterations`:
  /// what the slow-solve gate reads if it is kept (the class's survey and refinement).
  /// `unchecked`: its solver converged and its plan's check was deferred (the step residual its
  /// solve measured): the check runs only if the walk's choice depends on it. `replayed`: its
  /// open-loop replay's figures are measured.
  void add(Attempt a, PlanResult r, int own_iterations,
           std::optional<StepResidual> unchecked = std::nullopt, bool replayed = false) {
    a.termination = r.termination;
    a.iterations = r.iterations;
    const bool plan = r.maneuver.steps() == problem_.steps;
    a.cost = plan || a.stage == AttemptStage::ClassSurvey
                 ? r.cost
                 : std::numeric_limits<double>::quiet_NaN();
    if (!r.converged()) unchecked.reset();
    a.plan_checked = !unchecked;
    trail_.push_back(a);
    context_.record(a);
    if (!plan) {
      if (plans_.empty()) unplanned_ = std::move(r);  // how the walk ends if no attempt plans
      return;
    }
    if (a.stage != AttemptStage::MoreStarts) {
      solved_.push_back({a.homotopy, own_iterations, plans_.size()});
    }
    standing_.push_back(!r.converged() ? PlanStanding::NotConverged
                        : unchecked    ? PlanStanding::Unchecked
                                       : PlanStanding::Checked);
    costs_.push_back(r.cost);
    plans_.push_back({trail_.size() - 1, std::move(r), own_iterations, unchecked, replayed});
  }

  bool hasPlan() const { return !plans_.empty(); }
  /// The plan kept so far (with a plan: hasPlan), checked: the cheapest converged plan, ties to
  /// the earlier attempt (deterministic at exactly π); the first plan if none converged.
  const PlanResult& kept() { return plans_[keptPlan()].result; }
  /// Whether a plan is kept and converged (its check run).
  bool keptConverged() { return hasPlan() && kept().converged(); }
  HomotopyClass keptClass() { return trail_[plans_[keptPlan()].at].homotopy; }
  bool empty() const { return trail_.empty(); }
  /// Whether `homotopy` was solved on the requested grid (not counting the more starts).
  bool solvedOnRequestedGrid(const HomotopyClass& homotopy) const {
    return std::any_of(solved_.begin(), solved_.end(), [&](const ClassSolve& c) {
      return sameHomotopyClass(c.homotopy, homotopy);
    });
  }
  /// The classes the more starts may search: the kept one, and the request's own when it was
  /// solved on the requested grid too and converged (its basins are not the kept class's).
  std::vector<ClassSolve> searchedClasses(const HomotopyClass& request) {
    std::vector<ClassSolve> out;
    for (const HomotopyClass& c : {keptClass(), request}) {
      const auto found = std::find_if(solved_.begin(), solved_.end(), [&](const ClassSolve& s) {
        return sameHomotopyClass(s.homotopy, c) && converged(s.plan);
      });
      const bool listed = std::any_of(out.begin(), out.end(), [&](const ClassSolve& s) {
        return sameHomotopyClass(s.homotopy, c);
      });
      if (found != solved_.end() && !listed) out.push_back(*found);
    }
    return out;
  }
  const std::vector<Attempt>& trail() const { return trail_; }
  /// Whether an attempt in `homotopy` started from `start`.
  bool triedFrom(AttemptStart start, const HomotopyClass& homotopy) const {
    return std::any_of(trail_.begin(), trail_.end(), [&](const Attempt& a) {
      return a.start == start && sameHomotopyClass(a.homotopy, homotopy);
    });
  }

  /// The kept plan with the request's totals, the structured extremal and the brief.
  /// `replayed` (optional): whether the kept plan's open-loop replay figures are measured.
  PlanResult finish(bool* replayed = nullptr);

 private:
  /// The kept plan's index among plans_, every check it depends on run (once each).
  std::size_t keptPlan() {
    return keptWithChecksOnDemand(costs_, &standing_, p_.cheaper_tie,
                                  [this](std::size_t i) { return check(i); });
  }
  /// Whether plan i converged, its check run if it was deferred.
  bool converged(std::size_t i) {
    if (standing_[i] == PlanStanding::Unchecked) {
      standing_[i] = check(i) ? PlanStanding::Checked : PlanStanding::NotConverged;
    }
    return standing_[i] != PlanStanding::NotConverged;
  }
  /// Runs plan i's deferred check; a plan that fails it becomes what its solve returns for such a
  /// plan, and so does its attempt.
  bool check(std::size_t i);

  const PlanningProblem& problem_;
  SolveContext& context_;
  const NewtonParameters& p_;
  std::size_t first_recorded_;
  SolveContext::IterationTally tally_;  ///< the walk's iterations, every attempt's
  std::vector<Attempt> trail_;
  std::vector<WalkPlan> plans_;  ///< the plans on the requested grid, in attempt order
  std::vector<PlanStanding> standing_;
  std::vector<double> costs_;
  /// The last attempt that produced no plan on the requested grid (e.g. a boundary rate with no
  /// step on a coarser one), while none did: the answer if none ever does.
  PlanResult unplanned_;
  std::vector<ClassSolve> solved_;  ///< the classes solved on the requested grid, in order
};

Attempt attemptIn(AttemptStage stage, AttemptStart start, const PlanningProblem& problem,
                  Globalization globalization = Globalization::TrustRegion) {
  Attempt a;
  a.stage = stage;
  a.start = start;
  a.globalization = globalization;
  a.homotopy = homotopyClassOf(problem);
  a.steps = problem.steps;
  return a;
}

/// Each of `classes` surveyed in its own branch of `context` (runBranches, a queue on the
/// request's threads), the results in the classes' order. The request's own class, which is
/// refined whatever its survey cost (classesToRefine), is refined in its survey's branch as soon
/// as its survey converged (`*own_refined`), while the other classes are surveyed beside it. Each
/// survey and refinement is an independent solve, so each result is the same on any number of
/// threads. `replay_own`: the own class's refined plan is checked beside its open-loop replay
/// (checkBesideReplay).
std::vector<Surveyed> surveyClasses(const std::vector<HomotopyClass>& classes,
                                    const PlanningProblem& problem, const SurveyPlan& plan,
                                    SolveContext& context, const GridSettings& settings,
                                    const NewtonParameters& p, std::optional<Refined>* own_refined,
                                    bool replay_own) {
  std::vector<Surveyed> surveyed(classes.size());
  const bool refined_later = plan.survey + 1 < plan.levels.size();
  // Where the zero maneuver reaches the end, the request's own class is surveyed first, alone:
  // its cost 0 no class beats (costs are sums of squares), and the others are surveyed only where
  // it is not.
  const bool may_cost_nothing = problem.zeroManeuverReachesTheEnd();
  const auto work = [&](int i, SolveContext& branch) {
    {
      const SolveContext::Scope scope(branch, AttemptStage::ClassSurvey, classes[i]);
      surveyed[i] = surveyClass(classes[i], plan, branch, settings, p);
    }
    const bool own = sameHomotopyClass(classes[i], homotopyClassOf(problem));
    if (!own || !refined_later || !surveyed[i].result.converged() || branch.stopReason()) return;
    const SolveContext::Scope scope(branch, AttemptStage::ClassRefine, classes[i]);
    // Checked here: it is the plan kept in most requests, and its branch often ends before the
    // others' surveys do, so its check is off the request's critical path.
    *own_refined = refineClass(surveyed[i], plan, branch, settings, p, replay_own);
    if ((*own_refined)->unchecked) checkBesideReplay(problem, classes[i], branch, &**own_refined);
  };
  const auto own = std::find_if(classes.begin(), classes.end(), [&](const HomotopyClass& c) {
    return sameHomotopyClass(c, homotopyClassOf(problem));
  });
  const int first = may_cost_nothing && own != classes.end()
                        ? static_cast<int>(own - classes.begin())
                        : -1;  // none surveyed alone
  if (first >= 0) {
    runBranches(context, 1, [&](int, SolveContext& branch) { work(first, branch); });
    if (surveyed[first].result.converged() && surveyed[first].result.cost == 0) {
      return {surveyed[first]};
    }
  }
  std::vector<int> others;
  for (int i = 0; i < static_cast<int>(classes.size()); ++i) {
    if (i != first) others.push_back(i);
  }
  runBranches(context, static_cast<int>(others.size()),
              [&](int j, SolveContext& branch) { work(others[j], branch); });
  return surveyed;
}

/// The surveyed classes carried to the requested grid: the request's own (the answer is never
/// costlier than its solve alone) and those whose survey cost is within `margin` of the cheapest
/// (coarse costs reorder on refinement); a class whose survey met one already chosen (the same
/// extremal from another start) would repeat it. Read from the survey alone, so the refinements
/// are independent of one another.
std::vector<const Surveyed*> classesToRefine(const std::vector<Surveyed>& surveyed,
                                             const PlanningProblem& problem, double margin,
                                             const NewtonParameters& p) {
  double cheapest = std::numeric_limits<double>::infinity();
  for (const Surveyed& s : surveyed) {
    if (s.result.converged()) cheapest = std::min(cheapest, s.result.cost);
  }
  std::vector<const Surveyed*> out;
  for (const Surveyed& s : surveyed) {
    if (!s.result.converged()) continue;
    const bool wanted = sameHomotopyClass(s.homotopy, homotopyClassOf(problem)) ||
                        s.result.cost <= cheapest * (1 + margin);
    const bool repeated = std::any_of(out.begin(), out.end(), [&](const Surveyed* r) {
      return std::abs(s.result.cost - r->result.cost) <= p.same_extremal_cost * r->result.cost;
    });
    if (wanted && !repeated) out.push_back(&s);
  }
  return out;
}

/// The chosen classes' refinements (classesToRefine's order), each in its own branch of
/// `context` (a queue on the request's threads) but the request's own when `own_refined` holds it
/// already; a refinement the stop kept from beginning is left out, with those after it.
std::vector<Refined> refineClasses(const std::vector<const Surveyed*>& refine,
                                   const PlanningProblem& problem, const SurveyPlan& plan,
                                   SolveContext& context, const GridSettings& settings,
                                   const NewtonParameters& p, bool defer_check,
                                   std::optional<Refined> own_refined) {
  std::vector<std::optional<Refined>> refined(refine.size());
  std::vector<std::size_t> pending;
  for (std::size_t i = 0; i < refine.size(); ++i) {
    if (own_refined && sameHomotopyClass(refine[i]->homotopy, homotopyClassOf(problem))) {
      refined[i] = std::move(*own_refined);
      own_refined.reset();
    } else {
      pending.push_back(i);
    }
  }
  const auto work = [&](int j, SolveContext& branch) {
    if (branch.stopReason()) return;
    const Surveyed& s = *refine[pending[j]];
    const SolveContext::Scope scope(branch, AttemptStage::ClassRefine, s.homotopy);
    refined[pending[j]] = refineClass(s, plan, branch, settings, p, defer_check);
  };
  runBranches(context, static_cast<int>(pending.size()), work);
  std::vector<Refined> out;
  for (std::optional<Refined>& r : refined) {
    if (!r) break;
    out.push_back(std::move(*r));
  }
  return out;
}

/// Surveys every distinct class, then refines the request's own and those whose survey cost is
/// near the cheapest (classesToRefine: within class_refine_margin where `plans` hands the refined
/// plans on, else unconstrained_refine_margin); the surveys and the refinements run in branches
/// (surveyClasses, refineClasses) and are recorded in the classes' order. A stop (cancel,
/// deadline) carries the first class whose survey it ended to the requested grid (the request's
/// own class: its refinement, if it began) and ends the enumeration. `plans` (optional) receives
/// each converged survey's and refinement's plan (checked: the constrained search reads them);
/// without it, the refinements' checks are left to the walk, which runs those its choice reads.
void enumerateClasses(const PlanningProblem& problem, SolveContext& context, Walk* walk,
                      const NewtonParameters& p, std::vector<ClassPlan>* plans, bool replay_own) {
  const SolverOptions& options = context.options();
  const GridSettings settings{options.tolerance, options.max_iterations,
                              Globalization::TrustRegion};
  const SurveyPlan plan = surveyPlan(problem, p);
  const PlanningProblem& survey_grid = plan.levels[plan.survey];
  const AttemptStart survey_start = usesCoarserLevel(survey_grid, newtonGridRule(p))
                                        ? AttemptStart::CoarseLevel
                                        : AttemptStart::Hermite;
  const bool defer_checks = !plans;
  std::optional<Refined> own_refined;
  // The classes' lifts are those of the coarsest level, where their Hermite curves are built.
  std::vector<Surveyed> surveyed =
      surveyClasses(distinctClasses(plan.levels.front()), problem, plan, context, settings, p,
                    &own_refined, replay_own && !plans);
  const auto addRefined = [&](const Surveyed& s, const Refined& refined, int own_iterations) {
    walk->add(attemptIn(AttemptStage::ClassRefine, AttemptStart::CoarseLevel,
                        pinnedToClass(problem, s.homotopy)),
              refined.result, own_iterations, refined.unchecked, refined.replayed);
    if (plans && refined.result.converged() && refined.result.maneuver.steps() == problem.steps) {
      plans->push_back({s.homotopy, refined.result.maneuver});
    }
  };
  for (std::size_t i = 0; i < surveyed.size(); ++i) {
    const Surveyed& s = surveyed[i];
    walk->add(
        attemptIn(AttemptStage::ClassSurvey, survey_start, pinnedToClass(survey_grid, s.homotopy)),
        s.result, s.result.iterations);
    if (plans && s.result.converged()) plans->push_back({s.homotopy, surveyedPlan(s, survey_grid)});
    // A class at zero cost (the zero maneuver) cannot be beaten: costs are sums of squares.
    const bool unbeatable = s.result.converged() && s.result.cost == 0;
    if (context.stopReason()) {
      if (own_refined && sameHomotopyClass(s.homotopy, homotopyClassOf(problem))) {
        addRefined(s, *own_refined, s.result.iterations + own_refined->result.iterations);
      } else if (!s.on_requested_grid && !s.steps.empty()) {
        const SolveContext::Scope scope(context, AttemptStage::ClassRefine, s.homotopy);
        const Refined carried = refineClass(s, plan, context, settings, p, defer_checks);
        addRefined(s, carried, carried.result.iterations);
      }
      return;
    }
    if (unbeatable) {
      surveyed.resize(i + 1);
      break;
    }
  }
  if (plan.survey + 1 == plan.levels.size()) return;  // the survey was on the requested grid
  const double margin = plans ? p.class_refine_margin : p.unconstrained_refine_margin;
  const std::vector<const Surveyed*> refine = classesToRefine(surveyed, problem, margin, p);
  const std::vector<Refined> refined = refineClasses(refine, problem, plan, context, settings, p,
                                                     defer_checks, std::move(own_refined));
  for (std::size_t i = 0; i < refined.size(); ++i) {
    addRefined(*refine[i], refined[i], refine[i]->result.iterations + refined[i].result.iterations);
  }
}

// --- The recipe after the first answer --------------------------------------------------------

/// How an attempt reaches a plan for the requested grid.
enum class Method {
  ThroughGrids,          ///< grid continuation from the Hermite curve (or the warm start)
  RequestedGridOnly,     ///< the Hermite curve on the requested grid, no coarser level
  RateContinuation,      ///< from rest to rest, the boundary rates raised in stages
  InertiaHomotopy,       ///< from the sphere of the same mean inertia, J reached in stages
  Coasting,              ///< from the coasting start, with a longer iteration limit
  CoastingThroughGrids,  ///< from the coasting start on the coarsest level, through the grids
};

/// What the gates read: the request and the attempts so far.
struct RecipeState {
  const PlanningProblem& problem;
  const SolverOptions& options;
  const NewtonParameters& p;
  /// The attempts so far: reading whether its kept plan converged runs that plan's check.
  Walk& walk;
  /// The own iterations of the class the more starts would search (its survey and refinement,
  /// or the request's solve): the gate judges that first answer, not the further starts.
  int class_iterations = 0;
  bool kept_class = false;  ///< that class is the kept one
  HomotopyClass searched;   ///< that class
};

using Gate = bool (*)(const RecipeState&);

/// A spinning request that stalled from the Hermite start: fast rates over long horizons end at
/// the iteration limit; easier problems (rest to rest, or the coasting motion) lead to it.
bool stalledWithSpinningEnds(const RecipeState& s) {
  return hasSpinningEnds(s.problem) && !s.options.warm_start && !s.walk.keptConverged();
}

/// The stalled spinning request's continuation in the boundary rates, where it may take a stage
/// (a continuation allowed none is not tried: the probes below T*, drivers/minimum_time.cpp).
bool stalledAndRatesContinued(const RecipeState& s) {
  return stalledWithSpinningEnds(s) && s.p.rate_continuation_max_stages > 0;
}

/// The more starts search a spinning request that left its class free; their gates hold for no
/// other request, and are not read for one (reading them runs the checks of the plans they read).
bool mayTryMoreStarts(const RecipeState& s) {
  return hasSpinningEnds(s.problem) && classLeftFree(s.problem, s.options);
}

/// A converged spinning solve of a class that took many iterations (survey and refinement, or
/// its whole solve) wandered far from its start: within that class another start may reach a
/// cheaper extremal (the class survey compares classes, not the basins inside one).
bool slowSpinningSolve(const RecipeState& s) {
  return mayTryMoreStarts(s) && s.walk.keptConverged() &&
         s.class_iterations > s.p.more_starts_above_iterations;
}

/// A slow class is solved from the coasting start on its requested grid with the longer
/// iteration limit (unless a stalled request's retry already did).
bool slowAndNotCoasted(const RecipeState& s) {
  return slowSpinningSolve(s) && !s.walk.triedFrom(AttemptStart::Coasting, s.searched);
}

/// In the kept class of a converged spinning request that left its class free, the coasting
/// start competes even when the solve was fast (through the grids, which keeps it cheap): it
/// often ends in a cheaper basin than the Hermite curve's (docs/notes/newton_tuning.md).
bool keptClassNotCoasted(const RecipeState& s) {
  return mayTryMoreStarts(s) && s.walk.keptConverged() && s.kept_class && !slowSpinningSolve(s) &&
         !s.walk.triedFrom(AttemptStart::Coasting, s.searched);
}

/// The first start came through coarser grids: on the requested grid directly Newton may reach
/// another extremal.
bool slowSpinningSolveThroughGrids(const RecipeState& s) {
  return slowSpinningSolve(s) && usesCoarserLevel(s.problem, newtonGridRule(s.p));
}

struct RecipeEntry {
  AttemptStage stage;
  Method method;
  Globalization globalization;
  Gate when;
};

/// The attempts after the class's (or classes') first answer, each when its gate holds and the
/// solve was neither cancelled nor out of time. Stalled, they run in the request's class; the
/// more starts in the kept class and in the request's own (Walk::searchedClasses).
constexpr RecipeEntry kNewtonRecipe[] = {
    {AttemptStage::RateContinuation, Method::RateContinuation, Globalization::TrustRegion,
     stalledAndRatesContinued},
    {AttemptStage::CoastingRetry, Method::Coasting, Globalization::TrustRegion,
     stalledWithSpinningEnds},
    {AttemptStage::MoreStarts, Method::RequestedGridOnly, Globalization::TrustRegion,
     slowSpinningSolveThroughGrids},
    {AttemptStage::MoreStarts, Method::ThroughGrids, Globalization::LineSearch, slowSpinningSolve},
    {AttemptStage::MoreStarts, Method::InertiaHomotopy, Globalization::TrustRegion,
     slowSpinningSolve},
    {AttemptStage::MoreStarts, Method::Coasting, Globalization::TrustRegion, slowAndNotCoasted},
    {AttemptStage::MoreStarts, Method::CoastingThroughGrids, Globalization::TrustRegion,
     keptClassNotCoasted},
};

/// A staged continuation that did not reach the request: no plan for it; the reason it is given
/// is its last stage's.
PlanResult unfinished(const StagedOutcome& staged, const std::string& what) {
  PlanResult r;
  r.termination = staged.stopped.value_or(Termination::NotConverged);
  r.iterations = staged.iterations;
  carryReason(&r, staged.plan);
  frameMessage(&r, frames::StagedUnfinished{what, staged.reached, staged.stages});
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
  const StagedOutcome staged =
      solveByFixedStages(context, at, p.inertia_homotopy_stages,
                         [&](const PlanningProblem& stage, const Maneuver* from) {
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

/// The coasting start made on the coarsest level of the grid continuation and carried through
/// the finer ones (most iterations on the coarse levels); nothing if it has no start there.
std::optional<PlanResult> coastingThroughGrids(const PlanningProblem& problem,
                                               SolveContext& context, const GridSettings& settings,
                                               const NewtonParameters& p) {
  const std::vector<PlanningProblem> levels = gridLevels(problem, newtonGridRule(p));
  const std::optional<Maneuver> coasting = coastingStart(levels.front());
  if (!coasting) return std::nullopt;
  const LevelSolver<StepVectors> level = [&](const LevelRequest<StepVectors>& r,
                                             StepVectors* final_steps) {
    GridSettings at_level = settings;
    at_level.tolerance = r.tolerance;
    if (r.replay_only) at_level.max_iterations = 0;
    const bool coarsest = r.problem.steps == levels.front().steps;
    return solveOnGrid(r.problem, context, at_level,
                       {coarsest ? &*coasting : nullptr, r.coarse, r.coarser}, final_steps, p);
  };
  return solveByGridContinuation(problem, context, newtonGridRule(p), settings.tolerance, level);
}

/// Runs one entry of the recipe on `problem` (the class it runs in); nothing if it has no start
/// (no coasting motion at this h). `deferred` (optional): the plan's check is left to the walk
/// (GridSettings::deferred_check), except a staged continuation's, whose stages are each checked
/// as they end (each starts the next).
std::optional<PlanResult> runEntry(const RecipeEntry& entry, const PlanningProblem& problem,
                                   SolveContext& context, const NewtonParameters& p,
                                   std::optional<StepResidual>* deferred = nullptr) {
  const SolverOptions& options = context.options();
  GridSettings settings{options.tolerance, options.max_iterations, entry.globalization};
  const bool staged =
      entry.method == Method::RateContinuation || entry.method == Method::InertiaHomotopy;
  if (!staged) settings.deferred_check = deferred;
  switch (entry.method) {
    case Method::ThroughGrids:
      return solveThroughGrids(problem, context, settings, nullptr, p);
    case Method::RequestedGridOnly:
      return solveOnGrid(problem, context, settings, {}, nullptr, p);
    case Method::RateContinuation:
      return byRateContinuation(problem, context, settings, p);
    case Method::InertiaHomotopy:
      return byInertiaHomotopy(problem, context, settings, p);
    case Method::CoastingThroughGrids:
      return coastingThroughGrids(problem, context, settings, p);
    case Method::Coasting: {
      const std::optional<Maneuver> coasting = coastingStart(problem);
      if (!coasting) return std::nullopt;
      settings.max_iterations = coastingIterationLimit(options.max_iterations, p);
      return solveThroughGrids(problem, context, settings, &*coasting, p);
    }
  }
  return std::nullopt;
}

AttemptStart startOf(Method method, const PlanningProblem& problem, const NewtonParameters& p) {
  switch (method) {
    case Method::RequestedGridOnly:
      return AttemptStart::Hermite;
    case Method::RateContinuation:
      return AttemptStart::PreviousAttempt;
    case Method::InertiaHomotopy:
      return AttemptStart::InertiaHomotopy;
    case Method::Coasting:
    case Method::CoastingThroughGrids:
      return AttemptStart::Coasting;
    case Method::ThroughGrids:
      break;
  }
  return usesCoarserLevel(problem, newtonGridRule(p)) ? AttemptStart::CoarseLevel
                                                      : AttemptStart::Hermite;
}

/// One more start: a recipe entry and the class it runs in.
struct MoreStart {
  const RecipeEntry* entry;
  PlanningProblem in_class;
};

/// The more starts whose gates hold, in the recipe's order for each searched class (the kept
/// one, then the request's own). The gates read only what the walk held before them (a converged
/// kept plan stays converged, and each class's coasting attempts are its own), so they are read
/// at once, before any of them runs.
std::vector<MoreStart> moreStarts(const PlanningProblem& problem, RecipeState* state) {
  std::vector<MoreStart> out;
  if (!mayTryMoreStarts(*state) || !state->walk.hasPlan()) return out;
  const HomotopyClass kept = state->walk.keptClass();
  for (const ClassSolve& searched : state->walk.searchedClasses(homotopyClassOf(problem))) {
    state->class_iterations = searched.iterations;
    state->kept_class = sameHomotopyClass(searched.homotopy, kept);
    state->searched = searched.homotopy;
    for (const RecipeEntry& entry : kNewtonRecipe) {
      if (entry.stage == AttemptStage::MoreStarts && entry.when(*state)) {
        out.push_back({&entry, pinnedToClass(problem, searched.homotopy)});
      }
    }
  }
  return out;
}

/// The more starts, each an independent solve in its own branch of `context` (a queue on the
/// request's threads), recorded in their order; as run one after another, the walk ends with the
/// first that a stop (cancel, deadline) ended, and a start the stop kept from beginning is left
/// out, with those after it.
void runMoreStarts(const std::vector<MoreStart>& starts, SolveContext& context, Walk* walk,
                   const NewtonParameters& p) {
  std::vector<std::optional<PlanResult>> results(starts.size());
  std::vector<std::optional<StepResidual>> unchecked(starts.size());
  std::vector<char> began(starts.size(), 0);  // not vector<bool>: each thread writes its own
  runBranches(context, static_cast<int>(starts.size()), [&](int i, SolveContext& branch) {
    if (branch.stopReason()) return;
    began[i] = 1;
    const SolveContext::Scope scope(branch, starts[i].entry->stage,
                                    homotopyClassOf(starts[i].in_class));
    results[i] = runEntry(*starts[i].entry, starts[i].in_class, branch, p, &unchecked[i]);
  });
  for (std::size_t i = 0; i < starts.size() && began[i]; ++i) {
    if (!results[i]) continue;  // no start (no coasting motion at this h)
    const RecipeEntry& entry = *starts[i].entry;
    const Termination termination = results[i]->termination;
    const int own = results[i]->iterations;
    walk->add(attemptIn(entry.stage, startOf(entry.method, starts[i].in_class, p),
                        starts[i].in_class, entry.globalization),
              std::move(*results[i]), own, unchecked[i]);
    if (stoppedByRequest(termination)) break;
  }
}

/// The request's own class through the grids (from its warm start if given).
void solveRequestedClass(const PlanningProblem& problem, SolveContext& context, Walk* walk,
                         const NewtonParameters& p, const Maneuver* solved_before) {
  const SolverOptions& options = context.options();
  std::optional<StepResidual> unchecked;  // its check is left to the walk
  GridSettings settings{options.tolerance, options.max_iterations, Globalization::TrustRegion};
  settings.deferred_check = &unchecked;
  const SolveContext::Scope scope(context, AttemptStage::Solve, homotopyClassOf(problem));
  PlanResult r = solveThroughGrids(problem, context, settings, options.warm_start, p);
  // A warm start that is the request's unconstrained optimum solved before (a class solve's
  // polish) is an earlier attempt's plan.
  const AttemptStart start = !options.warm_start ? startOf(Method::ThroughGrids, problem, p)
                             : options.warm_start == solved_before ? AttemptStart::PreviousAttempt
                                                                   : AttemptStart::WarmStart;
  const int iterations = r.iterations;
  walk->add(attemptIn(AttemptStage::Solve, start, problem), std::move(r), iterations, unchecked);
}

/// The walk's brief around the kept attempt's reason: what stopped the walk, which attempt it was.
frames::WalkKept briefOf(const std::vector<Attempt>& trail, std::size_t kept_at,
                         std::optional<Termination> stop) {
  frames::WalkKept brief;
  brief.stopped = stop && trail[kept_at].termination != *stop;
  if (stop) brief.stop = *stop;
  brief.during = attemptStageName(trail.back().stage);
  brief.kept_at = kept_at;
  brief.tried = trail.size();
  brief.kept_stage = attemptStageName(trail[kept_at].stage);
  brief.kept_start = attemptStartName(trail[kept_at].start);
  return brief;
}

bool Walk::check(std::size_t i) {
  WalkPlan& plan = plans_[i];
  const bool passed = checkDeferredPlan(pinnedToClass(problem_, trail_[plan.at].homotopy),
                                        *plan.unchecked, &plan.result);
  plan.unchecked.reset();
  Attempt& attempt = trail_[plan.at];
  attempt.plan_checked = true;
  attempt.termination = plan.result.termination;
  context_.planChecked(first_recorded_ + plan.at, attempt.termination);
  return passed;
}

PlanResult Walk::finish(bool* replayed) {
  // An attempt cancelled or out of time ends the walk; after a converged plan it only spared
  // further attempts, otherwise the request ends with its termination.
  std::optional<Termination> stop;
  const Termination last = trail_.back().termination;
  if (stoppedByRequest(last)) stop = last;
  if (plans_.empty()) {  // no attempt planned on the requested grid: nothing is kept
    PlanResult none = std::move(unplanned_);
    if (none.termination == Termination::Converged) none.termination = Termination::NotConverged;
    frameMessage(&none, frames::NoAttemptPlanned{trail_.size()});
    none.attempts = trail_;
    return none;
  }
  WalkPlan& chosen = plans_[keptPlan()];
  if (replayed) *replayed = chosen.replayed;
  const std::size_t kept_at = chosen.at;
  PlanResult kept = std::move(chosen.result);
  if (kept.converged()) stop.reset();
  trail_[kept_at].kept = true;
  context_.markKept(first_recorded_ + kept_at);
  kept.iterations = tally_.iterations();
  for (std::size_t i = 0; i < trail_.size(); ++i) {
    if (i != kept_at) kept.extremal_summary.others.push_back(trail_[i]);
  }
  kept.extremal = describeExtremal(kept.extremal_summary);
  frameMessage(&kept, briefOf(trail_, kept_at, stop));
  if (stop && !kept.converged()) kept.termination = *stop;
  kept.attempts = trail_;
  return kept;
}

}  // namespace

std::vector<Vector3> newtonInitialSteps(const PlanningProblem& problem) {
  ReducedProblem np(problem);
  startOnHermiteCurve(problem, &np);
  return np.current();
}

PlanResult solveWithNewton(const PlanningProblem& problem, const SolveRequest& request,
                           SolveContext& context, std::vector<ClassPlan>* survey_plans,
                           bool* replayed) {
  const SolveContext::Call call(context, request);
  const SolverOptions& options = context.options();
  const NewtonParameters& p = options.advanced.newton;
  Walk walk(problem, context, p);
  if (replayed) *replayed = false;
  // The own class's replay beside its check pays where another thread is there to run it.
  const bool replay_own = replayed && context.threads() > 1;
  if (classLeftFree(problem, options)) {
    enumerateClasses(problem, context, &walk, p, survey_plans, replay_own);
  }
  // The request's own class when it names one or is warm-started; after the class survey, when
  // no class converged on the requested grid and the request's class was not solved whole there.
  const bool request_solved = walk.solvedOnRequestedGrid(homotopyClassOf(problem));
  if (!walk.hasPlan() || (!request_solved && !context.stopReason() && !walk.kept().converged())) {
    solveRequestedClass(problem, context, &walk, p, request.start.unconstrained_optimum);
  }
  const auto run = [&](const RecipeEntry& entry, const PlanningProblem& in) {
    const SolveContext::Scope scope(context, entry.stage, homotopyClassOf(in));
    std::optional<PlanResult> r = runEntry(entry, in, context, p);
    if (!r) return;
    const int own = r->iterations;
    walk.add(attemptIn(entry.stage, startOf(entry.method, in, p), in, entry.globalization),
             std::move(*r), own);
  };
  RecipeState state{problem, options, p, walk};
  for (const RecipeEntry& entry : kNewtonRecipe) {  // stalled: in the request's class
    if (context.stopReason()) break;
    if (entry.stage != AttemptStage::MoreStarts && entry.when(state)) run(entry, problem);
  }
  if (!context.stopReason()) runMoreStarts(moreStarts(problem, &state), context, &walk, p);
  PlanResult result = walk.finish(replayed);
  context.recordLevels(result.levels);  // the plan's: its kept attempt's
  return result;
}

}  // namespace attitude_planner
