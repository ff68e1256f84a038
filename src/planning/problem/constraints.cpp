#include "attitude_planner/planning/constraints.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include "attitude_planner/errors.hpp"
#include "attitude_planner/planning/problem.hpp"

namespace attitude_planner {

std::string constraintKindName(ConstraintKind kind) {
  switch (kind) {
    case ConstraintKind::MaxTorqueNorm:
      return "max_torque_norm";
    case ConstraintKind::MaxAngularRate:
      return "max_angular_rate";
    case ConstraintKind::KeepOut:
      return "keep_out";
    case ConstraintKind::KeepIn:
      return "keep_in";
  }
  return "unknown";
}

PlanningConstraint PlanningConstraint::maxTorqueNorm(double max_torque_norm) {
  PlanningConstraint c;
  c.kind = ConstraintKind::MaxTorqueNorm;
  c.limit = max_torque_norm;
  return c;
}

PlanningConstraint PlanningConstraint::maxAngularRate(double max_angular_rate) {
  PlanningConstraint c;
  c.kind = ConstraintKind::MaxAngularRate;
  c.limit = max_angular_rate;
  return c;
}

PlanningConstraint PlanningConstraint::keepOut(const Vector3& body_axis,
                                               const Vector3& world_direction, double half_angle,
                                               double margin) {
  PlanningConstraint c;
  c.kind = ConstraintKind::KeepOut;
  c.body_axis = body_axis;
  c.world_direction = world_direction;
  c.half_angle = half_angle;
  c.margin = margin;
  return c;
}

PlanningConstraint PlanningConstraint::keepIn(const Vector3& body_axis,
                                              const Vector3& world_direction, double half_angle,
                                              double margin) {
  PlanningConstraint c = keepOut(body_axis, world_direction, half_angle, margin);
  c.kind = ConstraintKind::KeepIn;
  return c;
}

namespace {

std::string vectorText(const Vector3& v) {
  return "[" + exactNumber(v(0)) + ", " + exactNumber(v(1)) + ", " + exactNumber(v(2)) + "]";
}

void requireUnit(const Vector3& v, const std::string& path) {
  if (!v.allFinite()) throw InvalidInput(path, "not finite: " + vectorText(v));
  if (v.norm() == 0.0)
    throw InvalidInput(path, "zero vector " + vectorText(v) + " has no direction");
  if (std::abs(v.norm() - 1.0) > kUnitVectorTolerance) {
    throw InvalidInput(path, "not a unit vector: " + vectorText(v) + " has norm " +
                                 exactNumber(v.norm()) + " (must be within " +
                                 exactNumber(kUnitVectorTolerance) + " of 1)");
  }
}

}  // namespace

void validateConstraints(const std::vector<PlanningConstraint>& constraints,
                         const std::string& field) {
  for (std::size_t i = 0; i < constraints.size(); ++i) {
    const PlanningConstraint& c = constraints[i];
    const std::string path = field + "[" + std::to_string(i) + "]." + constraintKindName(c.kind);
    if (c.isCone()) {
      requireUnit(c.body_axis, path + ".body_axis");
      requireUnit(c.world_direction, path + ".world_direction");
      if (!std::isfinite(c.half_angle) || !(c.half_angle > 0.0) || !(c.half_angle < M_PI)) {
        throw InvalidInput(path + ".half_angle",
                           "must be in (0, pi) rad, got " + exactNumber(c.half_angle));
      }
      const double node = c.nodeHalfAngle();
      if (!std::isfinite(c.margin) || !(c.margin >= 0.0) || !(node > 0.0) || !(node < M_PI)) {
        throw InvalidInput(path + ".margin",
                           std::string("must be >= 0 rad and leave a cone (") +
                               (c.kind == ConstraintKind::KeepOut ? "half_angle + margin < pi"
                                                                  : "half_angle - margin > 0") +
                               "), got " + exactNumber(c.margin));
      }
    } else {
      const char* unit = c.kind == ConstraintKind::MaxTorqueNorm ? " N m" : " rad/s";
      if (!std::isfinite(c.limit) || !(c.limit > 0.0)) {
        throw InvalidInput(path, std::string("must be a finite number > 0") + unit + ", got " +
                                     exactNumber(c.limit));
      }
    }
  }
}

double coneMargin(const PlanningConstraint& cone, const Matrix3& R) {
  const Vector3 pointing = R * cone.body_axis;
  // atan2 of |a × b| and a·b: accurate at every angle (acos loses it near 0 and π).
  const double angle =
      std::atan2(pointing.cross(cone.world_direction).norm(), pointing.dot(cone.world_direction));
  return cone.kind == ConstraintKind::KeepOut ? angle - cone.half_angle : cone.half_angle - angle;
}

double coneMarginOverStep(const PlanningConstraint& cone, const Matrix3& R_k,
                          const Matrix3& R_next) {
  double worst = std::min(coneMargin(cone, R_k), coneMargin(cone, R_next));
  const Vector3 omega = so3::log(Matrix3(R_k.transpose() * R_next));
  const double phi = omega.norm();
  if (!(phi > 0.0)) return worst;
  // Body-frame pointing exp(θ n^) b = (n·b) n + cos θ u + sin θ w, u = b − (n·b) n, w = n × b;
  // its cosine with d = R_kᵀ s is A + B cos θ + C sin θ, extreme at θ = atan2(C, B) (+ π).
  const Vector3 n = omega / phi;
  const Vector3 u = cone.body_axis - n.dot(cone.body_axis) * n;
  const Vector3 w = n.cross(cone.body_axis);
  const Vector3 d = R_k.transpose() * cone.world_direction;
  const double theta0 = std::atan2(d.dot(w), d.dot(u));
  for (double theta : {theta0, theta0 + M_PI, theta0 - M_PI, theta0 + 2 * M_PI}) {
    if (!(theta > 0.0 && theta < phi)) continue;
    const Matrix3 R = R_k * so3::exp(Vector3(theta * n));
    worst = std::min(worst, coneMargin(cone, R));
  }
  return worst;
}

double requiredConeMargin(const PlanningConstraint& cone, double step_angle) {
  const double offset = step_angle * step_angle / 8.0;  // max |p − chord| over the step
  const double a = cone.half_angle;
  if (cone.kind == ConstraintKind::KeepOut) {
    const double c = std::cos(a) - offset;
    return c < -1.0 ? std::numeric_limits<double>::infinity() : std::acos(c) - a;
  }
  const double c = std::cos(a) + offset;
  return c > 1.0 ? std::numeric_limits<double>::infinity() : a - std::acos(c);
}

std::string describeConstraint(const PlanningConstraint& c) {
  std::ostringstream s;
  s << constraintKindName(c.kind);
  if (c.isCone()) {
    s << " {body_axis " << vectorText(c.body_axis) << ", world_direction "
      << vectorText(c.world_direction) << ", half_angle " << c.half_angle << " rad";
    if (c.margin > 0.0) s << ", margin " << c.margin << " rad";
    s << "}";
  } else {
    s << " " << c.limit << (c.kind == ConstraintKind::MaxTorqueNorm ? " N m" : " rad/s");
  }
  return s.str();
}

}  // namespace attitude_planner
