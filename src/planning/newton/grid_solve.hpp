// Newton on one grid: a short loop over named pieces — the Newton step (newtonStep: normal
// equations or the augmented system), the step control (step_control.hpp: trust region or line
// search), the stopping test (StoppingTest) — on the reduced problem (reduced_problem.hpp), whose
// cost is the merit function. O(N) time and memory per iteration.
#pragma once

#include <optional>

#include "attitude_planner/planning/newton_parameters.hpp"
#include "attitude_planner/planning/problem.hpp"
#include "attitude_planner/planning/result.hpp"
#include "planning/newton/step_control.hpp"
#include "planning/problem/solve_context.hpp"
#include "planning/problem/verdict.hpp"
#include "planning/transcription/reduced_problem.hpp"

namespace attitude_planner {

/// What one grid solve iterates to and with.
struct GridSettings {
  double tolerance = 1e-10;  ///< on the relative Newton decrement
  int max_iterations = 200;
  Globalization globalization = Globalization::TrustRegion;
  /// Where set, a plan its solver converged to is not checked (planInconsistency): the step
  /// residual measured for its figures is left here, and the caller checks the plan if it keeps
  /// it (checkDeferredPlan; the Newton walk checks only the plan it keeps).
  std::optional<StepResidual>* deferred_check = nullptr;
};

/// Where one grid solve starts: the Hermite curve to the request's lift, replaced by the warm
/// start's attitudes if given, then by the coarser level's steps if given (extrapolated with the
/// one below it if given too).
struct GridStart {
  const Maneuver* warm_start = nullptr;
  const ReducedProblem::StepVectors* coarse = nullptr;
  const ReducedProblem::StepVectors* coarser = nullptr;
};

/// Newton on `problem`'s grid. Iterations are reported through `context` (numbered across the
/// request); a cancel or the deadline ends it with its last accepted iterate. With `final_steps`
/// (a coarse level) only the final iterate is produced, no plan figures.
PlanResult solveOnGrid(const PlanningProblem& problem, SolveContext& context,
                       const GridSettings& settings, const GridStart& start,
                       ReducedProblem::StepVectors* final_steps,
                       const NewtonParameters& parameters);

/// The check solveOnGrid deferred (GridSettings::deferred_check) of its converged `plan` (a grid
/// continuation's finest level, its notes added after): true if it passes; else the plan becomes
/// what solveOnGrid returns for a plan that fails its check (not converged, the check's words as
/// how its Newton solve and its level ended). `stepwise`: the plan's stepwise replay if measured
/// already (planInconsistency).
bool checkDeferredPlan(const PlanningProblem& problem, const StepResidual& residual,
                       PlanResult* plan, const StepwiseReplay* stepwise = nullptr);

}  // namespace attitude_planner
