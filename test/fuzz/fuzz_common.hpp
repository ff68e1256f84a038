// Shared by the fuzz targets (fuzz_scene.cpp, fuzz_request.cpp): invariants and the bounded plan.
#pragma once

#include <cmath>
#include <cstdio>
#include <cstdlib>

#include "attitude_planner/errors.hpp"
#include "attitude_planner/planner.hpp"

namespace ap_fuzz {

/// Aborts with a message: the fuzzer records the input as a crash.
inline void invariant(bool ok, const char* what) {
  if (!ok) {
    std::fprintf(stderr, "fuzz invariant violated: %s\n", what);
    std::abort();
  }
}

/// A bounded plan of a valid problem (N ≤ 48, ≤ 30 iterations, 0.5 s): never an exception other
/// than StepTooLarge, and a converged result is finite and lands.
inline void boundedPlan(attitude_planner::PlanningProblem problem) {
  namespace ap = attitude_planner;
  if (problem.steps > 48) return;
  ap::SolverOptions options;
  options.max_iterations = 30;
  options.time_budget_s = 0.5;
  try {
    const ap::PlanResult r = ap::planManeuver(problem, options);
    invariant(r.maneuver.steps() == problem.steps || r.maneuver.attitude.empty(),
              "result has the requested N");
    if (r.converged()) {
      invariant(std::isfinite(r.cost), "converged cost finite");
      invariant(r.terminal_attitude_error <= 1e-6, "converged plan lands (attitude)");
      invariant(r.terminal_velocity_error <= 1e-6, "converged plan lands (velocity)");
      for (const auto& t : r.maneuver.torque) invariant(t.allFinite(), "converged torques finite");
    }
  } catch (const ap::StepTooLarge&) {
    // a boundary velocity without a step at this h: a clean refusal
  }
}

}  // namespace ap_fuzz
