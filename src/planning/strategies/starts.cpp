#include "planning/strategies/starts.hpp"

#include <algorithm>
#include <cmath>

#include "attitude_planner/dynamics/simulation.hpp"
#include "attitude_planner/errors.hpp"

namespace attitude_planner {

namespace {

/// Lifts within this many whole turns beyond the coasting displacement's are considered.
constexpr int kExtraLiftTurns = 2;

}  // namespace

std::vector<Lift> nearestLifts(const PlanningProblem& problem, const ReducedProblem& reduced) {
  const Vector3 principal = reduced.principalSpan();
  const double angle = principal.norm();
  const Vector3 u = angle > 0 ? Vector3(principal / angle) : Vector3(Vector3::UnitX());
  const Vector3 coasting =
      0.5 * problem.duration *
      (problem.initial_velocity + so3::exp(principal) * problem.final_velocity);
  const int reach = kExtraLiftTurns + static_cast<int>(coasting.norm() / (2 * M_PI));
  std::vector<std::pair<double, Vector3>> lifts;
  for (int k = -reach; k <= reach; ++k) {
    const Vector3 lift = (angle + 2 * M_PI * k) * u;
    lifts.emplace_back((lift - coasting).norm(), lift);
  }
  std::stable_sort(lifts.begin(), lifts.end(),
                   [](const auto& a, const auto& b) { return a.first < b.first; });
  std::vector<Lift> out;
  for (int i = 0; i < 2; ++i) {
    Vector3 lift = lifts[i].second;
    const double turned = lift.norm();
    const Vector3 axis = turned > 0 ? Vector3(lift / turned) : u;
    lift += 2 * M_PI * problem.extra_revolutions * axis;
    out.push_back({lift, HomotopyClass{i == 1, problem.extra_revolutions}, lifts[i].first});
  }
  return out;
}

Lift startOnHermiteCurve(const PlanningProblem& problem, ReducedProblem* reduced) {
  const std::vector<Lift> lifts = nearestLifts(problem, *reduced);
  const Lift& lift = lifts[problem.direction == RotationDirection::LongWay ? 1 : 0];
  // Hermite slopes: body rotation per unit s, dR/ds = R Ω dt/ds with dt/ds = (N − 2) h.
  const double T_inner = (problem.steps - 2) * problem.duration / problem.steps;
  reduced->initializeHermite(lift.rotation, T_inner * problem.initial_velocity,
                             T_inner * (so3::exp(lift.rotation) * problem.final_velocity));
  return lift;
}

ExtremalSummary extremalOf(const Lift& lift) {
  ExtremalSummary e;
  e.known = true;
  e.homotopy = lift.homotopy;
  e.angle = lift.rotation.norm();
  if (e.angle > 0) e.axis = lift.rotation / e.angle;
  return e;
}

bool hasSpinningEnds(const PlanningProblem& problem) {
  return !problem.initial_velocity.isZero(0.0) || !problem.final_velocity.isZero(0.0);
}

std::optional<Maneuver> coastingStart(const PlanningProblem& problem) {
  const int N = problem.steps;
  try {
    const DiscreteScheme scheme(problem.scheme, problem.inertia, problem.duration / N);
    SimulationInput input;
    input.torque.assign(N + 1, Vector3::Zero());
    input.initial_attitude = problem.initial_attitude;
    input.initial_velocity = problem.initial_velocity;
    const Maneuver forward = simulate(scheme, input);
    // Backward from (R_N, Ω_{N−1}): the forward motion from (R_N, −Ω_{N−1}), reversed.
    input.initial_attitude = problem.final_attitude;
    input.initial_velocity = -problem.final_velocity;
    const Maneuver backward = simulate(scheme, input);
    ReducedProblem::StepVectors blend(N);
    for (int j = 0; j < N; ++j) {
      const double u = (j + 0.5) / N, w = u * u * (3 - 2 * u);
      const Vector3 ahead =
          so3::log(Matrix3(forward.attitude[j].transpose() * forward.attitude[j + 1]));
      const Vector3 behind =
          so3::log(Matrix3(backward.attitude[N - j].transpose() * backward.attitude[N - j - 1]));
      blend[j] = (1 - w) * ahead + w * behind;
    }
    ReducedProblem reduced(problem);
    reduced.initializeFromSteps(blend);
    Maneuver start;
    start.attitude = reduced.attitudes(reduced.current());
    return start;
  } catch (const StepTooLarge&) {
    return std::nullopt;
  }
}

namespace {

double angleBetween(const Vector3& a, const Vector3& b) {
  return std::atan2(a.cross(b).norm(), a.dot(b));
}

/// The free node (2 … N − 2) where `cone` is violated most deeply, and the first and last
/// violated free nodes; nothing if none is.
struct ConeViolation {
  int deepest = -1, first = -1, last = -1;
};

ConeViolation deepestViolation(const PlanningConstraint& cone, const std::vector<Matrix3>& R) {
  ConeViolation v;
  double worst = 0.0;
  const int N = static_cast<int>(R.size()) - 1;
  for (int k = 2; k <= N - 2; ++k) {
    const double depth =
        cone.half_angle + cone.margin - angleBetween(R[k] * cone.body_axis, cone.world_direction);
    if (depth <= 0.0) continue;
    if (v.first < 0) v.first = k;
    v.last = k;
    if (depth > worst) {
      worst = depth;
      v.deepest = k;
    }
  }
  return v;
}

/// 1 on [first, last], falling smoothly to 0 over as many nodes again on each side, 0 at the
/// boundary nodes (0, 1, N − 1, N).
double sideWeight(int k, const ConeViolation& v, int N) {
  if (k < 2 || k > N - 2) return 0.0;
  const double width = v.last - v.first + 1;
  double x = 1.0;
  if (k < v.first) x = 1.0 - (v.first - k) / width;
  if (k > v.last) x = 1.0 - (k - v.last) / width;
  x = std::clamp(x, 0.0, 1.0);
  return x * x * (3 - 2 * x);
}

}  // namespace

std::vector<Maneuver> coneSideStarts(const PlanningProblem& problem, const Maneuver& plan) {
  const std::vector<Matrix3>& R = plan.attitude;
  const int N = plan.steps();
  const PlanningConstraint* cone = nullptr;
  ConeViolation violation;
  double worst = 0.0;
  for (const PlanningConstraint& c : problem.constraints) {
    if (c.kind != ConstraintKind::KeepOut) continue;
    const ConeViolation v = deepestViolation(c, R);
    if (v.deepest < 0) continue;
    const double depth =
        c.half_angle + c.margin - angleBetween(R[v.deepest] * c.body_axis, c.world_direction);
    if (depth > worst) {
      worst = depth;
      cone = &c;
      violation = v;
    }
  }
  if (!cone) return {};
  const int k = violation.deepest;
  const Vector3& d = cone->world_direction;
  const Vector3 boresight = R[k] * cone->body_axis;
  const Vector3 along = R[k + 1] * cone->body_axis - R[k - 1] * cone->body_axis;
  Vector3 across = d.cross(along);
  if (across.norm() < 1e-12) across = d.unitOrthogonal();
  across.normalize();
  const double offset = kConeSideOffset * (cone->half_angle + cone->margin);
  std::vector<Maneuver> starts;
  for (const double side : {1.0, -1.0}) {
    const Vector3 target = std::cos(offset) * d + std::sin(offset) * side * across;
    const Vector3 turn_axis = boresight.cross(target);
    const double angle = angleBetween(boresight, target);
    const Vector3 turn =
        turn_axis.norm() > 1e-12 ? Vector3(angle * turn_axis.normalized()) : Vector3::Zero();
    Maneuver start;
    start.attitude = R;
    for (int j = 0; j <= N; ++j) {
      start.attitude[j] = so3::exp(Vector3(sideWeight(j, violation, N) * turn)) * R[j];
    }
    starts.push_back(std::move(start));
  }
  return starts;
}

}  // namespace attitude_planner
