// The free-time iterates the probes below a spinning minimum-time T* meet
// (drivers/minimum_time.cpp): where a free-time solve stops short of its KKT point strictly inside
// every bound, its last iterate is a plan at its own T. The driver keeps the lowest such plan, so
// T* is never answered above it.
#pragma once

#include <cstddef>
#include <optional>

#include "attitude_planner/planning/problem.hpp"
#include "attitude_planner/planning/result.hpp"

namespace attitude_planner {

/// A free-time solve's iterate that ended short of its KKT point strictly inside every bound
/// below its start's T (freeTimeFromPlan's `below`): a plan at its own T, and where that solve is
/// in the context's trail.
struct IterateBelow {
  Maneuver plan;
  std::size_t attempt = 0;
  double duration() const { return plan.time_step * plan.steps(); }
};

/// The minimum-effort problem at `duration` (no time margin): the problem the probes below T*
/// solve, and the one an iterate is a plan of.
PlanningProblem effortAt(const PlanningProblem& problem, double duration);

/// The iterate as a plan at its own T (effort.duration), its figures measured as every plan's
/// (evaluatePlan, the replay), if the one rule for plans accepts it (provesFeasible: the dynamics
/// step by step, the ends and every bound); else empty.
std::optional<PlanResult> iterateAsPlan(const PlanningProblem& effort, const Maneuver& iterate);

/// The lowest of the iterates offered that is a plan at its own T (iterateAsPlan): an upper
/// bound on T* whether or not a probe took it.
class LowestIterate {
 public:
  struct Plan {
    PlanningProblem effort;   ///< minimum effort at the iterate's T
    PlanResult plan;          ///< iterateAsPlan's
    std::size_t attempt = 0;  ///< its free-time solve in the trail
  };

  /// Keeps `iterate` (problem: the minimum-time request) if it lies below the lowest kept and is
  /// a plan at its T; an iterate not shown a plan is dropped.
  void offer(const PlanningProblem& problem, const std::optional<IterateBelow>& iterate);
  /// The lowest plan kept if it lies strictly below `duration`, else null.
  const Plan* below(double duration) const {
    return lowest_ && lowest_->effort.duration < duration ? &*lowest_ : nullptr;
  }

 private:
  std::optional<Plan> lowest_;
};

}  // namespace attitude_planner
