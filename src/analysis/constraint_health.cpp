#include "attitude_planner/analysis/constraint_health.hpp"

#include <algorithm>
#include <cmath>
#include <utility>

#include "attitude_planner/errors.hpp"

namespace attitude_planner {

double constraintViolation(const PlanningConstraint& constraint, const Matrix3& attitude,
                           const Vector3& angular_velocity, const Vector3& torque) {
  if (constraint.isCone()) return std::max(0.0, -coneMargin(constraint, attitude));
  const double value =
      constraint.kind == ConstraintKind::MaxAngularRate ? angular_velocity.norm() : torque.norm();
  return std::max(0.0, value - constraint.limit);
}

double actuatorLimitViolation(const Vector3& max_torque, const Vector3& torque) {
  double worst = 0.0;
  for (int i = 0; i < 3; ++i) {
    if (std::isfinite(max_torque[i])) worst = std::max(worst, std::abs(torque[i]) - max_torque[i]);
  }
  return worst;
}

ConstraintHealth::ConstraintHealth(const Vector3& max_torque,
                                   std::vector<PlanningConstraint> constraints)
    : max_torque_(max_torque), constraints_(std::move(constraints)) {
  limited_ = max_torque_.array().isFinite().any();
  if (limited_) names_.push_back("actuator_limits");
  for (const PlanningConstraint& c : constraints_) names_.push_back(constraintKindName(c.kind));
  worst_.assign(names_.size(), 0.0);
}

void ConstraintHealth::observe(const Matrix3& attitude, const Vector3& angular_velocity,
                               const Vector3& torque) {
  std::size_t i = 0;
  if (limited_) {
    worst_[i] = std::max(worst_[i], actuatorLimitViolation(max_torque_, torque));
    ++i;
  }
  for (const PlanningConstraint& c : constraints_) {
    worst_[i] = std::max(worst_[i], constraintViolation(c, attitude, angular_velocity, torque));
    ++i;
  }
  ++observations_;
}

namespace {

/// A unit vector perpendicular to `v` (unit).
Vector3 anyPerpendicular(const Vector3& v) {
  const Vector3 other = std::abs(v.x()) < 0.9 ? Vector3::UnitX() : Vector3::UnitY();
  return v.cross(other).normalized();
}

/// R turned in the world about the axis perpendicular to R b and s so that R b meets the cone's
/// stated half angle with kProjectionClearance to spare: away from s (keep_out) or towards it
/// (keep_in), by exactly the angle it is past (the smallest turn that meets the cone).
Matrix3 turnedOntoCone(const PlanningConstraint& cone, const Matrix3& R, double past) {
  const Vector3 pointing = R * cone.body_axis;
  Vector3 axis = cone.world_direction.cross(pointing);
  // R b on s (or opposite): every perpendicular axis turns it the same way.
  axis = axis.norm() > 1e-12 ? axis.normalized() : anyPerpendicular(cone.world_direction);
  // A positive turn about s × R b moves R b away from s.
  const double turn = past + kProjectionClearance;
  const double signed_turn = cone.kind == ConstraintKind::KeepOut ? turn : -turn;
  return so3::exp(Vector3(signed_turn * axis)) * R;
}

/// Projects the rate onto the rate limits (they do not interact with the cones).
void projectRates(const std::vector<PlanningConstraint>& constraints,
                  const ProjectionTolerance& tolerance, ProjectedStart* out) {
  for (std::size_t i = 0; i < constraints.size(); ++i) {
    const PlanningConstraint& c = constraints[i];
    if (c.kind != ConstraintKind::MaxAngularRate) continue;
    const double rate = out->state.angular_velocity.norm();
    if (rate <= c.limit) continue;
    if (rate > c.limit * (1.0 + tolerance.rate_fraction)) {
      out->feasible = false;
      out->refusal = "|Omega| = " + exactNumber(rate) + " rad/s is past constraints[" +
                     std::to_string(i) + "] (max_angular_rate " + exactNumber(c.limit) +
                     " rad/s) by more than the tolerance (" + exactNumber(tolerance.rate_fraction) +
                     " of the limit)";
      return;
    }
    out->state.angular_velocity *= c.limit * (1.0 - kProjectionClearance) / rate;
  }
}

/// Turns `attitude` onto every cone it is past by at most the tolerance; false with `refusal`
/// set (naming `which` attitude) when one is farther or the cones push against each other.
bool meetCones(const std::vector<PlanningConstraint>& constraints, double tolerance,
               const std::string& which, Matrix3* attitude, std::string* refusal) {
  // Cones are met one by one; a few passes settle cones that do not push against each other,
  // and the last pass only checks.
  constexpr int kPasses = 4;
  for (int pass = 0; pass <= kPasses; ++pass) {
    bool all_met = true;
    for (std::size_t i = 0; i < constraints.size(); ++i) {
      const PlanningConstraint& c = constraints[i];
      if (!c.isCone()) continue;
      const double past = -coneMargin(c, *attitude);
      if (past <= 0.0) continue;
      all_met = false;
      if (past > tolerance || pass == kPasses) {
        *refusal =
            which + " is " + exactNumber(past) + " rad past constraints[" + std::to_string(i) +
            "] (" + describeConstraint(c) + ")" +
            (pass == kPasses ? " after meeting the other cones"
                             : ", more than the tolerance " + exactNumber(tolerance) + " rad");
        return false;
      }
      *attitude = turnedOntoCone(c, *attitude, past);
    }
    if (all_met) return true;
  }
  return true;
}

}  // namespace

ProjectedStart projectOntoConstraints(const RigidBodyState& start,
                                      const std::vector<PlanningConstraint>& constraints,
                                      const ProjectionTolerance& tolerance, double first_step) {
  ProjectedStart out;
  out.state = start;
  const auto refuse = [&](std::string why) {
    out.feasible = false;
    out.refusal = std::move(why);
    out.state = start;
    return out;
  };
  std::string why;
  if (!meetCones(constraints, tolerance.cone_angle, "the attitude", &out.state.attitude, &why))
    return refuse(why);
  projectRates(constraints, tolerance, &out);
  if (!out.feasible) return refuse(out.refusal);
  if (first_step > 0.0) {
    // R_1 = R_0 exp(h Ω_0) is boundary data too: turned onto the cones, Ω_0 follows it.
    const Matrix3& R0 = out.state.attitude;
    const Matrix3 R1 = R0 * so3::exp(Vector3(first_step * out.state.angular_velocity));
    Matrix3 R1_met = R1;
    if (!meetCones(constraints, tolerance.cone_angle, "the attitude after the first step", &R1_met,
                   &why))
      return refuse(why);
    if (R1_met != R1)  // only then: the log's round trip would move an untouched Ω_0 by ulps
      out.state.angular_velocity = so3::log(Matrix3(R0.transpose() * R1_met)) / first_step;
    for (const PlanningConstraint& c : constraints) {
      if (c.kind == ConstraintKind::MaxAngularRate && out.state.angular_velocity.norm() > c.limit)
        return refuse("the rate that keeps the first step outside the cones is past " +
                      describeConstraint(c));
    }
  }
  out.moved = so3::angleBetween(start.attitude, out.state.attitude);
  out.slowed = (start.angular_velocity - out.state.angular_velocity).norm();
  return out;
}

bool firstStepFixedByStart(SchemeKind scheme) {
  return scheme == SchemeKind::Paper || scheme == SchemeKind::Variational;
}

}  // namespace attitude_planner
