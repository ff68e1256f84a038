// Grid continuation, for any solver: the problem is first solved on coarser grids (coarsest
// first) and each level's final iterate starts the next, finer one; from a coarse solution every
// level starts near its optimum and takes a few Newton steps, where the requested grid from a
// guess would wander through regions of negative curvature. The solver is a callable ("solve
// this level from this start"); the rule says how levels are made (coarsest N, the ratio between
// levels, when a coarse level helps, what it is solved to) and which ends of a level end the
// continuation; `Carry` is what a level hands the next (Newton: the steps' rotation vectors; the
// interior point: those and its multipliers). The Newton solver, its class refinement and the
// interior point all run this one loop.
#pragma once

#include <algorithm>
#include <cstddef>
#include <functional>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "attitude_planner/planning/problem.hpp"
#include "attitude_planner/planning/result.hpp"
#include "planning/problem/solve_context.hpp"

namespace attitude_planner {

/// How the levels of a continuation are made, and which ends of a level end it.
struct GridLevelRule {
  int coarsest_steps = 16;    ///< no level below this N
  int coarsening_factor = 4;  ///< N of a level ÷ N of the next coarser one
  /// A level of at most this N is solved on its own grid, without a coarser level (besides
  /// coarsest_steps; the interior point: its coarsest_grid).
  int direct_up_to = 0;
  /// A coarse level only starts the next: it is solved to max(tolerance, this).
  double coarse_tolerance_floor = 1e-6;
  /// Whether a coarse level (the problem at its N) is worth solving; empty: always.
  std::function<bool(const PlanningProblem& coarse)> level_helps;
  /// A level that ends Infeasible answers for the finer ones, which only carry its iterate (the
  /// interior point: an infeasibility certificate); otherwise the next level starts afresh.
  bool infeasible_ends = false;
  /// A coarse level that does not converge ends the continuation there, with no plan on the
  /// requested grid (a refinement from a given iterate, where a fresh start would be another
  /// attempt); otherwise the next level starts afresh. A level stopped by a cancel or the
  /// deadline does not end it: its iterate is carried on.
  bool unconverged_ends = false;
};

/// The next coarser level of `problem` under `rule`.
PlanningProblem coarserLevel(const PlanningProblem& problem, const GridLevelRule& rule);
/// Whether `problem` is solved through a coarser level first.
bool usesCoarserLevel(const PlanningProblem& problem, const GridLevelRule& rule);
/// The levels to solve, coarsest first; the last one is `problem` itself.
std::vector<PlanningProblem> gridLevels(const PlanningProblem& problem, const GridLevelRule& rule);

/// How one level ended, before a stop's termination replaced its own.
struct LevelEnd {
  int steps = 0;  ///< its N
  Termination termination = Termination::NotConverged;
  std::vector<MessageClause> clauses;  ///< its result's reason, as data
};

/// What stopped a continuation (cancel, deadline, or a level's end under the rule) and where.
struct ContinuationStop {
  Termination termination = Termination::Cancelled;
  LevelEnd level;  ///< the level whose end stopped it
};

/// Every level's end, for the message and for a caller's verdict rules.
struct ContinuationRecord {
  std::vector<LevelEnd> levels;  ///< all levels, coarsest first
  std::size_t first = 0;         ///< the first level solved here (a resumed one: after `from`)
  std::size_t reached = 0;       ///< levels [first, reached) were solved
  std::optional<ContinuationStop> stop;
  std::size_t stopped_at = 0;  ///< with stop: the index of the level that stopped it
};

/// What one level is solved from and to.
template <class Carry>
struct LevelRequest {
  const PlanningProblem& problem;  ///< this level (its N)
  double tolerance = 0.0;
  bool finest = false;  ///< the requested grid (its plan is the answer; no iterate to hand on)
  /// The solve stopped on a coarser level (see stop): carry `coarse` over, no iteration.
  bool replay_only = false;
  const Carry* coarse = nullptr;           ///< the next coarser level's final iterate, if usable
  const Carry* coarser = nullptr;          ///< the one below it, converged (for extrapolation)
  const ContinuationStop* stop = nullptr;  ///< with replay_only: what stopped the solve
};

/// Solves one level; fills `final_iterate` on coarse levels (for the next), never on the finest.
template <class Carry>
using LevelSolver = std::function<PlanResult(const LevelRequest<Carry>&, Carry* final_iterate)>;

/// Writes the finest result's message (and any verdict a solver draws from the levels) once the
/// levels are solved.
using ContinuationFinish = std::function<void(const ContinuationRecord&, PlanResult* finest)>;

/// The default finish: how the level below the requested grid started it, or where a stop
/// happened and that the plan is its iterate carried over.
void describeContinuation(const ContinuationRecord& record, PlanResult* finest);

/// A level already solved by the caller (e.g. a class survey's grid) from which a continuation
/// resumes through the finer levels.
template <class Carry>
struct SolvedLevel {
  std::size_t index = 0;  ///< its place among the levels
  Termination termination = Termination::Converged;
  Carry iterate;                 ///< its final iterate
  Carry below;                   ///< the final iterate of the level below it ...
  bool below_converged = false;  ///< ... usable for extrapolation if that one converged
};

namespace grid_continuation_detail {

/// The stop in force before solving level i: kept once set; else a cancelled level, the
/// context's cancel flag or deadline, or the rule's stopping ends.
inline std::optional<Termination> stopBefore(Termination previous, const SolveContext& context,
                                             const GridLevelRule& rule) {
  if (previous == Termination::Cancelled) return Termination::Cancelled;
  if (std::optional<Termination> reason = context.stopReason()) return reason;
  if (rule.infeasible_ends && previous == Termination::Infeasible) return Termination::Infeasible;
  return std::nullopt;
}

/// Solves levels[first..]: each from the one below when it converged (or, after a stop, carries
/// its iterate over); `carry` and `record.levels` hold the levels below `first`.
template <class Carry>
PlanResult runLevels(const std::vector<PlanningProblem>& levels, std::size_t first,
                     std::vector<Carry> carry, ContinuationRecord record,
                     const SolveContext& context, const GridLevelRule& rule, double tolerance,
                     const LevelSolver<Carry>& solve, const ContinuationFinish& finish) {
  const std::size_t count = levels.size();
  std::vector<LevelSummary> summaries;
  const SolveContext::IterationTally tally(context);
  PlanResult result;
  record.first = first;
  for (std::size_t i = first; i < count; ++i) {
    const bool finest = i + 1 == count;
    LevelRequest<Carry> request{
        levels[i], finest ? tolerance : std::max(tolerance, rule.coarse_tolerance_floor), finest};
    if (i > 0 && !record.stop) {
      if (const auto reason = stopBefore(record.levels[i - 1].termination, context, rule)) {
        record.stop = ContinuationStop{*reason, record.levels[i - 1]};
        record.stopped_at = i - 1;
      }
    }
    const bool converged_below =
        i > 0 && record.levels[i - 1].termination == Termination::Converged;
    if (record.stop) {
      request.replay_only = true;
      request.stop = &*record.stop;
      if (!carry[i - 1].empty()) request.coarse = &carry[i - 1];
    } else if (converged_below) {
      request.coarse = &carry[i - 1];
      if (i > 1 && record.levels[i - 2].termination == Termination::Converged) {
        request.coarser = &carry[i - 2];
      }
    }
    result = solve(request, finest ? nullptr : &carry[i]);
    record.levels[i].termination = result.termination;
    record.levels[i].clauses = result.clauses;
    record.reached = i + 1;
    if (record.stop) {
      result.termination = record.stop->termination;
      if (!result.levels.empty()) result.levels.back().termination = record.stop->termination;
    }
    summaries.insert(summaries.end(), result.levels.begin(), result.levels.end());
    // A level stopped inside its solve (cancel, deadline) is not an unconverged end: its
    // iterate is carried on to the requested grid as after a stop between levels, so that a
    // stopped refinement still hands over its plan (and no other attempt is run to get one).
    const bool stopped_inside = stoppedByRequest(result.termination);
    if (!finest && !record.stop && rule.unconverged_ends && !result.converged() && !stopped_inside)
      break;
  }
  result.iterations = tally.iterations();
  result.levels = std::move(summaries);
  finish(record, &result);
  return result;
}

/// Every level's N, their ends not yet known.
inline ContinuationRecord recordOf(const std::vector<PlanningProblem>& levels) {
  ContinuationRecord record;
  for (const PlanningProblem& level : levels) {
    record.levels.push_back({level.steps, Termination::NotConverged, {}});
  }
  return record;
}

}  // namespace grid_continuation_detail

/// The finest level's result with every level's iterations and LevelSummary; stopped on a coarse
/// level, the finest level is the last iterate carried over, with the stop's termination. `finish`
/// writes the message (not called when the problem has no coarser level: its own solve's stands).
template <class Carry>
PlanResult solveByGridContinuation(const PlanningProblem& problem, const SolveContext& context,
                                   const GridLevelRule& rule, double tolerance,
                                   const LevelSolver<Carry>& solve,
                                   const ContinuationFinish& finish = describeContinuation) {
  const std::vector<PlanningProblem> levels = gridLevels(problem, rule);
  if (levels.size() == 1) {
    return solve(LevelRequest<Carry>{levels[0], tolerance, true}, nullptr);
  }
  return grid_continuation_detail::runLevels(levels, 0, std::vector<Carry>(levels.size()),
                                             grid_continuation_detail::recordOf(levels), context,
                                             rule, tolerance, solve, finish);
}

/// The continuation resumed after `from` (solved by the caller) through the finer `levels`
/// (coarsest first, as gridLevels makes them): the same loop from that level's iterate.
template <class Carry>
PlanResult resumeGridContinuation(const std::vector<PlanningProblem>& levels,
                                  const SolvedLevel<Carry>& from, const SolveContext& context,
                                  const GridLevelRule& rule, double tolerance,
                                  const LevelSolver<Carry>& solve,
                                  const ContinuationFinish& finish) {
  std::vector<Carry> carry(levels.size());
  ContinuationRecord record = grid_continuation_detail::recordOf(levels);
  carry[from.index] = from.iterate;
  record.levels[from.index].termination = from.termination;
  if (from.index > 0) {
    carry[from.index - 1] = from.below;
    record.levels[from.index - 1].termination =
        from.below_converged ? Termination::Converged : Termination::NotConverged;
  }
  return grid_continuation_detail::runLevels(levels, from.index + 1, std::move(carry),
                                             std::move(record), context, rule, tolerance, solve,
                                             finish);
}

}  // namespace attitude_planner
