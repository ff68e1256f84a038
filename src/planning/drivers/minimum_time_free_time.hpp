// Minimum time as one free-time interior-point problem per start (drivers/minimum_time.cpp's
// answer where it applies): the structured starts (minimum_time_starts.hpp) solved on the
// coarsest level of the free-time grid continuation, the least T kept and carried through the
// finer levels (strategies/grid_continuation.hpp); its free-time plan is the answer. T* is a KKT
// point of the discrete minimum-time problem (interior_point/free_time_solver.hpp).
#pragma once

#include <optional>
#include <string>
#include <vector>

#include "attitude_planner/planning/plan_at_resolution.hpp"
#include "planning/drivers/free_time_recipe.hpp"
#include "planning/strategies/grid_continuation.hpp"

namespace attitude_planner {

/// The starts run on the coarsest of N, N/2, ... at or above this N; the best is refined up.
constexpr int kFreeTimeStartGrid = 64;

/// The free-time grid levels (strategies/grid_continuation.hpp): N, N/2, ... down to the coarsest
/// at or above kFreeTimeStartGrid, each solved to kFreeTimeTolerance. A refinement by 2 at a time:
/// measured, a resampled N = 64 plan started N = 512 so far from its optimum that the solve slid
/// to the eigenaxis slew's T. Below 2 kFreeTimeStartGrid a grid's half would be under the
/// coarsest, so it is solved on its own. A refined level that does not converge ends the
/// continuation with no answer (a fresh start there would be another attempt; the caller falls
/// back to the search).
GridLevelRule freeTimeGridRule();

/// The grid levels a free-time solve continues over (freeTimeGridRule), less the coarse ones
/// whose boundary steps would turn more than representableDuration allows at the proven least
/// duration (durationLowerBound): a start there has no boundary step, so the continuation starts
/// on the first grid that has one.
std::vector<PlanningProblem> freeTimeLevels(const PlanningProblem& problem);

/// The free-time answer on a coarser grid carried to grid p at its T: the coarse rates
/// interpolated in time (ReducedProblem::initializeFromCoarser), so the torques stay near the
/// coarse ones. (Resampling the attitudes instead put torque spikes of ~1.5× the bound next to
/// the switches of a bang–bang plan: the free-time start then had to raise T by ~27 % before
/// every bound held, measured on Bilimoria–Wie, N = 512 → 1024.) With cones the new nodes
/// between the coarse ones dip past an active bound by O(h²): they are turned out of the cones
/// (pushedOutOfCones), as a free-time start must clear them strictly.
std::vector<Matrix3> prolonged(const PlanningProblem& p, const FreeTimeOutcome& coarse);

/// The minimum-time plan from the free-time solves: the kept plan at T* (minimum_time.kkt_point
/// true, the KKT residuals in minimum_time, every solve in attempts, the free-time levels first in
/// levels), or empty if no start converged or a refined level did not (the caller falls back to
/// the search). Every solve is recorded in the context's trail, the one returned kept.
std::optional<PlanResult> freeTimeMinimumTime(const PlanningProblem& problem,
                                              SolveContext& context);

/// One free-time solve on the requested grid from `plan`, a plan meeting every bound at T =
/// `duration` (the search's answer where the structured starts did not converge, a probe's, ...;
/// `start` names it in the answer's message): its
/// KKT point if it converged at or below `duration`, else empty (its solve is in the context's
/// trail either way). Where it ended short of a KKT point at an iterate strictly inside every
/// bound below `duration`, that iterate's plan goes to `*below` (a plan at its own T). `barrier`:
/// where its barrier begins (StartBarrier::NearKktPoint for a plan that is a neighbouring
/// problem's KKT point). `watch`: the caller's stop at a solved barrier problem (empty if none).
std::optional<PlanResult> freeTimeFromPlan(const PlanningProblem& problem, const Maneuver& plan,
                                           double duration, const std::string& start,
                                           SolveContext& context,
                                           std::optional<Maneuver>* below = nullptr,
                                           StartBarrier barrier = StartBarrier::Initial,
                                           const BarrierWatch& watch = {});

/// The attitudes of a converged outcome's plan moved by `size` [rad, signed] along its
/// negative-curvature direction (R_j exp(size δ_j^)), the boundary attitudes kept: a start off a
/// saddle, one free-time solve from it descends into a basin on either side. Empty where the
/// outcome has no such direction.
std::vector<Matrix3> displacedAlongNegativeCurvature(const PlanningProblem& problem,
                                                     const FreeTimeOutcome& outcome, double size);
}  // namespace attitude_planner
