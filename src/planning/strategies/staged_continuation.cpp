#include "planning/strategies/staged_continuation.hpp"

#include <algorithm>

namespace attitude_planner {

namespace {

bool stoppedEarly(const PlanResult& r) {
  return stoppedByRequest(r.termination);
}

}  // namespace

StagedOutcome solveByAdaptiveStages(const SolveContext& context, const StageProblem& at,
                                    const AdaptiveSchedule& schedule, const StageSolver& solve) {
  StagedOutcome out;
  out.reached = -1;
  if (context.stopReason()) return out;
  const SolveContext::IterationTally tally(context);
  out.plan = solve(at(0.0), nullptr);
  out.iterations = tally.iterations();
  if (stoppedEarly(out.plan)) {
    out.stopped = out.plan.termination;
    return out;
  }
  if (!out.plan.converged()) return out;
  out.reached = 0.0;
  double ds = schedule.first_increment;
  int held = 0;  // converged stages still to go at ds before it may double
  while (out.reached < 1.0 && out.stages < schedule.max_stages && !context.stopReason()) {
    const double next = std::min(1.0, out.reached + ds);
    const Maneuver from = out.plan.maneuver;
    PlanResult r = solve(at(next), &from);
    ++out.stages;
    out.iterations = tally.iterations();
    if (stoppedEarly(r)) {
      out.stopped = r.termination;
      out.plan = std::move(r);
      return out;
    }
    if (r.converged()) {
      out.plan = std::move(r);
      out.reached = next;
      if (held > 0) {
        --held;
      } else {
        ds = std::min(2.0 * ds, schedule.max_increment);
      }
    } else {
      // Half the increment tried, not ds: where s + ds was cut at 1, halving ds could pose the
      // failed stage again from the same plan.
      ds = 0.5 * (next - out.reached);
      held = schedule.hold_after_failure;
      if (ds < schedule.min_increment) break;
    }
  }
  return out;
}

StagedOutcome solveByFixedStages(const SolveContext& context, const StageProblem& at, int stages,
                                 const StageSolver& solve) {
  StagedOutcome out;
  out.reached = -1;
  const SolveContext::IterationTally tally(context);
  Maneuver previous;
  for (int i = 0; i <= stages; ++i) {
    const double s = static_cast<double>(i) / stages;
    out.plan = solve(at(s), i > 0 ? &previous : nullptr);
    out.iterations = tally.iterations();
    if (stoppedEarly(out.plan)) out.stopped = out.plan.termination;
    if (!out.plan.converged()) break;
    out.reached = s;
    out.stages = i;
    previous = out.plan.maneuver;
  }
  return out;
}

}  // namespace attitude_planner
