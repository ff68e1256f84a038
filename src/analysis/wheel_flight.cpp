// A plan flown with reaction wheels (wheel_flight.hpp).
#include "attitude_planner/analysis/wheel_flight.hpp"

#include <algorithm>
#include <cmath>

#include "attitude_planner/analysis/wheel_plant.hpp"
#include "attitude_planner/dynamics/discrete_wheel_replay.hpp"
#include "attitude_planner/dynamics/wheel_replay.hpp"

namespace attitude_planner {

Eigen::VectorXd heldLinearly(const std::vector<Eigen::VectorXd>& rows, double time_step, double t) {
  const int N = static_cast<int>(rows.size()) - 1;
  const double s = std::clamp(t / time_step, 0.0, static_cast<double>(N));
  const int k = std::min(static_cast<int>(std::floor(s)), N - 1);
  const double f = s - k;
  return (1.0 - f) * rows[k] + f * rows[k + 1];
}

Eigen::VectorXd WheelFlight::torqueAt(double t) const {
  return heldLinearly(torque, body.time_step, t);
}

Eigen::VectorXd WheelFlight::momentumAt(double t) const {
  return heldLinearly(momentum, body.time_step, t);
}

namespace {

/// The flight's body at node k from its state and the array's reaction on it.
void appendNode(const WheelArray& array, const Matrix3& attitude, const Vector3& rate,
                const Vector3& body_torque, const Eigen::VectorXd& momentum, WheelFlight* out) {
  const int k = static_cast<int>(out->body.attitude.size());
  out->body.time.push_back(k * out->body.time_step);
  out->body.attitude.push_back(attitude);
  out->body.angular_velocity.push_back(rate);
  out->body.torque.push_back(body_torque);
  out->momentum.push_back(momentum);
  out->peaks.observeMomentum(array.axes, momentum);
  out->peaks.observeTorque(out->torque[k]);  // every node's u is flown (held linearly)
}

/// The continuous body + wheels (RK4) from the wheel torques already in `out`.
void flyContinuously(const Matrix3& inertia, const WheelArray& array,
                     const Eigen::VectorXd& initial, double time_step, const RigidBodyState& start,
                     WheelFlight* out) {
  // No world disturbance: the tracker refuses effects during a flight with wheels.
  const WheelReplay replay =
      replayWithWheels(inertia, array.axes, start.attitude, start.angular_velocity, initial,
                       time_step, out->torque, Vector3::Zero(), kWheelFlightSubsteps);
  out->peaks.peak_momentum = replay.peak_momentum;
  for (std::size_t k = 0; k < replay.attitude.size(); ++k) {
    const Vector3& rate = replay.angular_velocity[k];
    appendNode(array, replay.attitude[k], rate,
               arrayReaction(array, out->torque[k], rate, replay.momentum[k]), replay.momentum[k],
               out);
  }
}

/// Body + wheels on the plan's discrete scheme from the wheel torques already in `out`; the
/// body's velocities reported as the scheme reports a plan's.
void flyOnTheScheme(SchemeKind scheme, const Matrix3& inertia, const WheelArray& array,
                    const Eigen::VectorXd& initial, double time_step, const RigidBodyState& start,
                    WheelFlight* out) {
  const DiscreteWheelReplay replay =
      replayWithWheelsOnTheScheme(scheme, inertia, array.axes, start.attitude,
                                  start.angular_velocity, initial, time_step, out->torque);
  const DiscreteScheme discrete(scheme, inertia, time_step);
  const int N = static_cast<int>(replay.attitude.size()) - 1;
  for (int k = 0; k <= N; ++k) {
    Vector3 rate = replay.node_velocity[k];
    if (!discrete.hasEndTorques()) {  // each step's reported velocity, row N repeating N − 1
      const int step = std::min(k, N - 1);
      rate =
          discrete.velocity(Matrix3(replay.attitude[step].transpose() * replay.attitude[step + 1]));
    }
    appendNode(array, replay.attitude[k], rate, replay.body_torque[k], replay.momentum[k], out);
  }
}

}  // namespace

WheelFlight flyWithWheels(const Matrix3& inertia, SchemeKind scheme, const ReactionWheels& wheels,
                          const Maneuver& plan, std::vector<Eigen::VectorXd> wheel_torque,
                          const RigidBodyState& start, WheelFlightModel model) {
  const WheelArray array = wheelArray(wheels);
  if (wheel_torque.empty()) wheel_torque = wheelStates(scheme, inertia, wheels, plan).torque;
  Eigen::VectorXd initial(wheels.count());
  for (int i = 0; i < wheels.count(); ++i) initial(i) = wheels.initialMomentum(i);
  WheelFlight out;
  out.torque = std::move(wheel_torque);
  out.body.time_step = plan.time_step;
  out.peaks = WheelPeaks(wheels.count());
  if (model == WheelFlightModel::PlanScheme && schemeIsDiscretization(scheme)) {
    flyOnTheScheme(scheme, inertia, array, initial, plan.time_step, start, &out);
  } else {
    flyContinuously(inertia, array, initial, plan.time_step, start, &out);
  }
  return out;
}

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
    const Eigen::VectorXd u =
        wheelTorquesFor(wheels, array, law.command(R, rate, t), rate, h, &cut);
    const Vector3 delivered = arrayReaction(array, u, rate, h);
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
