// A plan flown with reaction wheels (wheel_flight.hpp).
#include "attitude_planner/analysis/wheel_flight.hpp"

#include <algorithm>
#include <cmath>

#include "attitude_planner/dynamics/wheel_replay.hpp"

namespace attitude_planner {

namespace {

/// Rows k and k + 1 and the fraction between them of time t on a grid of `rows` rows, step h.
Eigen::VectorXd linearAt(const std::vector<Eigen::VectorXd>& rows, double time_step, double t) {
  const int N = static_cast<int>(rows.size()) - 1;
  const double s = std::clamp(t / time_step, 0.0, static_cast<double>(N));
  const int k = std::min(static_cast<int>(std::floor(s)), N - 1);
  const double f = s - k;
  return (1.0 - f) * rows[k] + f * rows[k + 1];
}

}  // namespace

Eigen::VectorXd WheelFlight::torqueAt(double t) const {
  return linearAt(torque, body.time_step, t);
}

Eigen::VectorXd WheelFlight::momentumAt(double t) const {
  return linearAt(momentum, body.time_step, t);
}

WheelFlight flyWithWheels(const Matrix3& inertia, SchemeKind scheme, const ReactionWheels& wheels,
                          const Maneuver& plan, std::vector<Eigen::VectorXd> wheel_torque,
                          const RigidBodyState& start) {
  const WheelArray array = wheelArray(wheels);
  const int N = plan.steps();
  if (wheel_torque.empty()) wheel_torque = wheelStates(scheme, inertia, wheels, plan).torque;
  Eigen::VectorXd initial(wheels.count());
  for (int i = 0; i < wheels.count(); ++i) initial(i) = wheels.initialMomentum(i);
  // No world disturbance: the tracker refuses effects during a flight with wheels.
  const WheelReplay replay =
      replayWithWheels(inertia, array.axes, start.attitude, start.angular_velocity, initial,
                       plan.time_step, wheel_torque, Vector3::Zero(), kWheelFlightSubsteps);
  WheelFlight out;
  out.torque = std::move(wheel_torque);
  out.momentum = replay.momentum;
  out.body.time_step = plan.time_step;
  out.peaks = WheelPeaks(wheels.count());
  out.peaks.peak_momentum = replay.peak_momentum;
  for (int k = 0; k <= N; ++k) {
    const Vector3 array_momentum = array.axes * replay.momentum[k];
    out.body.time.push_back(k * plan.time_step);
    out.body.attitude.push_back(replay.attitude[k]);
    out.body.angular_velocity.push_back(replay.angular_velocity[k]);
    out.body.torque.push_back(-array.axes * out.torque[k] -
                              replay.angular_velocity[k].cross(array_momentum));
    out.peaks.observeMomentum(array.axes, replay.momentum[k]);
    out.peaks.observeTorque(out.torque[k]);  // every node's u is flown (held linearly)
  }
  return out;
}

}  // namespace attitude_planner
