// The loop of primal_dual_loop.hpp.
#include "planning/interior_point/primal_dual_loop.hpp"

namespace attitude_planner {

void PrimalDualLoop::run(int max_iterations, int* iteration) {
  for (;; ++*iteration) {
    if (profile_.limits_before_direction_work && limitReached(*iteration, max_iterations)) return;
    try {
      if (pass(*iteration, max_iterations) == Pass::Stop) return;
    } catch (const SolveInterrupted& interrupted) {
      // Inside an assembly or a factorization: the iterate is the last accepted one.
      problem_.stopped(interrupted.termination, true);
      return;
    }
  }
}

/// One pass: the problem prepared, the stopping test, what comes before the direction, the
/// limits (free time), the step.
Pass PrimalDualLoop::pass(int iteration, int max_iterations) {
  problem_.prepare();
  if (const std::optional<LoopEnd> end = stop_.beforeDirection(problem_.state())) {
    return problem_.ended(*end);
  }
  const Pass before = problem_.beforeDirection();
  if (before != Pass::Step) return before;
  if (!profile_.limits_before_direction_work && limitReached(iteration, max_iterations)) {
    return Pass::Stop;
  }
  return step();
}

Pass PrimalDualLoop::step() {
  LineSearchRequest request;
  Eigen::VectorXd* d = nullptr;
  DirectionMeasures measures;
  const Pass direction = problem_.direction(&request, &d, &measures);
  if (direction == Pass::Reject) return rejected({}, {});
  if (direction != Pass::Step) return direction;
  const StopVerdict verdict = stop_.afterDirection(problem_.state(), measures);
  request.take_outright = verdict.final_step;
  request.at_floor = verdict.at_floor;
  const LineSearchResult result = search_.search(problem_, request, d);
  if (!result.accepted) return rejected(result, verdict);
  const Pass after = problem_.accept(result, verdict);
  if (after == Pass::Continue) stop_.accepted(verdict, result.alpha);
  return after;
}

Pass PrimalDualLoop::rejected(const LineSearchResult& result, const StopVerdict& verdict) {
  const Pass solved = problem_.solvedToRoundOff(result);
  if (solved != Pass::Step) return solved;
  if (const std::optional<LoopEnd> end = stop_.onRejected(problem_.state(), verdict)) {
    return problem_.ended(*end);
  }
  return problem_.rejected(result, verdict);
}

bool PrimalDualLoop::limitReached(int iteration, int max_iterations) {
  const bool at_limit = iteration >= max_iterations;
  if (at_limit && profile_.limits_before_direction_work) {
    problem_.iterationLimit();
    return true;
  }
  if (const std::optional<Termination> stop = context_.stopReason()) {
    problem_.stopped(*stop, false);
    return true;
  }
  if (at_limit) problem_.iterationLimit();
  return at_limit;
}

}  // namespace attitude_planner
