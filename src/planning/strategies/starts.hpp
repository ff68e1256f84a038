// Where a solve starts: the lifts of the rotation between the ends (each a homotopy class), the
// rate-honouring Hermite curve to one of them, and the coasting start. Solver-agnostic: each is
// a first iterate on the reduced problem, or a maneuver to warm-start from.
#pragma once

#include <optional>
#include <vector>

#include "attitude_planner/dynamics/maneuver.hpp"
#include "attitude_planner/planning/problem.hpp"
#include "attitude_planner/planning/result.hpp"
#include "planning/transcription/reduced_problem.hpp"

namespace attitude_planner {

/// One lift ψ = (θ + 2πk) u of the rotation R_1ᵀ R_{N−1} (θ u the principal one), extra
/// revolutions added in its own sense.
struct Lift {
  Vector3 rotation;        ///< ψ (extra revolutions included)
  HomotopyClass homotopy;  ///< nearest (long_way false) or second-nearest, and the extra turns
  double distance = 0.0;   ///< |ψ − coasting displacement| without the extra revolutions
};

/// The two lifts nearest the coasting displacement c = T (Ω_0 + R_1ᵀR_{N−1} Ω_{N−1})/2 (rest to
/// rest c = 0: the principal rotation first, the other way round second).
std::vector<Lift> nearestLifts(const PlanningProblem& problem, const ReducedProblem& reduced);

/// Puts the Hermite curve to the lift for problem.direction on `reduced` (matching both boundary
/// velocities) and returns that lift.
Lift startOnHermiteCurve(const PlanningProblem& problem, ReducedProblem* reduced);

/// The extremal a plan from `lift` belongs to (PlanResult::extremal_summary without `others`).
ExtremalSummary extremalOf(const Lift& lift);

/// Ω_0 or Ω_{N−1} nonzero.
bool hasSpinningEnds(const PlanningProblem& problem);

/// The coasting start: the torque-free motions from both ends blended in their body steps (a
/// smoothstep in time), the gap at R_{N−1} closed by a cubic. Long spinning maneuvers coast most
/// of the way; the Hermite curve matches only the end rates. Nothing if a torque-free step has
/// no solution at this h.
std::optional<Maneuver> coastingStart(const PlanningProblem& problem);

/// Starts on either side of the keep-out cone a plan violates most deeply: the plan's attitudes
/// (N + 1) turned in the world, over the nodes inside the cone and as many again on each side
/// (tapering to none at the boundary nodes), by the rotation that takes the deepest node's
/// boresight to kConeSideOffset × the node bound (half angle + margin) from the cone's axis, on one
/// side of the path and then on the other (the side is across the path's direction there). Empty if
/// the plan violates no keep-out cone at a free node. Which side a solve from the violating plan
/// passes is decided by its first steps; these name it.
std::vector<Maneuver> coneSideStarts(const PlanningProblem& problem, const Maneuver& plan);

/// How far off a cone's axis a side start puts the deepest node's boresight, in half angles.
constexpr double kConeSideOffset = 1.25;

}  // namespace attitude_planner
