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

/// One pass: the problem prepared, the stopping test, the barrier problem solved, the limits
/// (free time), the step.
Pass PrimalDualLoop::pass(int iteration, int max_iterations) {
  problem_.prepare();
  const BarrierState state = problem_.state();
  if (const std::optional<LoopEnd> end = stop_.beforeDirection(state)) {
    return problem_.ended(*end);
  }
  if (mu_->subproblemSolved(state, problem_.barrier())) return barrierSolved();
  if (!profile_.limits_before_direction_work && limitReached(iteration, max_iterations)) {
    return Pass::Stop;
  }
  return step();
}

Pass PrimalDualLoop::barrierSolved() {
  const Pass observed = problem_.atSolvedBarrier();
  if (observed != Pass::Step) return observed;
  mu_->decrease(problem_.barrier());
  problem_.barrierDecreased();
  return Pass::Continue;  // the same iterate for the next barrier problem
}

Pass PrimalDualLoop::step() {
  LineSearchRequest request;
  Eigen::VectorXd* d = nullptr;
  DirectionMeasures measures;
  const Pass found = direction(&request, &d, &measures);
  if (found == Pass::Reject) return rejected({}, {});
  if (found != Pass::Step) return found;
  const StopVerdict verdict = stop_.afterDirection(problem_.state(), measures);
  request.take_outright = verdict.final_step;
  request.at_floor = verdict.at_floor;
  const LineSearchResult result = search_.search(problem_, request, d);
  if (!result.accepted) return rejected(result, verdict);
  const Pass after = problem_.accept(result, verdict);
  if (after == Pass::Continue) accepted(verdict, result.alpha);
  return after;
}

Pass PrimalDualLoop::direction(LineSearchRequest* request, Eigen::VectorXd** d,
                               DirectionMeasures* measures) {
  bool primal = false;
  for (int attempt = 0; attempt < (profile_.refactor_after_failure ? 2 : 1); ++attempt) {
    const Pass assembled = problem_.assemble(primal);
    if (assembled != Pass::Step) return assembled;
    const NewtonSystem system = problem_.newtonSystem();
    double shift = 0.0;
    if (!inertia_->factorAndSolve(*system.kkt, *system.rhs, system.d, &shift)) continue;
    const BarrierAccess b = problem_.barrier();
    if (!primal && *b.mu > b.scales.mu_final) {
      mu_->beforeStep(
          b, [&system](Eigen::VectorXd* v) { system.kkt->solve(v); }, *system.rhs, system.d);
    }
    const Pass found = problem_.direction(primal, shift, request, d, measures);
    if (found != Pass::Retry) return found;
    primal = true;
  }
  return problem_.noDirection();
}

void PrimalDualLoop::accepted(const StopVerdict& verdict, double alpha) {
  if (!verdict.final_step && !verdict.at_final_barrier) {
    mu_->afterStep(problem_.barrier(), {verdict.relative_decrement, alpha});
  }
  inertia_->afterStep(alpha, problem_.state().end_game);
  stop_.accepted(verdict, alpha);
}

Pass PrimalDualLoop::rejected(const LineSearchResult& result, const StopVerdict& verdict) {
  const Pass solved = problem_.solvedToRoundOff(result);
  if (solved != Pass::Step) return solved;
  if (const std::optional<LoopEnd> end = stop_.onRejected(problem_.state(), verdict)) {
    return problem_.ended(*end);
  }
  if (inertia_->afterRejection()) return problem_.retry(verdict);
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
