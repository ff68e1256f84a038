// Continuation through a family of problems P(s), s from 0 (easy) to 1 (the request), each
// stage solved from the previous stage's plan. Solver-agnostic: the solver is a callable "solve
// this problem from this plan (or from its own start)". Two schedules: adaptive (a stage that
// fails halves the increment; the continuation in the boundary rates) and fixed (equal stages;
// the inertia homotopy).
#pragma once

#include <functional>
#include <optional>

#include "attitude_planner/dynamics/maneuver.hpp"
#include "attitude_planner/planning/problem.hpp"
#include "attitude_planner/planning/result.hpp"
#include "planning/problem/solve_context.hpp"

namespace attitude_planner {

/// P(s).
using StageProblem = std::function<PlanningProblem(double s)>;
/// Solves a stage from `from` (nullptr: the solver's own start).
using StageSolver = std::function<PlanResult(const PlanningProblem& stage, const Maneuver* from)>;

/// How far a staged continuation got.
struct StagedOutcome {
  PlanResult plan;     ///< the last converged stage's (s = reached), or the stage that stopped
  double reached = 0;  ///< the s of the last converged stage (−1: not even s = 0)
  int stages = 0;      ///< stages solved after s = 0
  int iterations = 0;  ///< over every stage (the context's count while they ran)
  std::optional<Termination> stopped;  ///< a stage was cancelled or ran out of time
  bool complete() const { return !stopped && reached == 1.0 && plan.converged(); }
};

/// The adaptive schedule: s = 0, then s + ds (at most 1) with ds doubling (to max_increment)
/// after a converged stage and half the increment tried after a failed one (giving up below
/// min_increment). After a
/// failed stage ds is held for `hold_after_failure` converged stages before it doubles again: an
/// increment that just failed is likely to fail again from the next stage (doubling straight back
/// to it alternates failed and converged stages, and failed stages count against max_stages).
struct AdaptiveSchedule {
  double first_increment = 0.25;
  double max_increment = 0.5;
  double min_increment = 1.0 / 64;
  int max_stages = 24;
  int hold_after_failure = 0;
};

StagedOutcome solveByAdaptiveStages(const SolveContext& context, const StageProblem& at,
                                    const AdaptiveSchedule& schedule, const StageSolver& solve);

/// `stages` equal steps of s after s = 0, ending at the first stage that does not converge.
StagedOutcome solveByFixedStages(const SolveContext& context, const StageProblem& at, int stages,
                                 const StageSolver& solve);

}  // namespace attitude_planner
