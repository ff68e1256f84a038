#include "attitude_planner/planning/pointing.hpp"

#include <cmath>
#include <variant>

#include "attitude_planner/errors.hpp"
#include "attitude_planner/lie/so3.hpp"

namespace attitude_planner {

namespace {
/// Below this |b × d| (unit vectors) with b·d < 0 the shortest arc is not defined: b = −d.
constexpr double kAntiparallelSine = 1e-14;
}  // namespace

Matrix3 pointingReference(const Vector3& body_axis, const Vector3& world_direction) {
  const Vector3 b = body_axis.normalized(), d = world_direction.normalized();
  const Vector3 cross = b.cross(d);
  const double sine = cross.norm(), cosine = b.dot(d);
  if (sine > kAntiparallelSine || cosine > 0.0) {
    if (sine == 0.0) return Matrix3::Identity();
    return so3::exp(Vector3(std::atan2(sine, cosine) / sine * cross));
  }
  int smallest = 0;
  for (int i = 1; i < 3; ++i) {
    if (std::abs(b(i)) < std::abs(b(smallest))) smallest = i;
  }
  const Vector3 axis = b.cross(Vector3(Vector3::Unit(smallest))).normalized();
  return so3::exp(Vector3(M_PI * axis));
}

Matrix3 pointingAttitude(const EndCondition& end, double twist) {
  return pointingReference(end.body_axis, end.world_direction) *
         so3::exp(Vector3(twist * end.body_axis.normalized()));
}

double twistOf(const Matrix3& attitude, const EndCondition& end) {
  const Matrix3 M = pointingReference(end.body_axis, end.world_direction).transpose() * attitude;
  // M = I + sin ψ b^ + (1 − cos ψ) b^²: vee(M)·b = sin ψ, tr M = 1 + 2 cos ψ.
  return std::atan2(so3::vee(M).dot(end.body_axis.normalized()), 0.5 * (M.trace() - 1.0));
}

double pointingError(const Matrix3& attitude, const EndCondition& end) {
  const Vector3 aimed = attitude * end.body_axis.normalized();
  const Vector3 d = end.world_direction.normalized();
  return std::atan2(aimed.cross(d).norm(), aimed.dot(d));
}

double nearestTwist(const Matrix3& from, const EndCondition& end) {
  const Matrix3 A = from.transpose() * pointingReference(end.body_axis, end.world_direction);
  const Matrix3 B = so3::hat(Vector3(end.body_axis.normalized()));
  // exp(ψ b^) = I + sin ψ b^ + (1 − cos ψ) b^²
  const double alpha = (A * B).trace(), beta = (A * B * B).trace();
  return std::atan2(alpha, -beta);
}

void summarizePointingEnd(const Matrix3& planned_end, const EndCondition& end,
                          PointingSummary* summary) {
  summary->active = true;
  summary->final_twist = twistOf(planned_end, end);
  summary->error = pointingError(planned_end, end);
}

PointingInfeasibleBasis pointingInfeasibleBasis(const PlanResult& r) {
  if (r.termination != Termination::Infeasible) return PointingInfeasibleBasis::None;
  const bool proven = r.duration_verdict.proven_infeasible ||
                      std::holds_alternative<verdicts::BelowProvenBound>(r.verdict) ||
                      std::holds_alternative<verdicts::InfeasibleAtEveryDuration>(r.verdict);
  if (proven) return PointingInfeasibleBasis::Proven;
  if (std::holds_alternative<verdicts::LocallyInfeasible>(r.verdict) ||
      std::holds_alternative<verdicts::MinimumTimeFoundNone>(r.verdict)) {
    return PointingInfeasibleBasis::MinimumTimeOverTwist;
  }
  return PointingInfeasibleBasis::LocalToStarts;
}

PlanningProblem endingAt(const PlanningProblem& problem, const Matrix3& final_attitude) {
  PlanningProblem at = problem;
  if (problem.end_condition.pointing()) at.final_attitude = final_attitude;
  return at;
}

void requirePointingVector(const Vector3& v, const std::string& field) {
  if (!v.allFinite() || v.norm() == 0.0 || !std::isfinite(v.norm())) {
    throw InvalidInput(field, "must be a finite nonzero vector, got [" + exactNumber(v(0)) + ", " +
                                  exactNumber(v(1)) + ", " + exactNumber(v(2)) + "]");
  }
}

}  // namespace attitude_planner
