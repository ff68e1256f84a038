#include "planning/drivers/pointing.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <sstream>

#include "attitude_planner/errors.hpp"
#include "attitude_planner/planning/pointing.hpp"
#include "planning/newton/newton_parameters.hpp"
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
  bool converged() const { return solve.termination == Termination::Converged; }
};

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

/// One twist Newton solve on `at` from `coarse` (a coarser grid's iterate) or the Hermite curve.
TwistRun runTwist(const PlanningProblem& at, double twist, const HomotopyClass& homotopy,
                  const ReducedProblem::StepVectors* coarse, double tolerance,
                  SolveContext& context, const NewtonParameters& p) {
  TwistRun run;
  run.homotopy = homotopy;
  run.start_twist = twist;
  run.steps = at.steps;
  try {
    ReducedProblem np(at);
    run.lift = startOnHermiteCurve(at, &np);
    if (coarse) np.initializeFromCoarser(*coarse);
    run.solve = solveTwistNewton(np, twist, context, tolerance, context.options().max_iterations, p,
                                 &run.history);
    run.iterate = np.current();
  } catch (const StepTooLarge& e) {
    run.solve.termination = Termination::StepTooLarge;
    run.solve.reason = std::string("boundary velocity: ") + e.what();
  }
  return run;
}

/// Records `run` as an attempt in the trail; returns its index there.
std::size_t record(const TwistRun& run, AttemptStage stage, AttemptStart start, int coarse_steps,
                   SolveContext& context) {
  Attempt a;
  a.stage = stage;
  a.start = start;
  a.globalization = Globalization::LineSearch;
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

/// The survey's converged answers worth refining: distinct, cheapest first, within the class
/// survey's margin of the cheapest.
std::vector<const TwistRun*> worthRefining(const std::vector<TwistRun>& survey,
                                           const NewtonParameters& p) {
  std::vector<const TwistRun*> sorted;
  for (const TwistRun& r : survey) {
    if (r.converged()) sorted.push_back(&r);
  }
  std::sort(sorted.begin(), sorted.end(),
            [](const TwistRun* a, const TwistRun* b) { return a->solve.cost < b->solve.cost; });
  std::vector<const TwistRun*> out;
  for (const TwistRun* r : sorted) {
    if (r->solve.cost > (1.0 + p.class_refine_margin) * sorted.front()->solve.cost) break;
    const bool repeated =
        std::any_of(out.begin(), out.end(), [&](const TwistRun* o) { return sameAnswer(*o, *r); });
    if (!repeated) out.push_back(r);
  }
  return out;
}

/// A survey answer carried to the requested grid through factor-4 levels (each level's solve to
/// the coarse tolerance but the last); the attempt is the last level's solve.
TwistRun refine(const PlanningProblem& problem, const TwistRun& from, SolveContext& context,
                const NewtonParameters& p) {
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
        runTwist(at, run.solve.twist, from.homotopy, &run.iterate, tolerance, context, p);
    next.start_twist = from.start_twist;
    next.history.insert(next.history.begin(), run.history.begin(), run.history.end());
    run = std::move(next);
    run.solve.iterations = context.iterations() - counted_before;
    if (!run.converged()) break;
  }
  return run;
}

/// The plan of `run` (on the requested grid) with its figures, the pointing summary and the
/// message.
PlanResult resultOf(const PlanningProblem& problem, const TwistRun& run) {
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
  result.pointing.active = true;
  result.pointing.final_twist = twistOf(chosen.final_attitude, problem.end_condition);
  result.pointing.error = pointingError(planned.attitude.back(), problem.end_condition);
  result.pointing.twist_gradient = run.solve.twist_gradient;
  double scale = 0.0;
  Eigen::VectorXd gradient;
  np.evaluateWithTwist(&gradient, nullptr, nullptr, nullptr, &scale);
  result.pointing.twist_stationarity = std::abs(gradient(np.unknowns())) / scale;
  std::ostringstream msg;
  msg << reason << " after " << run.solve.iterations << " iterations (relative gradient "
      << run.solve.relative_gradient << ", relative Newton decrement "
      << run.solve.relative_decrement << "); pointing: twist " << result.pointing.final_twist
      << " rad, d cost/d twist " << run.solve.twist_gradient;
  result.message = msg.str();
  return result;
}

/// Every start (kPointingStartTwists twists from the one of least rotation × the ways round) solved
/// on `steps` steps, each recorded as a `stage` attempt; with `finals`, each appended there too (a
/// plan on the requested grid). Stops at a cancel or the deadline.
std::vector<TwistRun> runStarts(const PlanningProblem& problem, int steps, double tolerance,
                                AttemptStage stage, SolveContext& context,
                                const NewtonParameters& p,
                                std::vector<std::pair<TwistRun, std::size_t>>* finals) {
  const double base = nearestTwist(problem.initial_attitude, problem.end_condition);
  std::vector<TwistRun> runs;
  for (int i = 0; i < kPointingStartTwists; ++i) {
    const double twist = std::remainder(base + 2.0 * M_PI * i / kPointingStartTwists, 2.0 * M_PI);
    for (const HomotopyClass& c : kPointingClasses) {
      if (context.stopReason()) return runs;
      runs.push_back(
          runTwist(posedAt(problem, steps, twist, c), twist, c, nullptr, tolerance, context, p));
      const std::size_t at = record(runs.back(), stage, AttemptStart::Hermite, 0, context);
      if (finals) finals->emplace_back(runs.back(), at);
    }
  }
  return runs;
}

/// The kept answer: the cheapest converged plan on the requested grid (else the first with an
/// iterate there, not converged), with the request's trail and totals.
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
  if (kept) {
    result = resultOf(problem, kept->first);
    context.markKept(kept->second);
  } else {
    result.termination = context.stopReason().value_or(Termination::NotConverged);
    result.message = "no start converged (" + std::to_string(survey.size()) +
                     " twist and way-round starts tried)";
    if (!survey.empty()) addNote(&result, notes::LastPointingStart{survey.back().solve.reason});
    result.cost = std::numeric_limits<double>::quiet_NaN();
  }
  result.attempts.assign(context.attempts().begin() + first_recorded, context.attempts().end());
  result.pointing.starts = static_cast<int>(survey.size());
  if (result.attempts.size() > 1 && kept) {
    std::ostringstream brief;
    brief << result.message << "; attempt " << kept->second - first_recorded + 1 << " of "
          << result.attempts.size() << " kept (" << kPointingStartTwists << " start twists x "
          << std::size(kPointingClasses) << " ways round)";
    result.message = brief.str();
  }
  return result;
}

}  // namespace

PlanResult planPointing(const PlanningProblem& problem, const SolverOptions& options,
                        SolveContext& context) {
  if (options.solver != SolverKind::Structured) {
    throw InvalidInput("solver: " + solverName(options.solver) +
                       " does not serve final.pointing (the twist is an unknown of the newton "
                       "solver only)");
  }
  if (options.warm_start) {
    throw InvalidInput("final.pointing: not supported with a warm start (initial_guess) yet");
  }
  const SolveContext::Call call(context, options);
  const NewtonParameters& p = newtonDefaults();
  const std::size_t first_recorded = context.attempts().size();
  const int counted_at_start = context.iterations();
  const int survey_steps = surveySteps(problem, p);
  const bool on_requested = survey_steps == problem.steps;
  const double survey_tolerance =
      on_requested ? options.tolerance : std::max(options.tolerance, p.coarse_tolerance_floor);
  std::vector<std::pair<TwistRun, std::size_t>> finals;  // on the requested grid, trail index
  const std::vector<TwistRun> survey =
      runStarts(problem, survey_steps, survey_tolerance,
                on_requested ? AttemptStage::Solve : AttemptStage::ClassSurvey, context, p,
                on_requested ? &finals : nullptr);
  for (const TwistRun* r :
       on_requested ? std::vector<const TwistRun*>() : worthRefining(survey, p)) {
    if (context.stopReason()) break;
    TwistRun refined = refine(problem, *r, context, p);
    const std::size_t at = record(refined, AttemptStage::ClassRefine, AttemptStart::CoarseLevel,
                                  survey_steps, context);
    finals.emplace_back(std::move(refined), at);
  }
  const bool planned =
      std::any_of(finals.begin(), finals.end(), [](const auto& f) { return f.first.converged(); });
  if (!planned && !on_requested && !context.stopReason()) {
    // Nothing of the survey grid's reached the requested one: the starts on the requested grid.
    runStarts(problem, problem.steps, options.tolerance, AttemptStage::Solve, context, p, &finals);
  }
  PlanResult result = finishPointing(problem, survey, finals, first_recorded, context);
  result.iterations = context.iterations() - counted_at_start;  // every start, as reported
  return result;
}

}  // namespace attitude_planner
