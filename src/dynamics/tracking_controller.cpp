#include "attitude_planner/dynamics/tracking_controller.hpp"

#include <cmath>

#include "attitude_planner/errors.hpp"

namespace attitude_planner {

TrackingGains trackingGains(const Matrix3& inertia, double natural_frequency, double damping) {
  if (!std::isfinite(natural_frequency) || !(natural_frequency > 0.0)) {
    throw InvalidInput("natural_frequency: must be a finite number > 0 rad/s, got " +
                       exactNumber(natural_frequency));
  }
  if (!std::isfinite(damping) || !(damping > 0.0)) {
    throw InvalidInput("damping: must be a finite number > 0, got " + exactNumber(damping));
  }
  TrackingGains gains;
  gains.attitude = natural_frequency * natural_frequency * inertia;
  gains.rate = 2.0 * damping * natural_frequency * inertia;
  return gains;
}

TrackingErrors trackingErrors(const Matrix3& attitude, const Vector3& angular_velocity,
                              const AttitudeReference& reference) {
  const Matrix3 E = reference.attitude.transpose() * attitude;  // R_dᵀ R
  TrackingErrors e;
  e.attitude = 0.5 * so3::vee(E - E.transpose());
  // Ω_d carried into the current body frame: Rᵀ R_d Ω_d = Eᵀ Ω_d.
  e.rate = angular_velocity - E.transpose() * reference.angular_velocity;
  e.angle = so3::log(E).norm();
  return e;
}

Vector3 feedForwardTorque(const Matrix3& inertia, const AttitudeReference& reference) {
  const Vector3& w = reference.angular_velocity;
  return inertia * reference.angular_acceleration + w.cross(inertia * w);
}

Vector3 trackingTorque(const Matrix3& inertia, const TrackingGains& gains, const Matrix3& attitude,
                       const Vector3& angular_velocity, const AttitudeReference& reference) {
  const Matrix3 Et = attitude.transpose() * reference.attitude;  // Rᵀ R_d
  const Vector3 omega_r = Et * reference.angular_velocity;       // Rᵀ R_d Ω_d
  const Vector3 alpha_r = Et * reference.angular_acceleration;   // Rᵀ R_d Ω̇_d
  const Vector3 e_R = 0.5 * so3::vee(Et.transpose() - Et);       // ½ (R_dᵀR − RᵀR_d)^∨
  const Vector3 e_W = angular_velocity - omega_r;
  const Vector3& w = angular_velocity;
  return -gains.attitude * e_R - gains.rate * e_W + w.cross(inertia * w) -
         inertia * (w.cross(omega_r) - alpha_r);
}

}  // namespace attitude_planner
