// The free-time iterates the probes below a spinning minimum-time T* meet
// (drivers/minimum_time.cpp): where a free-time solve stops short of its KKT point strictly inside
// every bound, its last iterate is a plan at its own T. The driver keeps the lowest such plan of
// each chain (the iterates that descend from one solve's, each probe from the last), so T* is never
// answered above the lowest, and the probes can run again from each chain's.
#pragma once

#include <cstddef>
#include <optional>
#include <vector>

#include "attitude_planner/planning/problem.hpp"
#include "attitude_planner/planning/result.hpp"

namespace attitude_planner {

/// A free-time solve's iterate that ended short of its KKT point strictly inside every bound
/// below its start's T (freeTimeFromPlan's `below`): a plan at its own T, and where that solve is
/// in the context's trail; `chain_root` the trail's attempt of its chain's first solve where the
/// solve started from an earlier iterate's chain (empty: its chain starts at its own solve).
struct IterateBelow {
  Maneuver plan;
  std::size_t attempt = 0;
  std::optional<std::size_t> chain_root;
  double duration() const { return plan.time_step * plan.steps(); }
  std::size_t root() const { return chain_root.value_or(attempt); }
};

/// The minimum-effort problem at `duration` (no time margin): the problem the probes below T*
/// solve, and the one an iterate is a plan of.
PlanningProblem effortAt(const PlanningProblem& problem, double duration);

/// The iterate as a plan at its own T (effort.duration), its figures measured as every plan's
/// (evaluatePlan, the replay), if the one rule for plans accepts it (provesFeasible: the dynamics
/// step by step, the ends and every bound); else empty.
std::optional<PlanResult> iterateAsPlan(const PlanningProblem& effort, const Maneuver& iterate);

/// The lowest of each chain's iterates offered that is a plan at its own T (iterateAsPlan): the
/// lowest of all is an upper bound on T* whether or not a probe took it, and each chain's is a
/// start the probes below T* can run from again.
class LowestIterate {
 public:
  struct Plan {
    PlanningProblem effort;   ///< minimum effort at the iterate's T
    PlanResult plan;          ///< iterateAsPlan's
    std::size_t attempt = 0;  ///< its free-time solve in the trail
    std::size_t root = 0;     ///< its chain (IterateBelow::root)
  };

  /// Keeps `iterate` (problem: the minimum-time request) if it lies below the lowest kept of its
  /// chain and is a plan at its T; an iterate not shown a plan is dropped.
  void offer(const PlanningProblem& problem, const std::optional<IterateBelow>& iterate);
  /// The lowest plan kept if it lies strictly below `duration`, else null (of equal ones, the
  /// first chain's).
  const Plan* below(double duration) const;
  /// Each chain's lowest plan strictly below `duration` but chain `except_root`'s, highest first.
  std::vector<Plan> chainsBelow(double duration, std::size_t except_root) const;

 private:
  std::vector<Plan> chains_;  ///< one per chain: its lowest plan, in the order chains began
};

}  // namespace attitude_planner
