// Reaction wheels (reaction_wheels.hpp): validation, the array's matrices, wheel states of a plan.
#include "attitude_planner/planning/reaction_wheels.hpp"

#include <Eigen/SVD>
#include <cmath>
#include <sstream>
#include <string>

#include "attitude_planner/errors.hpp"

namespace attitude_planner {

namespace {

/// Smallest singular value of the normalized A below which the axes do not span R³.
constexpr double kSpanTolerance = 1e-6;
/// Relative slack of the initial momenta against their limits (a value written at the limit).
constexpr double kLimitSlack = 1e-12;

std::string listed(const std::vector<double>& values) {
  std::ostringstream s;
  s << "[";
  for (std::size_t i = 0; i < values.size(); ++i) s << (i ? ", " : "") << exactNumber(values[i]);
  s << "]";
  return s.str();
}

/// A per-wheel list (limits, spin inertias): 1 or n entries, each finite and > 0; `noun` says
/// what an entry is in the message ("limit", "value").
void requirePositiveValues(const std::vector<double>& limits, int n, const std::string& field,
                           const char* unit, const char* noun = "limit") {
  if (limits.size() != 1 && static_cast<int>(limits.size()) != n) {
    throw InvalidInput(field, "give one value or one per wheel (" + std::to_string(n) + "), got " +
                                  std::to_string(limits.size()) + " values " + listed(limits));
  }
  for (std::size_t i = 0; i < limits.size(); ++i) {
    if (!std::isfinite(limits[i]) || !(limits[i] > 0.0)) {
      throw InvalidInput(field, "each " + std::string(noun) + " must be a finite number > 0 " +
                                    std::string(unit) + ", got " + exactNumber(limits[i]) +
                                    " at index " + std::to_string(i));
    }
  }
}

void requireSpanningAxes(const ReactionWheels& wheels, const std::string& field) {
  const int n = wheels.count();
  if (n < 3) {
    throw InvalidInput(field + ".spin_axes",
                       "need at least 3 wheels, got " + std::to_string(n) + " spin axes");
  }
  for (int i = 0; i < n; ++i) {
    if (!wheels.spin_axes[i].allFinite() || !(wheels.spin_axes[i].norm() > 0.0)) {
      std::ostringstream v;
      v << "[" << wheels.spin_axes[i].transpose() << "]";
      throw InvalidInput(field + ".spin_axes", "axis " + std::to_string(i) +
                                                   " must be finite and nonzero, got " + v.str());
    }
  }
  const Eigen::JacobiSVD<Eigen::MatrixXd> svd(wheelArray(wheels).axes);
  const double smallest = svd.singularValues().minCoeff();
  if (!(smallest > kSpanTolerance)) {
    throw InvalidInput(field + ".spin_axes",
                       "the axes do not span R^3 (smallest singular value of the unit axes " +
                           exactNumber(smallest) + "): some body torque no wheel can make");
  }
}

}  // namespace

WheelArray wheelArray(const ReactionWheels& wheels) {
  WheelArray out;
  const int n = wheels.count();
  out.axes.resize(3, n);
  Eigen::VectorXd initial(n);
  for (int i = 0; i < n; ++i) {
    out.axes.col(i) = wheels.spin_axes[i].normalized();
    initial(i) = wheels.initialMomentum(i);
  }
  const Matrix3 gram = out.axes * out.axes.transpose();
  out.pseudo_inverse = out.axes.transpose() * gram.inverse();
  out.initial_array_momentum = out.axes * initial;
  out.null_momentum = initial - out.pseudo_inverse * out.initial_array_momentum;
  return out;
}

void validateReactionWheels(const ReactionWheels& wheels, const std::string& field) {
  requireSpanningAxes(wheels, field);
  const int n = wheels.count();
  requirePositiveValues(wheels.max_torque, n, field + ".max_torque", "N m");
  requirePositiveValues(wheels.max_momentum, n, field + ".max_momentum", "N m s");
  if (!wheels.initial_momentum.empty() && static_cast<int>(wheels.initial_momentum.size()) != n) {
    throw InvalidInput(field + ".initial_momentum", "give one value per wheel (" +
                                                        std::to_string(n) + "), got " +
                                                        listed(wheels.initial_momentum));
  }
  for (int i = 0; i < n; ++i) {
    const double h = wheels.initialMomentum(i), limit = wheels.momentumLimit(i);
    if (!std::isfinite(h) || std::abs(h) > limit * (1.0 + kLimitSlack)) {
      throw InvalidInput(field + ".initial_momentum",
                         "wheel " + std::to_string(i + 1) + " starts at " + exactNumber(h) +
                             " N m s, beyond its max_momentum " + exactNumber(limit) + " N m s");
    }
  }
  const double envelope = wheels.max_momentum_norm;
  if (std::isnan(envelope) || !(envelope > 0.0)) {
    throw InvalidInput(field + ".max_momentum_norm",
                       "must be a number > 0 N m s, got " + exactNumber(envelope));
  }
  const double start = wheelArray(wheels).initial_array_momentum.norm();
  if (start > envelope * (1.0 + kLimitSlack)) {
    throw InvalidInput(field + ".max_momentum_norm",
                       "the initial momenta give |A h_w| = " + exactNumber(start) +
                           " N m s, beyond the envelope " + exactNumber(envelope) + " N m s");
  }
  if (wheels.hasSpinInertia()) {
    requirePositiveValues(wheels.spin_inertia, n, field + ".spin_inertia", "kg m^2", "value");
  }
}

namespace {

/// a_i·Ω of every wheel, after checking the spin inertias a rate ↔ momentum conversion needs
/// (`needed_for` says which): h_w,i = J_s,i (a_i·Ω + w_i), the wheel's axial rate being the
/// body's about a_i plus its own w_i.
Eigen::VectorXd axialBodyRates(const ReactionWheels& wheels, const Vector3& body_rate,
                               const std::string& needed_for) {
  if (!wheels.hasSpinInertia()) {
    throw InvalidInput("actuators.reaction_wheels.spin_inertia", "not given: " + needed_for);
  }
  Eigen::VectorXd axial(wheels.count());
  for (int i = 0; i < wheels.count(); ++i) {
    axial(i) = wheels.spin_axes[i].normalized().dot(body_rate);
  }
  return axial;
}

}  // namespace

Eigen::VectorXd wheelSpinRates(const ReactionWheels& wheels, const Eigen::VectorXd& momenta,
                               const Vector3& body_rate) {
  const Eigen::VectorXd axial =
      axialBodyRates(wheels, body_rate, "a wheel's spin rate needs its spin inertia");
  Eigen::VectorXd rates(wheels.count());
  for (int i = 0; i < wheels.count(); ++i) rates(i) = momenta(i) / wheels.spinInertia(i) - axial(i);
  return rates;
}

Eigen::VectorXd wheelMomentaFromSpinRates(const ReactionWheels& wheels,
                                          const Eigen::VectorXd& rates, const Vector3& body_rate) {
  const Eigen::VectorXd axial = axialBodyRates(
      wheels, body_rate, "a wheel's momentum from its spin rate needs its spin inertia");
  Eigen::VectorXd momenta(wheels.count());
  for (int i = 0; i < wheels.count(); ++i)
    momenta(i) = wheels.spinInertia(i) * (axial(i) + rates(i));
  return momenta;
}

Vector3 planNodeMomentum(SchemeKind scheme, const Matrix3& inertia, const Maneuver& plan, int k) {
  const int N = plan.steps();
  if (k == 0 || k == N || schemeHasEndTorques(scheme)) return inertia * plan.angular_velocity[k];
  const DiscreteScheme discrete(scheme, inertia, plan.time_step);
  const auto stepMomentum = [&](int j) {
    return discrete.momentumOfStep(so3::log(plan.attitude[j].transpose() * plan.attitude[j + 1]));
  };
  const Matrix3 previous = plan.attitude[k - 1].transpose() * plan.attitude[k];  // F_{k−1}
  return 0.5 * (stepMomentum(k) + previous.transpose() * stepMomentum(k - 1));
}

Vector3 totalMomentum(const Matrix3& inertia, const WheelArray& array, const Maneuver& plan) {
  return plan.attitude[0] * (inertia * plan.angular_velocity[0] + array.initial_array_momentum);
}

namespace {
/// R_kᵀπ_k, π_k = π₀ + k h τ_d.
Vector3 bodyTotalMomentum(const Matrix3& inertia, const WheelArray& array, const Maneuver& plan,
                          int k, const Vector3& world_disturbance) {
  const Vector3 total =
      totalMomentum(inertia, array, plan) + (k * plan.time_step) * world_disturbance;
  return plan.attitude[k].transpose() * total;
}
}  // namespace

Vector3 planArrayMomentum(SchemeKind scheme, const Matrix3& inertia, const WheelArray& array,
                          const Maneuver& plan, int k, const Vector3& world_disturbance) {
  return bodyTotalMomentum(inertia, array, plan, k, world_disturbance) -
         planNodeMomentum(scheme, inertia, plan, k);
}

Vector3 planArrayTorque(SchemeKind scheme, const Matrix3& inertia, const WheelArray& array,
                        const Maneuver& plan, int k, const Vector3& world_disturbance) {
  const Vector3 Pi = planNodeMomentum(scheme, inertia, plan, k);
  const Vector3 q = bodyTotalMomentum(inertia, array, plan, k, world_disturbance) - Pi;
  return -(plan.torque[k] + (inertia.inverse() * Pi).cross(q));
}

WheelStates wheelStates(SchemeKind scheme, const Matrix3& inertia, const ReactionWheels& wheels,
                        const Maneuver& plan, const Vector3& world_disturbance) {
  WheelStates out;
  const WheelArray array = wheelArray(wheels);
  for (int k = 0; k <= plan.steps(); ++k) {
    out.momentum.push_back(
        array.wheelMomenta(planArrayMomentum(scheme, inertia, array, plan, k, world_disturbance)));
    out.torque.push_back(array.pseudo_inverse *
                         planArrayTorque(scheme, inertia, array, plan, k, world_disturbance));
  }
  return out;
}

}  // namespace attitude_planner
