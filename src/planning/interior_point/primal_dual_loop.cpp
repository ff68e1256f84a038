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

/// One pass: what comes before the direction, the limits (free time), the direction, the line
/// search, the step or the rejection.
Pass PrimalDualLoop::pass(int iteration, int max_iterations) {
  const Pass before = problem_.beforeDirection();
  if (before != Pass::Step) return before;
  if (!profile_.limits_before_direction_work && limitReached(iteration, max_iterations)) {
    return Pass::Stop;
  }
  LineSearchRequest request;
  Eigen::VectorXd* d = nullptr;
  const Pass direction = problem_.direction(&request, &d);
  if (direction != Pass::Step) return direction;
  const LineSearchResult result = search_.search(problem_, request, d);
  return result.accepted ? problem_.accept(result) : problem_.rejected(result);
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
