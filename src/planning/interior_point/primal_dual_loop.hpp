// The one primal–dual interior-point loop: the order of a pass (limits, the stopping test, the
// barrier problem solved, direction, line search, step or rejection) over a PrimalDualProblem,
// which holds the iterate and the termination. The loop calls the strategies itself: the stopping
// test (ConvergenceCheck), the μ rule (BarrierUpdate) and the inertia correction
// (InertiaCorrection), the last two its own. Two profiles: fixed h (grid_solve.cpp) and free time
// (free_time_solver.cpp).
#pragma once

#include <memory>

#include "planning/interior_point/barrier_problem.hpp"
#include "planning/interior_point/barrier_update.hpp"
#include "planning/interior_point/inertia_correction.hpp"
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
  /// A system no shift factors is assembled and factored once more (fixed h); free time, whose
  /// system is the pass's, rejects at once.
  bool refactor_after_failure = true;
};

/// One profile's strategies: the stopping test (the problem's: it keeps a memory the problem
/// reads), the μ rule and the inertia correction (the loop's).
struct LoopStrategies {
  ConvergenceCheck& stop;
  std::unique_ptr<BarrierUpdate> mu;
  std::unique_ptr<InertiaCorrection> inertia;
};

class PrimalDualLoop {
 public:
  PrimalDualLoop(PrimalDualProblem& problem, LoopStrategies strategies, const LoopProfile& profile,
                 SolveContext& context)
      : problem_(problem),
        stop_(strategies.stop),
        mu_(std::move(strategies.mu)),
        inertia_(std::move(strategies.inertia)),
        profile_(profile),
        search_(profile.search),
        context_(context) {}
  /// Passes until the problem stops, the iteration limit or the context's stop reason, counted
  /// in *iteration (the problem's count, which its hooks read). The iterate and the termination
  /// stay in the problem.
  void run(int max_iterations, int* iteration);

 private:
  Pass pass(int iteration, int max_iterations);
  /// The barrier problem is solved: the problem's observer, then μ falls (a pass without a step).
  Pass barrierSolved();
  /// The direction, the stopping test's verdict on it, the line search, the step or rejection.
  Pass step();
  /// Assembly, the inertia correction, the μ rule's predictor and the problem's verdict on the
  /// direction, once more with the primal multipliers where it is no descent direction.
  Pass direction(LineSearchRequest* request, Eigen::VectorXd** d, DirectionMeasures* measures);
  /// A step taken: the μ rule, the inertia correction and the stopping test updated.
  void accepted(const StopVerdict& verdict, double alpha);
  /// No step: a barrier problem solved to round-off, the stopping test, the inertia correction's
  /// retry, else the problem's failure.
  Pass rejected(const LineSearchResult& result, const StopVerdict& verdict);
  /// Ends the solve (in the problem) at the iteration limit or a stop reason; false: go on.
  bool limitReached(int iteration, int max_iterations);

  PrimalDualProblem& problem_;
  ConvergenceCheck& stop_;
  std::unique_ptr<BarrierUpdate> mu_;
  std::unique_ptr<InertiaCorrection> inertia_;
  const LoopProfile profile_;
  const ArmijoBacktracking search_;
  SolveContext& context_;
};

}  // namespace attitude_planner
