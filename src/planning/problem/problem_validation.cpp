#include <Eigen/Eigenvalues>
#include <cmath>
#include <cstdio>
#include <optional>
#include <sstream>
#include <vector>

#include "attitude_planner/errors.hpp"
#include "attitude_planner/planning/pointing.hpp"
#include "attitude_planner/planning/problem.hpp"
#include "attitude_planner/planning/result.hpp"
#include "attitude_planner/planning/warm_start.hpp"
#include "planning/problem/duration_bound.hpp"

namespace attitude_planner {

namespace {

std::string str(const Eigen::MatrixXd& m) {
  std::ostringstream s;
  s << m.format(
      Eigen::IOFormat(Eigen::FullPrecision, Eigen::DontAlignCols, ", ", "; ", "", "", "[", "]"));
  return s.str();
}

void requireFinite(const Eigen::MatrixXd& m, const std::string& field) {
  if (!m.allFinite()) throw InvalidInput(field, "not finite: " + str(m));
}

void requireRotation(const Matrix3& R, const std::string& field) {
  requireFinite(R, field);
  if (so3::orthogonalityError(R) > 1e-9) {
    throw InvalidInput(field, "not a rotation matrix (|R^T R - I| + |det R - 1| = " +
                                  exactNumber(so3::orthogonalityError(R)) + ")");
  }
}

/// The boundary data must meet the node constraints themselves: R_0, R_N every cone, Ω_0 and
/// Ω_{N−1} every rate limit (they are data, no plan can change them). The error's field is the
/// boundary datum; the detail names the constraint by index and kind, a name both the scene and
/// the request spell the same way.
void requireBoundaryWithinConstraints(const PlanningProblem& p) {
  for (std::size_t i = 0; i < p.constraints.size(); ++i) {
    const PlanningConstraint& c = p.constraints[i];
    const std::string which =
        "constraints[" + std::to_string(i) + "] (" + constraintKindName(c.kind) + ")";
    if (c.isCone()) {
      const std::pair<const char*, const Matrix3*> ends[] = {
          {"initial.attitude", &p.initial_attitude}, {"final.attitude", &p.final_attitude}};
      for (const auto& [field, R] : ends) {
        // A pointing end's R_N moves with its free twist: its cone is a row of the solve.
        if (R == &p.final_attitude && p.end_condition.pointing()) continue;
        const double margin = coneMargin(c, *R);
        if (margin < 0.0) {
          throw InvalidInput(
              field, "already violates " + which + ": the angle between R b and s is " +
                         exactNumber(c.kind == ConstraintKind::KeepOut ? c.half_angle + margin
                                                                       : c.half_angle - margin) +
                         " rad, half_angle " + exactNumber(c.half_angle) + " rad");
        }
      }
    } else if (c.kind == ConstraintKind::MaxAngularRate) {
      const std::pair<const char*, const Vector3*> ends[] = {
          {"initial.angular_velocity", &p.initial_velocity},
          {"final.angular_velocity", &p.final_velocity}};
      for (const auto& [field, Omega] : ends) {
        if (Omega->norm() > c.limit) {
          throw InvalidInput(field, "already violates " + which +
                                        ": |Omega| = " + exactNumber(Omega->norm()) + " rad/s > " +
                                        exactNumber(c.limit) + " rad/s");
        }
      }
    }
  }
}

/// Reaction wheels: the array valid, the combinations the wheel model does not plan refused by
/// name (every effect but a world-frame disturbance_torque; that one with minimum time), and the
/// end state's wheel momenta (fixed by the boundary data: q_N = R_Nᵀ(π₀ + T τ_d) − J Ω(T)) within
/// their limits, else no plan exists.
void requireWheelsServed(const PlanningProblem& p) {
  const std::string field = "actuators.reaction_wheels";
  validateReactionWheels(p.reaction_wheels, field);
  const auto refuse = [&](const std::string& what, const std::string& why) {
    throw InvalidInput(field, "not supported with " + what + ": " + why);
  };
  if (p.hasTorqueBounds()) {
    refuse("effects actuator_limits",
           "the wheels' max_torque bounds the actuators (a body-torque box beside it would "
           "bound a torque no actuator makes); give per-wheel max_torque, or max_torque_norm "
           "under constraints for a body-torque bound");
  }
  const bool disturbed = p.effects && !p.effects->empty();
  if (disturbed && !p.effects->constantWorldTorque()) {
    std::string names;
    for (const std::string& name : p.effects->names()) names += (names.empty() ? "" : ", ") + name;
    refuse("effects (" + names + ")",
           "the wheel momenta follow from the total angular momentum, which an external torque "
           "changes by its impulse; only a disturbance_torque in the world frame has an impulse "
           "independent of the path (t tau_d); gravity_gradient and a body-frame disturbance "
           "depend on the path");
  }
  if (disturbed && p.objective == Objective::MinimumTime) {
    refuse("effects and objective minimum_time",
           "the end state's wheel momenta depend on the duration through the disturbance's "
           "impulse; give a duration (minimum effort)");
  }
  if (p.end_condition.pointing()) refuse("final.pointing", "give a final attitude");
  if (p.accuracy.active()) refuse("an accuracy target", "give steps");
  const WheelArray array = wheelArray(p.reaction_wheels);
  const Vector3 total =
      p.initial_attitude * (p.inertia * p.initial_velocity + array.initial_array_momentum) +
      p.duration * p.worldDisturbance();  // π(T) = π₀ + T τ_d
  const Vector3 final_array = p.final_attitude.transpose() * total - p.inertia * p.final_velocity;
  const Eigen::VectorXd final_wheels = array.wheelMomenta(final_array);
  for (int i = 0; i < p.reaction_wheels.count(); ++i) {
    const double limit = p.reaction_wheels.momentumLimit(i);
    if (std::abs(final_wheels(i)) > limit) {
      throw InvalidInput(field + ".max_momentum",
                         "the final state (attitude and angular velocity) leaves wheel " +
                             std::to_string(i + 1) + " with " + exactNumber(final_wheels(i)) +
                             " N m s, beyond its limit " + exactNumber(limit) +
                             " N m s: no plan can end there");
    }
  }
  if (final_array.norm() > p.reaction_wheels.max_momentum_norm) {
    throw InvalidInput(
        field + ".max_momentum_norm",
        "the final state leaves the array with |A h_w| = " + exactNumber(final_array.norm()) +
            " N m s, beyond " + exactNumber(p.reaction_wheels.max_momentum_norm) + " N m s");
  }
}

/// `value` (> 0, finite) within the magnitudes the planner works in, else InvalidInput naming
/// `field`, the value and the cause (the floating-point range, not the physics).
void requireMagnitude(double value, const std::string& field, const std::string& what) {
  if (!(value > 0.0) || !std::isfinite(value)) return;  // their own rules name these
  if (value <= kMagnitudeRange && value >= 1.0 / kMagnitudeRange) return;
  throw InvalidInput(field, what + " = " + exactNumber(value) +
                                " is outside the floating-point range the planner works in ([" +
                                exactNumber(1.0 / kMagnitudeRange) + ", " +
                                exactNumber(kMagnitudeRange) +
                                "] in SI units: the solvers form squares and fourth powers of "
                                "these magnitudes); state the problem in other units");
}

/// Every magnitude the solvers scale by, checked up front (requireMagnitude): the principal
/// moments, T and h, the bounds, and the torque scale J/T² of the duration (minimum time: of
/// the proven least duration, durationLowerBound). Boundary rates are left to the step check,
/// which names them (step too large).
void requireFloatingPointRange(const PlanningProblem& p, const Vector3& moments) {
  requireMagnitude(moments(0), "inertia", "the least principal moment [kg m^2]");
  requireMagnitude(moments(2), "inertia", "the largest principal moment [kg m^2]");
  for (int i = 0; i < 3; ++i) {
    requireMagnitude(p.max_torque(i), "actuator_limits.max_torque", "a bound [N m]");
  }
  for (std::size_t i = 0; i < p.constraints.size(); ++i) {
    const PlanningConstraint& c = p.constraints[i];
    if (c.isCone()) continue;
    requireMagnitude(c.limit,
                     "constraints[" + std::to_string(i) + "]." + constraintKindName(c.kind),
                     "the limit");
  }
  double T = p.duration;
  std::string field = "duration";
  if (p.objective == Objective::MinimumTime && !(T > 0.0)) {
    T = durationLowerBound(p).seconds;
    field = "objective";
    requireMagnitude(T, field, "the least duration any plan needs [s] (proven)");
  }
  if (!(T > 0.0)) return;
  requireMagnitude(T, field, "T [s]");
  if (!p.accuracy.active()) requireMagnitude(T / p.steps, field, "the step h = T/N [s]");
  requireMagnitude(moments(2) / (T * T), field, "the torque scale J/T^2 [N m]");
}

/// A pointing end condition: its vectors, and the requests the pointing solver serves (minimum
/// effort and minimum time with every stage constraint, no effects, a direct
/// scheme, the class left to the planner). The others are refused by name.
void requirePointingServed(const PlanningProblem& p) {
  requirePointingVector(p.end_condition.body_axis, "final.pointing.body_axis");
  requirePointingVector(p.end_condition.world_direction, "final.pointing.world_direction");
  const auto refuse = [](const std::string& what) {
    throw InvalidInput("final.pointing",
                       "not supported with " + what + " yet; give a final attitude instead");
  };
  if (p.scheme == SchemeKind::FourthOrder) refuse("scheme fourth_order");
  if (p.effects && !p.effects->empty()) refuse("effects");
  if (p.accuracy.active()) refuse("an accuracy target");
  if (p.direction != RotationDirection::Shortest || p.extra_revolutions != 0) {
    throw InvalidInput("final.pointing",
                       "direction and extra_revolutions do not apply (a whole turn of the free "
                       "twist joins the ways round: the planner starts from both), got direction " +
                           directionName(p.direction) + ", extra_revolutions " +
                           std::to_string(p.extra_revolutions));
  }
}

}  // namespace

void validateProblem(const PlanningProblem& p) {
  requireFinite(p.inertia, "inertia");
  if ((p.inertia - p.inertia.transpose()).cwiseAbs().maxCoeff() >
      1e-12 * p.inertia.cwiseAbs().maxCoeff()) {
    throw InvalidInput("inertia: not symmetric: " + str(p.inertia));
  }
  const Eigen::SelfAdjointEigenSolver<Matrix3> eig(p.inertia);
  const Vector3 moments = eig.eigenvalues();  // ascending
  if (!(moments(0) > 0.0)) {
    throw InvalidInput("inertia: not positive definite: " + str(p.inertia) +
                       " (principal moments " + str(moments.transpose()) + ")");
  }
  // The discrete dynamics are well posed for every SPD J, and the seed's own example inertia
  // (moments 3.15, 12.54, 32.19) violates J1 + J2 >= J3: the check is skipped only on request.
  if (!p.allow_nonphysical_inertia) requirePhysicalInertia(p.inertia);
  if (moments(2) / moments(0) > 1e12) {
    throw InvalidInput("inertia: condition number " + exactNumber(moments(2) / moments(0)) +
                       " of " + str(p.inertia) + " > 1e12");
  }
  // minimum_time: the duration is optional (0 = not given; else an upper bound and first guess).
  if (p.objective != Objective::MinimumTime || p.duration != 0.0) {
    requireDuration(p.duration, "duration");
  }
  if (p.objective == Objective::MinimumEffort && p.time_margin != 0.0) {
    throw InvalidInput("time_margin: only with objective minimum_time, got " +
                       exactNumber(p.time_margin));
  }
  if (!std::isfinite(p.time_margin) || p.time_margin < 0.0) {
    throw InvalidInput("time_margin: must be a finite number >= 0, got " +
                       exactNumber(p.time_margin));
  }
  // With an accuracy target the planner chooses N: `steps` is not used.
  if (!p.accuracy.active() && p.steps < kMinSteps) {
    throw InvalidInput("steps: must be >= " + std::to_string(kMinSteps) + ", got " +
                       std::to_string(p.steps));
  }
  if (!p.accuracy.active() && p.steps > kMaxSteps) {
    throw InvalidInput("steps: must be <= " + std::to_string(kMaxSteps) + ", got " +
                       std::to_string(p.steps));
  }
  if (!p.accuracy.active() && p.scheme == SchemeKind::FourthOrder && p.steps > kMaxSteps / 2) {
    throw InvalidInput("steps: must be <= " + std::to_string(kMaxSteps / 2) +
                       " with scheme fourth_order (it solves second_order at 2N), got " +
                       std::to_string(p.steps));
  }
  for (int i = 0; i < 3; ++i) {
    if (std::isnan(p.max_torque(i)) || !(p.max_torque(i) > 0.0)) {
      throw InvalidInput("actuator_limits.max_torque: each bound must be > 0 N m, got " +
                         str(p.max_torque.transpose()));
    }
  }
  if (p.max_torque.array().isFinite().any() && !p.max_torque.allFinite()) {
    throw InvalidInput("actuator_limits.max_torque: give all three bounds, got " +
                       str(p.max_torque.transpose()));
  }
  if (p.accuracy.choose_scheme && !p.accuracy.active()) {
    throw InvalidInput(std::string("scheme: '") + kAutoSchemeName +
                       "' needs an accuracy target (accuracy_measure, --target-miss or "
                       "--target-cost-error): the planner chooses the scheme only for a "
                       "requested accuracy");
  }
  validateConstraints(p.constraints, "constraints");
  if (p.duration > 0.0 || p.objective == Objective::MinimumTime) {
    requireFloatingPointRange(p, moments);
  }
  if (p.accuracy.active()) {
    if (!std::isfinite(p.accuracy.value) || !(p.accuracy.value > 0.0)) {
      throw InvalidInput("accuracy_target: must be a finite number > 0 (" +
                         accuracyMeasureName(p.accuracy.measure) + "), got " +
                         exactNumber(p.accuracy.value));
    }
    if (p.effects && !p.effects->empty()) {
      throw InvalidInput(
          "accuracy_target: not supported with effects (the replay that measures the terminal "
          "miss is of the bare rigid body); actuator_limits and constraints are supported");
    }
    if (p.accuracy.max_steps < 16 || p.accuracy.max_steps > kMaxSteps) {
      throw InvalidInput("accuracy.max_steps: must be in [16, " + std::to_string(kMaxSteps) +
                         "], got " + std::to_string(p.accuracy.max_steps));
    }
  }
  requireExtraRevolutions(p.extra_revolutions, "extra_revolutions");
  if (!p.accuracy.active()) requireRepresentableTurns(p.extra_revolutions, p.steps);
  requireRotation(p.initial_attitude, "initial.attitude");
  requireRotation(p.final_attitude, "final.attitude");
  requireFinite(p.initial_velocity, "initial.angular_velocity");
  requireFinite(p.final_velocity, "final.angular_velocity");
  if (p.end_condition.pointing()) requirePointingServed(p);
  requireBoundaryWithinConstraints(p);
  if (p.reaction_wheels.present()) requireWheelsServed(p);
}

void applySchemeName(const std::string& text, const std::string& field, PlanningProblem* problem) {
  problem->accuracy.choose_scheme = text == kAutoSchemeName;
  if (problem->accuracy.choose_scheme) return;
  if (const std::optional<SchemeKind> scheme = findByName(kSchemeNames, text)) {
    problem->scheme = *scheme;
    return;
  }
  std::vector<std::string> accepted = namesOf(kSchemeNames);
  accepted.push_back(kAutoSchemeName);
  throw InvalidInput(field + ": unknown value '" + text + "' (expected " + oneOf(accepted) + ")");
}

void requireExtraRevolutions(int extra_revolutions, const std::string& field) {
  if (extra_revolutions < 0) {
    throw InvalidInput(field + ": must be >= 0, got " + std::to_string(extra_revolutions) +
                       " (whole extra turns in the sense of the chosen way; use direction "
                       "long_way to turn the other way)");
  }
}

void requireRepresentableTurns(int extra_revolutions, int steps) {
  // The class with K extra turns has a lift of at least 2πK from R_1 to R_{N−1}; a plan in it
  // turns at least that far (classInconsistency) in N − 2 steps of less than π each.
  if (extra_revolutions == 0 || 2 * static_cast<long>(extra_revolutions) < steps - 2) return;
  throw StepTooLarge("extra_revolutions",
                     "step too large, increase steps: " + std::to_string(extra_revolutions) +
                         " extra turns need a path of at least " +
                         exactNumber(2 * M_PI * extra_revolutions) + " rad, which the " +
                         std::to_string(steps - 2) +
                         " inner steps (each less than pi rad) cannot turn: needs steps > " +
                         std::to_string(2 * static_cast<long>(extra_revolutions) + 2) + ", got " +
                         std::to_string(steps));
}

void validateOptions(const SolverOptions& o) {
  if (!std::isfinite(o.tolerance) || !(o.tolerance > 0.0)) {
    throw InvalidInput("tolerance: must be a finite number > 0, got " + exactNumber(o.tolerance));
  }
  if (o.max_iterations < 0) {
    throw InvalidInput("max_iterations: must be >= 0, got " + std::to_string(o.max_iterations));
  }
  if (!std::isfinite(o.time_budget_s) || o.time_budget_s < 0.0) {
    throw InvalidInput("time_budget: must be a finite number >= 0 s (0 = none), got " +
                       exactNumber(o.time_budget_s));
  }
  if (o.threads < 0) {
    throw InvalidInput("threads: must be >= 0 (0 = the machine's cores), got " +
                       std::to_string(o.threads));
  }
  if (o.warm_start) validateInitialGuess(*o.warm_start, "warm_start");
  validateAdvancedParameters(o.advanced);
}

void requirePhysicalInertia(const Matrix3& inertia) {
  const Eigen::SelfAdjointEigenSolver<Matrix3> eig(inertia);
  const Vector3 moments = eig.eigenvalues();  // ascending
  if (moments(0) + moments(1) < moments(2) * (1.0 - 1e-12)) {
    throw InvalidInput("inertia: " + str(inertia) + " has principal moments " +
                       str(moments.transpose()) +
                       " that violate the triangle inequality J1 + J2 >= J3 (no rigid body has "
                       "them; set allow_nonphysical_inertia: true to plan anyway)");
  }
}

}  // namespace attitude_planner
