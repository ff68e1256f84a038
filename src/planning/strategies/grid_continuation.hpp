// Grid continuation, for any solver: the problem is first solved on coarser grids (coarsest
// first) and each level's final iterate starts the next, finer one; from a coarse solution every
// level starts near its optimum and takes a few Newton steps, where the requested grid from a
// guess would wander through regions of negative curvature. The solver is a callable ("solve
// this level from this start"); the rule says how levels are made (coarsest N, the ratio between
// levels, when a coarse level helps, what it is solved to); `Carry` is what a level hands the next
// (Newton: the steps' rotation vectors).
#pragma once

#include <algorithm>
#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "attitude_planner/planning/problem.hpp"
#include "attitude_planner/planning/result.hpp"
#include "planning/problem/solve_context.hpp"

namespace attitude_planner {

/// How the levels of a continuation are made.
struct GridLevelRule {
  int coarsest_steps = 16;    ///< no level below this N
  int coarsening_factor = 4;  ///< N of a level ÷ N of the next coarser one
  /// A coarse level only starts the next: it is solved to max(tolerance, this).
  double coarse_tolerance_floor = 1e-6;
  /// Whether a coarse level (the problem at its N) is worth solving; empty: always.
  std::function<bool(const PlanningProblem& coarse)> level_helps;
};

/// The next coarser level of `problem` under `rule`.
PlanningProblem coarserLevel(const PlanningProblem& problem, const GridLevelRule& rule);
/// Whether `problem` is solved through a coarser level first.
bool usesCoarserLevel(const PlanningProblem& problem, const GridLevelRule& rule);
/// The levels to solve, coarsest first; the last one is `problem` itself.
std::vector<PlanningProblem> gridLevels(const PlanningProblem& problem, const GridLevelRule& rule);

/// What one level is solved from and to.
template <class Carry>
struct LevelRequest {
  const PlanningProblem& problem;  ///< this level (its N)
  double tolerance = 0.0;
  bool finest = false;  ///< the requested grid (its plan is the answer; no iterate to hand on)
  /// The solve stopped on a coarser level (cancel, deadline): carry `coarse` over, no iteration.
  bool replay_only = false;
  const Carry* coarse = nullptr;   ///< the next coarser level's final iterate, if usable
  const Carry* coarser = nullptr;  ///< the one below it, converged (for extrapolation)
};

/// Solves one level; fills `final_iterate` on coarse levels (for the next), never on the finest.
template <class Carry>
using LevelSolver = std::function<PlanResult(const LevelRequest<Carry>&, Carry* final_iterate)>;

/// The finest level's result with every level's iterations and LevelSummary; stopped on a coarse
/// level, the finest level is the last iterate carried over, with the stop's termination.
template <class Carry>
PlanResult solveByGridContinuation(const PlanningProblem& problem, const SolveContext& context,
                                   const GridLevelRule& rule, double tolerance,
                                   const LevelSolver<Carry>& solve) {
  const std::vector<PlanningProblem> levels = gridLevels(problem, rule);
  const int count = static_cast<int>(levels.size());
  std::vector<Carry> carry(count);
  std::vector<Termination> ended(count, Termination::NotConverged);
  std::vector<LevelSummary> summaries;
  std::optional<Termination> stopped;
  int stopped_at = 0;  // the level whose end stopped the solve
  int iterations = 0;
  PlanResult result;
  for (int i = 0; i < count; ++i) {
    const bool finest = i + 1 == count;
    LevelRequest<Carry> request{
        levels[i], finest ? tolerance : std::max(tolerance, rule.coarse_tolerance_floor), finest};
    if (i > 0 && !stopped) {
      stopped = result.termination == Termination::Cancelled ? Termination::Cancelled
                                                             : context.stopReason();
      stopped_at = i - 1;
    }
    if (stopped) {
      request.replay_only = true;
      if (!carry[i - 1].empty()) request.coarse = &carry[i - 1];
    } else if (i > 0 && ended[i - 1] == Termination::Converged) {
      request.coarse = &carry[i - 1];
      if (i > 1 && ended[i - 2] == Termination::Converged) request.coarser = &carry[i - 2];
    }
    result = solve(request, finest ? nullptr : &carry[i]);
    ended[i] = result.termination;
    iterations += result.iterations;
    if (stopped) {
      result.termination = *stopped;
      if (!result.levels.empty()) result.levels.back().termination = *stopped;
    }
    summaries.insert(summaries.end(), result.levels.begin(), result.levels.end());
  }
  result.iterations = iterations;
  result.levels = summaries;
  if (count == 1) return result;
  const int below = levels[count - 2].steps;
  if (stopped) {
    result.message =
        std::string(*stopped == Termination::Cancelled ? "cancelled" : "time budget exceeded") +
        " on the N = " + std::to_string(levels[stopped_at].steps) +
        " level; the plan is its iterate carried over to N = " + std::to_string(problem.steps);
  } else if (ended[count - 2] == Termination::Converged) {
    result.message += "; started from the N = " + std::to_string(below) + " solution";
  } else {
    result.message += "; the N = " + std::to_string(below) + " level ended " +
                      terminationName(ended[count - 2]) + ", started from the geodesic";
  }
  return result;
}

}  // namespace attitude_planner
