// The pointing end condition R_N b = d (a body axis b aimed at a world direction d) and its free
// twist. Every attitude that meets it is R_N(ψ) = R_ref exp(ψ b^), ψ the twist about b from a
// documented reference R_ref (pointingReference): the planner solves for ψ as a global unknown
// of the transcription (transcription/reduced_problem.hpp), and reports ψ as `final_twist`.
#pragma once

#include "attitude_planner/planning/problem.hpp"
#include "attitude_planner/planning/result.hpp"

namespace attitude_planner {

/// R_ref(b, d): the shortest-arc rotation taking the unit b to the unit d (about b × d by their
/// angle). For b = −d (no shortest arc) a half turn about the unit axis b × e_i / |b × e_i|, e_i
/// the basis vector along b's smallest-magnitude component (the first of equal ones).
Matrix3 pointingReference(const Vector3& body_axis, const Vector3& world_direction);

/// R_N(ψ) = R_ref exp(ψ b^) for `end` (b and d normalized).
Matrix3 pointingAttitude(const EndCondition& end, double twist);

/// The twist ψ ∈ (−π, π] of R about `end`'s body axis from R_ref: atan2 of the b-component of
/// vee(R_refᵀ R) and its cosine part; exact for R = pointingAttitude(end, ψ).
double twistOf(const Matrix3& attitude, const EndCondition& end);

/// The end condition's residual: the angle [rad] between R b and d (atan2 form, exact near 0).
double pointingError(const Matrix3& attitude, const EndCondition& end);

/// The twist whose R_N(ψ) is nearest `from` (least rotation angle of fromᵀ R_N(ψ)), in closed
/// form: tr(fromᵀ R_ref exp(ψ b^)) = c + α sin ψ − β cos ψ is largest at ψ = atan2(α, −β).
double nearestTwist(const Matrix3& from, const EndCondition& end);

/// A pointing plan's end in its summary, the one rule every driver follows: `active`,
/// `final_twist` = twistOf(R_N) and `error` = pointingError(R_N), R_N = `planned_end` (the returned
/// maneuver's last attitude). The stationarity fields and `starts` (the solver's and the driver's)
/// are left as they are.
void summarizePointingEnd(const Matrix3& planned_end, const EndCondition& end,
                          PointingSummary* summary);

/// What a pointing request's answer `r` rests on if it is "infeasible": its verdict proven
/// (below a proven bound, no duration admits a plan), the minimum time over the twist (a
/// LocallyInfeasible T* or MinimumTimeFoundNone: the bounded drivers check it where a torque
/// bound is present), else the starts' local verdicts; None where it is not infeasible.
PointingInfeasibleBasis pointingInfeasibleBasis(const PlanResult& r);

/// `problem` with R_N = `final_attitude` where its end condition is a pointing one (the twist a
/// plan or a start chose: a solve from that plan starts there, and the plan is judged there),
/// else `problem` unchanged.
PlanningProblem endingAt(const PlanningProblem& problem, const Matrix3& final_attitude);

/// Throws InvalidInput naming `field` and the value unless `v` is finite and nonzero.
void requirePointingVector(const Vector3& v, const std::string& field);

}  // namespace attitude_planner
