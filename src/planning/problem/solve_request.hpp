// What a driver hands a solver: the user's options and where the solve starts. The start is the
// drivers' knowledge of the plan they hand on (a constrained plan, one strictly inside, the
// unconstrained optimum already solved), which no user sets; SolverOptions carried it as three
// public fields, deprecated there and translated here when a user's options enter a solve.
#pragma once

#include "attitude_planner/planning/problem.hpp"

namespace attitude_planner {

/// Where a solve starts beyond the user's warm start (SolverOptions::warm_start).
struct StartSpec {
  /// With node constraints and a warm start: the warm start is a plan under the constraints and
  /// starts the interior point itself, instead of its unconstrained optimum (the minimum-time
  /// search's last feasible plan is far closer to the next one).
  bool from_constrained_plan = false;
  /// With from_constrained_plan: that plan meets every constraint with room (a plan at T*
  /// time-scaled to a longer T), so the interior point takes a request's own recipe (free
  /// slacks, Mehrotra) rather than the probes' (elastic form first, LOQO's barrier), which is for
  /// starts that may be infeasible (drivers/constrained_recipe.cpp).
  bool strictly_inside = false;
  /// With node constraints and no warm start: the request's unconstrained optimum, already solved
  /// on its grid in its class (the class survey's plan, drivers/constrained_classes.cpp). Newton
  /// polishes it (an iteration or two) instead of solving the class again through the grids, and
  /// it starts the interior point as that solve would. Null, or another N: none.
  const Maneuver* unconstrained_optimum = nullptr;
};

/// The user's options and the start. A request is a SolverOptions (a solver that needs no start
/// takes it as one); only the functions that read the start take a SolveRequest.
struct SolveRequest : SolverOptions {
  StartSpec start;

  /// `options` as a request: the start their deprecated fields ask for (an API user's; the
  /// planner sets none), those fields cleared so that the start is read from `start` alone.
  explicit SolveRequest(const SolverOptions& options) : SolverOptions(options) {
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wdeprecated-declarations"
    start = {options.constrained_from_warm_start, options.warm_start_strictly_inside,
             options.unconstrained_optimum};
    constrained_from_warm_start = warm_start_strictly_inside = false;
    unconstrained_optimum = nullptr;
#pragma GCC diagnostic pop
  }
  /// `options` (whose deprecated fields a driver does not set) with the start `from`.
  SolveRequest(const SolverOptions& options, const StartSpec& from) : SolveRequest(options) {
    start = from;
  }
};

}  // namespace attitude_planner
