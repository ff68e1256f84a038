// Constraint health of a flown maneuver (the tracker's `done`, docs/ros_tracker.md "Constraint
// health"): how far the body went past each constraint of the plan along the path it really
// flew, and the start a re-plan may use when the body is slightly past a constraint.
//
// A body tracked in closed loop is not the plan: noise, saturation and the law's transients can
// take it past a cone or a rate limit the plan met. The planner refuses a start that violates a
// cone or a rate limit (boundary data are checked against the stated bounds), so a body that is
// inside a keep-out cone by 2e-4 rad could not be re-planned at all: projectOntoConstraints moves
// such a start onto the constraint (the nearest attitude, the largest admissible rate along the
// same direction) when it is past it by less than a tolerance, and says so when it is farther.
#pragma once

#include <string>
#include <vector>

#include "attitude_planner/analysis/tracking.hpp"
#include "attitude_planner/dynamics/discrete_scheme.hpp"
#include "attitude_planner/planning/constraints.hpp"

namespace attitude_planner {

/// How far (R, Ω, τ) is past one node constraint, in its unit, ≥ 0 (0 where it holds):
/// max_torque_norm |τ| − t [N m], max_angular_rate |Ω| − w [rad/s], keep_out / keep_in the angle
/// past the stated half angle a [rad] (not the node bound a ± margin).
double constraintViolation(const PlanningConstraint& constraint, const Matrix3& attitude,
                           const Vector3& angular_velocity, const Vector3& torque);

/// How far τ is past per-axis actuator limits a: max_i (|τ_i| − a_i) [N m], ≥ 0 (infinite a_i: no
/// limit on that axis).
double actuatorLimitViolation(const Vector3& max_torque, const Vector3& torque);

/// The worst violation of each constraint over the states it is shown.
class ConstraintHealth {
 public:
  /// `max_torque`: the actuator limits (all infinite: none); `constraints`: the node constraints.
  ConstraintHealth(const Vector3& max_torque, std::vector<PlanningConstraint> constraints);
  /// Takes one state of the flown path and the torque acting there (commanded or delivered).
  void observe(const Matrix3& attitude, const Vector3& angular_velocity, const Vector3& torque);
  /// The constraints' scene keys: "actuator_limits" first when any limit is finite, then each
  /// node constraint in order (the order of worstViolations()).
  const std::vector<std::string>& names() const { return names_; }
  /// The worst violation of each seen so far [its unit], ≥ 0; 0 before any observe().
  const std::vector<double>& worstViolations() const { return worst_; }
  int observations() const { return observations_; }

 private:
  Vector3 max_torque_;
  bool limited_ = false;
  std::vector<PlanningConstraint> constraints_;
  std::vector<std::string> names_;
  std::vector<double> worst_;
  int observations_ = 0;
};

/// How far past a constraint a re-plan's start may be and still be moved onto it.
struct ProjectionTolerance {
  double cone_angle = 1e-2;     ///< [rad] past a cone's stated half angle
  double rate_fraction = 1e-2;  ///< past a rate limit w, as a fraction of w
};

/// Where a start ends up (projectOntoConstraints).
struct ProjectedStart {
  RigidBodyState state;  ///< the start to plan from (the given one when nothing was past)
  double moved = 0.0;    ///< ‖log(R_givenᵀ R)‖ [rad] the attitude was turned
  double slowed = 0.0;   ///< |Ω_given − Ω| [rad/s] the rate was reduced by
  bool feasible = true;  ///< false: past a constraint by more than the tolerance (state = given)
  std::string refusal;   ///< why not feasible: the constraint, how far past, the tolerance
};

/// Clearance kept inside a bound after a projection, so the planner's check (≥ the bound, in
/// floating point) passes [rad for cones, relative for the rate].
inline constexpr double kProjectionClearance = 1e-9;

/// The start nearest `start` that meets every cone (at its stated half angle) and rate limit of
/// `constraints`, when it is past each by at most `tolerance`: a cone turns the attitude about the
/// axis perpendicular to R b and s by the angle it is past (+ kProjectionClearance), the
/// smallest turn that meets it; a rate limit scales Ω down to the limit. Cones are met one after
/// the other, repeated until all hold (at most a few passes: overlapping cones that push against
/// each other end not feasible). Torque constraints do not restrict a start.
/// `first_step` h > 0: the scheme fixes the first step by the start (paper: F_0 = exp(hΩ_0);
/// variational: its momentum JΩ_0, F_0 = exp(hΩ_0) to O(h³) — firstStepFixedByStart), so
/// R_1 = R_0 exp(hΩ_0) must meet the cones too: it is turned onto them the same way and Ω_0
/// becomes log(R_0ᵀR_1)/h (refused if that rate is past a rate limit).
ProjectedStart projectOntoConstraints(const RigidBodyState& start,
                                      const std::vector<PlanningConstraint>& constraints,
                                      const ProjectionTolerance& tolerance,
                                      double first_step = 0.0);

/// Whether `scheme`'s boundary rate Ω_0 fixes its first step (paper, variational: F_0 from Ω_0)
/// rather than a node rate with a free end torque (second_order, fourth_order).
bool firstStepFixedByStart(SchemeKind scheme);

}  // namespace attitude_planner
