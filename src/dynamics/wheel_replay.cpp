// Body + reaction wheels from the wheel torques (wheel_replay.hpp).
#include "attitude_planner/dynamics/wheel_replay.hpp"

#include <Eigen/Geometry>

namespace attitude_planner {

namespace {

/// The coupled state: attitude as a unit quaternion, body rate, wheel momenta.
struct State {
  Eigen::Quaterniond attitude;
  Vector3 rate;
  Eigen::VectorXd momentum;
};

/// d/dt of the state: q̇ = ½ q ⊗ (0, Ω), J Ω̇ = −Ω × (J Ω + A h_w) − A u + τ_e(R, t), ḣ_w = u.
struct Derivative {
  Eigen::Vector4d attitude;  ///< (w, x, y, z)
  Vector3 rate;
  Eigen::VectorXd momentum;
};

Derivative derivative(const State& s, const Eigen::VectorXd& u, const Matrix3& J,
                      const Matrix3& J_inverse, const Eigen::Matrix<double, 3, Eigen::Dynamic>& A,
                      const ExternalTorque& external, double t) {
  Derivative d;
  const Eigen::Quaterniond omega(0.0, s.rate.x(), s.rate.y(), s.rate.z());
  const Eigen::Quaterniond q_dot = s.attitude * omega;
  d.attitude = 0.5 * Eigen::Vector4d(q_dot.w(), q_dot.x(), q_dot.y(), q_dot.z());
  const Vector3 total = J * s.rate + A * s.momentum;
  Vector3 rate_change = -s.rate.cross(total) - A * u;
  if (external) rate_change += external(s.attitude.normalized().toRotationMatrix(), t);
  d.rate = J_inverse * rate_change;
  d.momentum = u;
  return d;
}

State advanced(const State& s, const Derivative& d, double dt) {
  State out;
  const Eigen::Vector4d q =
      Eigen::Vector4d(s.attitude.w(), s.attitude.x(), s.attitude.y(), s.attitude.z()) +
      dt * d.attitude;
  out.attitude = Eigen::Quaterniond(q(0), q(1), q(2), q(3));
  out.rate = s.rate + dt * d.rate;
  out.momentum = s.momentum + dt * d.momentum;
  return out;
}

}  // namespace

WheelReplay replayWithWheels(const Matrix3& inertia,
                             const Eigen::Matrix<double, 3, Eigen::Dynamic>& axes,
                             const Matrix3& initial_attitude, const Vector3& initial_velocity,
                             const Eigen::VectorXd& initial_momentum, double time_step,
                             const std::vector<Eigen::VectorXd>& torque,
                             const Vector3& world_disturbance, int substeps) {
  ExternalTorque external;
  if (!world_disturbance.isZero(0.0)) {
    external = [world_disturbance](const Matrix3& R, double) -> Vector3 {
      return R.transpose() * world_disturbance;
    };
  }
  return replayWithWheelsUnder(inertia, axes, initial_attitude, initial_velocity, initial_momentum,
                               time_step, torque, external, substeps);
}

WheelReplay replayWithWheelsUnder(const Matrix3& inertia,
                                  const Eigen::Matrix<double, 3, Eigen::Dynamic>& axes,
                                  const Matrix3& initial_attitude, const Vector3& initial_velocity,
                                  const Eigen::VectorXd& initial_momentum, double time_step,
                                  const std::vector<Eigen::VectorXd>& torque,
                                  const ExternalTorque& external, int substeps) {
  const Matrix3 J_inverse = inertia.inverse();
  State s{Eigen::Quaterniond(initial_attitude), initial_velocity, initial_momentum};
  WheelReplay out;
  out.peak_momentum = initial_momentum.cwiseAbs();
  const auto record = [&] {
    out.attitude.push_back(s.attitude.toRotationMatrix());
    out.angular_velocity.push_back(s.rate);
    out.momentum.push_back(s.momentum);
  };
  record();
  const double dt = time_step / substeps;
  for (std::size_t k = 0; k + 1 < torque.size(); ++k) {
    // u(t) linear between u_k and u_{k+1}
    const auto u = [&](double fraction) {
      return Eigen::VectorXd((1.0 - fraction) * torque[k] + fraction * torque[k + 1]);
    };
    const auto rate = [&](const State& at, double fraction) {
      return derivative(at, u(fraction), inertia, J_inverse, axes, external,
                        (static_cast<double>(k) + fraction) * time_step);
    };
    for (int j = 0; j < substeps; ++j) {
      const double f0 = static_cast<double>(j) / substeps, f1 = (j + 1.0) / substeps;
      const double fm = 0.5 * (f0 + f1);
      const Derivative k1 = rate(s, f0);
      const Derivative k2 = rate(advanced(s, k1, 0.5 * dt), fm);
      const Derivative k3 = rate(advanced(s, k2, 0.5 * dt), fm);
      const Derivative k4 = rate(advanced(s, k3, dt), f1);
      Derivative sum;
      sum.attitude = (k1.attitude + 2 * k2.attitude + 2 * k3.attitude + k4.attitude) / 6.0;
      sum.rate = (k1.rate + 2 * k2.rate + 2 * k3.rate + k4.rate) / 6.0;
      sum.momentum = (k1.momentum + 2 * k2.momentum + 2 * k3.momentum + k4.momentum) / 6.0;
      s = advanced(s, sum, dt);
      s.attitude.normalize();
      out.peak_momentum = out.peak_momentum.cwiseMax(s.momentum.cwiseAbs());
    }
    record();
  }
  return out;
}

}  // namespace attitude_planner
