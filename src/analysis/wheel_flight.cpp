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

namespace {

/// The wheel torques that make the body torque `body_torque` (minimum norm), cut to the array's
/// limits at wheel momenta `momentum`; `cut` is set when a wheel's command was changed.
Eigen::VectorXd wheelCommand(const ReactionWheels& wheels, const WheelArray& array,
                             const Vector3& body_torque, const Vector3& rate,
                             const Eigen::VectorXd& momentum, bool* cut) {
  // τ = −A u − Ω × A h_w  ⇒  A u = −(τ + Ω × A h_w); u = A⁺(A u) carries no null-space part.
  const Vector3 array_torque = -(body_torque + rate.cross(array.axes * momentum));
  Eigen::VectorXd u = array.pseudo_inverse * array_torque;
  for (int i = 0; i < wheels.count(); ++i) {
    const double limit = wheels.torqueLimit(i), H = wheels.momentumLimit(i);
    double wanted = std::clamp(u(i), -limit, limit);
    if ((momentum(i) >= H && wanted > 0.0) || (momentum(i) <= -H && wanted < 0.0)) wanted = 0.0;
    if (wanted != u(i)) *cut = true;
    u(i) = wanted;
  }
  return u;
}

}  // namespace

WheelTracking trackWithWheels(const ManeuverInterpolation& reference, const Matrix3& inertia,
                              const ReactionWheels& wheels, const RigidBodyState& start,
                              const TrackingOptions& options) {
  const TrackingLaw law(reference, nullptr, options);
  const WheelArray array = wheelArray(wheels);
  WheelTracking out;
  out.substeps = law.substepsPerPlanStep();
  out.natural_frequency = law.naturalFrequency();
  out.samples = reference.steps() * out.substeps;  // simulateTracking's control grid
  const double dt = reference.duration() / out.samples;
  WheelFlight& flight = out.flight;
  flight.body.time_step = dt;
  flight.peaks = WheelPeaks(wheels.count());
  Matrix3 R = start.attitude;
  Vector3 rate = start.angular_velocity;
  Eigen::VectorXd h(wheels.count());
  for (int i = 0; i < wheels.count(); ++i) h(i) = wheels.initialMomentum(i);
  flight.peaks.peak_momentum = h.cwiseAbs();
  for (int j = 0; j <= out.samples; ++j) {
    const double t = j * dt;
    bool cut = false;
    const Eigen::VectorXd u = wheelCommand(wheels, array, law.command(R, rate, t), rate, h, &cut);
    const Vector3 delivered = -array.axes * u - rate.cross(array.axes * h);
    flight.body.time.push_back(t);
    flight.body.attitude.push_back(R);
    flight.body.angular_velocity.push_back(rate);
    flight.body.torque.push_back(delivered);
    flight.torque.push_back(u);
    flight.momentum.push_back(h);
    flight.peaks.observeMomentum(array.axes, h);
    flight.peaks.observeTorque(u);
    if (j == out.samples) break;
    out.saturated_samples += cut ? 1 : 0;
    out.effort += 0.5 * delivered.squaredNorm() * dt;
    // u held over the period: the replay's linear hold between two equal rows.
    const WheelReplay period = replayWithWheels(inertia, array.axes, R, rate, h, dt, {u, u},
                                                Vector3::Zero(), kWheelFlightSubsteps);
    R = period.attitude.back();
    rate = period.angular_velocity.back();
    h = period.momentum.back();
    flight.peaks.peak_momentum = flight.peaks.peak_momentum.cwiseMax(period.peak_momentum);
  }
  return out;
}

}  // namespace attitude_planner
