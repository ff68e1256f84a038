// Planning constraints at every node (scene key `constraints:`, DESIGN.md "Scene file"), besides
// the per-axis actuator limits |τ_i| ≤ a_i (effect `actuator_limits`, PlanningProblem::max_torque):
//
//   max_torque_norm  t   |τ_k|₂ ≤ t [N m],            k = 1..N−1 (control torque)
//   max_angular_rate w   |Ω_k|₂ ≤ w [rad/s],          k = 0..N−1 (the scheme's reported Ω_k)
//   keep_out {b, s, a}   angle(R_k b, s) ≥ a [rad],   k = 0..N
//   keep_in  {b, s, a}   angle(R_k b, s) ≤ a [rad],   k = 0..N
//
// b is a unit body axis, s a unit world direction, a ∈ (0, π). The constraints hold at the nodes.
// Between two nodes the motion R_k exp(s ω_k^), s ∈ [0, 1], ω_k = log(R_kᵀR_{k+1}), keeps the
// torque bounds (torques are held) and, for the paper scheme, the rate bound (constant rate
// ω_k/h); a cone's angle can dip past its bound by up to a − acos(cos a + |ω_k|²/8) (keep_out,
// docs/notes/constraints_notes.md "Between nodes"). A cone's `margin` m tightens its node bound to
// a + m (keep_out) or a − m (keep_in); requiredConeMargin gives the m that keeps the continuous
// motion outside (inside) the cone for steps up to a given angle.
#pragma once

#include <string>
#include <vector>

#include "attitude_planner/lie/so3.hpp"

namespace attitude_planner {

enum class ConstraintKind { MaxTorqueNorm, MaxAngularRate, KeepOut, KeepIn };

/// The scene key of a kind: "max_torque_norm", "max_angular_rate", "keep_out", "keep_in".
std::string constraintKindName(ConstraintKind kind);

/// One constraint imposed at every node.
struct PlanningConstraint {
  ConstraintKind kind = ConstraintKind::MaxTorqueNorm;
  double limit = 0.0;                          ///< t [N m] or w [rad/s] (norm and rate kinds)
  Vector3 body_axis = Vector3::UnitZ();        ///< b, unit, body frame (cone kinds)
  Vector3 world_direction = Vector3::UnitX();  ///< s, unit, world frame (cone kinds)
  double half_angle = 0.0;                     ///< a [rad] in (0, π) (cone kinds)
  /// m [rad] ≥ 0 (cone kinds): the nodes keep a + m (keep_out) or a − m (keep_in).
  double margin = 0.0;

  static PlanningConstraint maxTorqueNorm(double max_torque_norm);
  static PlanningConstraint maxAngularRate(double max_angular_rate);
  static PlanningConstraint keepOut(const Vector3& body_axis, const Vector3& world_direction,
                                    double half_angle, double margin = 0.0);
  static PlanningConstraint keepIn(const Vector3& body_axis, const Vector3& world_direction,
                                   double half_angle, double margin = 0.0);
  bool isCone() const { return kind == ConstraintKind::KeepOut || kind == ConstraintKind::KeepIn; }
  /// The half angle the planner imposes at the nodes [rad]: a + m (keep_out), a − m (keep_in).
  double nodeHalfAngle() const {
    return kind == ConstraintKind::KeepOut ? half_angle + margin : half_angle - margin;
  }
};

/// Tolerance on |b|, |s| − 1 for a unit vector.
constexpr double kUnitVectorTolerance = 1e-9;

/// Checks the values (limits finite and > 0; b, s unit within kUnitVectorTolerance; half angle in
/// (0, π); margin ≥ 0 with the node half angle still in (0, π)); throws InvalidInput naming
/// `field`[i].<kind>.<key> and the value.
void validateConstraints(const std::vector<PlanningConstraint>& constraints,
                         const std::string& field);

/// Signed margin of a cone constraint at attitude R [rad]: ≥ 0 where it holds
/// (keep_out: angle − a, keep_in: a − angle).
double coneMargin(const PlanningConstraint& cone, const Matrix3& R);

/// The smallest signed margin [rad] of a cone (against its half angle, not the node bound) over
/// the motion between two nodes, R_k exp(s ω^), s ∈ [0, 1], ω = log(R_kᵀ R_next): exact (the
/// pointing cosine is A + B cos(s|ω|) + C sin(s|ω|); its extremes are in closed form).
double coneMarginOverStep(const PlanningConstraint& cone, const Matrix3& R_k,
                          const Matrix3& R_next);

/// The node margin m [rad] that keeps a cone's half angle a over every step of angle ≤
/// `step_angle` = |ω| [rad] whose end nodes meet the tightened bound: the pointing cosine p(s)
/// exceeds the chord between its end values by at most |ω|²/8 (|p''| ≤ |ω|²), so
/// m = acos(cos a − |ω|²/8) − a (keep_out), a − acos(cos a + |ω|²/8) (keep_in); +∞ if no node
/// bound can guarantee it (the cosine offset leaves [−1, 1]).
double requiredConeMargin(const PlanningConstraint& cone, double step_angle);

/// A one-line description, e.g. "keep_out {body_axis [0, 0, 1], world_direction [1, 0, 0],
/// half_angle 0.5 rad}" or "max_angular_rate 0.2 rad/s".
std::string describeConstraint(const PlanningConstraint& constraint);

}  // namespace attitude_planner
