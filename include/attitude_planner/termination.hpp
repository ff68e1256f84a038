// How a solve ended (Termination): below every layer, so each planner reports its end the same
// way and every caller maps it in one place.
#pragma once

#include <string>

namespace attitude_planner {

/// How a solve ended: the one status of a result (of both planners: the maneuver planner and
/// the drift + two-input planner). Messages explain it, they never carry it; the
/// node maps it to PlanErrorCode in one switch (ros/planner_node.cpp, errorCodeOf).
enum class Termination {
  Converged,     ///< first-order optimal and consistent to the tolerance
  NotConverged,  ///< iteration limit, stall, or a check failed (the message says which)
  Infeasible,    ///< the constraints admit no maneuver (the message names the binding one)
  StepTooLarge,  ///< an implicit step has no solution at this h (h·|Ω| too large): increase N
  TimedOut,      ///< the time budget ran out (the plan so far is returned)
  Cancelled,     ///< the caller asked to stop (on_iteration or the cancel flag; the plan so far)
  InvalidInput,  ///< the problem or options were refused (a node answers this; the core throws)
};

/// "converged", "not_converged", "infeasible", "step_too_large", "timed_out", "cancelled",
/// "invalid_input" (JSON summary, logs).
std::string terminationName(Termination termination);

}  // namespace attitude_planner
