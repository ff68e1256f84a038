#include "attitude_planner/planning/constraints.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include "attitude_planner/dynamics/discrete_scheme.hpp"
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

ConstraintCheck checkConstraints(const PlanningProblem& problem, const Maneuver& maneuver) {
  ConstraintCheck out;
  const int N = maneuver.steps();
  const double h = maneuver.time_step;
  int worst_k = -1;
  // One node constraint: `slack` to the stated limit (≥ 0: holds; violations are measured
  // against it), `node_slack` to the bound the planner imposes (activity), against `scale`.
  const auto visit = [&](double slack, double node_slack, double scale, const std::string& what,
                         int k) {
    if (node_slack <= kActiveConstraintTolerance * scale) ++out.active;
    out.max_node_bound_violation = std::max(out.max_node_bound_violation, -node_slack);
    out.max_violation_between_nodes = std::max(out.max_violation_between_nodes, -slack);
    // The solver's verdict (planInconsistency) is on the bound it was asked to meet.
    out.max_relative_violation = std::max(out.max_relative_violation, -node_slack / scale);
    if (-slack > out.max_violation) {
      out.max_violation = -slack;
      out.worst = what;
      worst_k = k;  // worst_where is written once, at the end
    }
  };
  // Between nodes: torques are held (or, with end torques, interpolated linearly: the bounds are
  // convex), so only rates and cones need more.
  const auto between = [&](double slack) {
    out.max_violation_between_nodes = std::max(out.max_violation_between_nodes, -slack);
  };
  // The torques τ_k and rates Ω_k of the plan: k = 1..N−1 and steps 0..N−1 for paper and
  // variational (τ_0 = τ_N = 0; Ω_N repeats Ω_{N−1}); every node k = 0..N with end torques.
  const bool end_torques = schemeHasEndTorques(problem.scheme);
  const int first_torque = end_torques ? 0 : 1, last_torque = end_torques ? N : N - 1;
  const int last_rate = end_torques ? N : N - 1;
  if (problem.hasTorqueBounds()) {
    out.names.push_back("actuator_limits");
    static const char* axis[] = {"x", "y", "z"};
    std::string what[3];  // formed once: a stream per node and axis cost as much as the solve's
                          // replay (measured, N = 128)
    for (int i = 0; i < 3; ++i) {
      std::ostringstream s;
      s << "|tau_" << axis[i] << "| <= " << problem.max_torque(i) << " N m";
      what[i] = s.str();
    }
    for (int k = first_torque; k <= last_torque; ++k) {
      for (int i = 0; i < 3; ++i) {
        const double a = problem.max_torque(i);
        const double slack = a - std::abs(maneuver.torque[k](i));
        visit(slack, slack, a, what[i], k);
      }
    }
  }
  for (const PlanningConstraint& c : problem.constraints) {
    out.names.push_back(constraintKindName(c.kind));
    const std::string what = describeConstraint(c);
    switch (c.kind) {
      case ConstraintKind::MaxTorqueNorm:
        for (int k = first_torque; k <= last_torque; ++k) {
          const double slack = c.limit - maneuver.torque[k].norm();
          visit(slack, slack, c.limit, what, k);
        }
        break;
      case ConstraintKind::MaxAngularRate:
        for (int k = 0; k <= last_rate; ++k) {
          const double slack = c.limit - maneuver.angular_velocity[k].norm();
          visit(slack, slack, c.limit, what, k);
          // The motion between nodes turns at log(F_k)/h (a scheme's reported Ω_k may differ
          // from it by O(h²)).
          if (k < N) {
            const Matrix3 F = maneuver.attitude[k].transpose() * maneuver.attitude[k + 1];
            between(c.limit - so3::log(F).norm() / h);
          }
        }
        break;
      case ConstraintKind::KeepOut:
      case ConstraintKind::KeepIn:
        for (int k = 0; k <= N; ++k) {
          const double slack = coneMargin(c, maneuver.attitude[k]);
          visit(slack, slack - c.margin, 1.0, what, k);
          if (k < N) between(coneMarginOverStep(c, maneuver.attitude[k], maneuver.attitude[k + 1]));
        }
        break;
    }
  }
  if (worst_k >= 0) {
    std::ostringstream w;
    w << "by " << out.max_violation << " at k = " << worst_k << " (t = " << worst_k * h << " s)";
    out.worst_where = w.str();
  }
  return out;
}

}  // namespace attitude_planner
