// The one primal–dual interior-point loop: the order of a pass (limits, the stopping test,
// direction, line search, step or rejection) over a PrimalDualProblem, which holds the iterate,
// its barrier rule and inertia correction, and the termination; the loop calls the stopping test
// (ConvergenceCheck) itself. Two profiles: fixed h
// (grid_solve.cpp) and free time (free_time_solver.cpp).
#pragma once

#include "planning/interior_point/barrier_problem.hpp"
#include "planning/interior_point/line_search.hpp"
#include "planning/problem/solve_context.hpp"

namespace attitude_planner {

struct LoopProfile {
  LineSearchProfile search;
  /// Fixed h tests the iteration limit, then the stop reason, before it assembles; free time the
  /// stop reason, then the limit, after its assembly and convergence test (a solve that
  /// converges on its last allowed pass says so, and a stopped one reports the assembled
  /// residuals). Moving either costs one assembly at the limit and can change what is reported.
  bool limits_before_direction_work = true;
};

class PrimalDualLoop {
 public:
  PrimalDualLoop(PrimalDualProblem& problem, ConvergenceCheck& stop, const LoopProfile& profile,
                 SolveContext& context)
      : problem_(problem),
        stop_(stop),
        profile_(profile),
        search_(profile.search),
        context_(context) {}
  /// Passes until the problem stops, the iteration limit or the context's stop reason, counted
  /// in *iteration (the problem's count, which its hooks read). The iterate and the termination
  /// stay in the problem.
  void run(int max_iterations, int* iteration);

 private:
  Pass pass(int iteration, int max_iterations);
  /// The direction, the stopping test's verdict on it, the line search, the step or rejection.
  Pass step();
  /// No step: a barrier problem solved to round-off, the stopping test, else the problem's retry
  /// or failure.
  Pass rejected(const LineSearchResult& result, const StopVerdict& verdict);
  /// Ends the solve (in the problem) at the iteration limit or a stop reason; false: go on.
  bool limitReached(int iteration, int max_iterations);

  PrimalDualProblem& problem_;
  ConvergenceCheck& stop_;
  const LoopProfile profile_;
  const ArmijoBacktracking search_;
  SolveContext& context_;
};

}  // namespace attitude_planner
