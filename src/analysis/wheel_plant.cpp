// Body + reaction wheels as a plant (wheel_plant.hpp).
#include "attitude_planner/analysis/wheel_plant.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>

#include "attitude_planner/analysis/wheel_flight.hpp"
#include "attitude_planner/dynamics/wheel_replay.hpp"
#include "attitude_planner/errors.hpp"

namespace attitude_planner {

Eigen::VectorXd wheelTorquesFor(const ReactionWheels& wheels, const WheelArray& array,
                                const Vector3& body_torque, const Vector3& rate,
                                const Eigen::VectorXd& momentum, bool* cut) {
  // τ = −A u − Ω × A h_w  ⇒  A u = −(τ + Ω × A h_w); u = A⁺(A u) carries no null-space part.
  const Vector3 array_torque = -(body_torque + rate.cross(array.axes * momentum));
  Eigen::VectorXd u = array.pseudo_inverse * array_torque;
  for (int i = 0; i < wheels.count(); ++i) {
    const double limit = wheels.torqueLimit(i), H = wheels.momentumLimit(i);
    double wanted = std::clamp(u(i), -limit, limit);
    if ((momentum(i) >= H && wanted > 0.0) || (momentum(i) <= -H && wanted < 0.0)) wanted = 0.0;
    if (wanted != u(i) && cut) *cut = true;
    u(i) = wanted;
  }
  return u;
}

Vector3 arrayReaction(const WheelArray& array, const Eigen::VectorXd& torque, const Vector3& rate,
                      const Eigen::VectorXd& momentum) {
  return -array.axes * torque - rate.cross(array.axes * momentum);
}

namespace {

/// The effects' torque on the body over a replay that starts at maneuver time t0 (none: null).
ExternalTorque effectTorqueFrom(const EffectModel* effects, double t0) {
  if (!effects || effects->empty()) return nullptr;
  return [effects, t0](const Matrix3& R, double s) { return effects->torque(R, t0 + s); };
}

}  // namespace

WheelBodyState predictWheelState(const Matrix3& inertia, const WheelArray& array,
                                 const WheelBodyState& state, const Eigen::VectorXd& torque,
                                 double dt, const EffectModel* effects, double t) {
  if (!(dt > 0.0)) return state;
  const WheelReplay step = replayWithWheelsUnder(
      inertia, array.axes, state.body.attitude, state.body.angular_velocity, state.momentum, dt,
      {torque, torque}, effectTorqueFrom(effects, t), kWheelFlightSubsteps);
  return {{step.attitude.back(), step.angular_velocity.back()}, step.momentum.back()};
}

WheelPlant::WheelPlant(const Matrix3& inertia, const ReactionWheels& wheels,
                       const RigidBodyState& start, double max_step,
                       std::shared_ptr<const EffectModel> effects)
    : inertia_(inertia),
      wheels_(wheels),
      effects_(effects && !effects->empty() ? std::move(effects) : nullptr),
      array_(wheelArray(wheels)),
      max_step_(max_step),
      commanded_(Eigen::VectorXd::Zero(wheels.count())),
      delivered_(Eigen::VectorXd::Zero(wheels.count())),
      saturated_at_(wheels.count(), std::numeric_limits<double>::quiet_NaN()) {
  if (!(std::isfinite(max_step) && max_step > 0.0)) {
    throw InvalidInput("max_step: must be a finite time > 0 s, got " + exactNumber(max_step));
  }
  state_.body = start;
  state_.momentum.resize(wheels.count());
  for (int i = 0; i < wheels.count(); ++i) state_.momentum(i) = wheels.initialMomentum(i);
}

const Eigen::VectorXd& WheelPlant::command(const Eigen::VectorXd& torque) {
  if (torque.size() != wheels_.count()) {
    throw InvalidInput("wheel command: needs one torque per wheel (" +
                       std::to_string(wheels_.count()) + "), got " + std::to_string(torque.size()));
  }
  for (int i = 0; i < wheels_.count(); ++i) {
    commanded_(i) = std::clamp(torque(i), -wheels_.torqueLimit(i), wheels_.torqueLimit(i));
  }
  updateDelivered();
  return delivered_;
}

void WheelPlant::updateDelivered() {
  for (int i = 0; i < wheels_.count(); ++i) {
    const double h = state_.momentum(i), H = wheels_.momentumLimit(i), u = commanded_(i);
    const bool stopped = (h >= H && u > 0.0) || (h <= -H && u < 0.0);
    delivered_(i) = stopped ? 0.0 : u;
  }
}

void WheelPlant::integrate(double dt) {
  // Equal steps of at most max_step, the held torques at every RK4 stage.
  const int steps = std::max(1, static_cast<int>(std::ceil(dt / max_step_)));
  const WheelReplay replay = replayWithWheelsUnder(
      inertia_, array_.axes, state_.body.attitude, state_.body.angular_velocity, state_.momentum,
      dt, {delivered_, delivered_}, effectTorqueFrom(effects_.get(), time_), steps);
  state_ = {{replay.attitude.back(), replay.angular_velocity.back()}, replay.momentum.back()};
}

void WheelPlant::advanceTo(double t) {
  while (t > time_) {
    updateDelivered();
    // ḣ_w = u: each momentum is linear in time, so the first wheel to reach its limit ends
    // this stretch exactly where it does.
    double end = t;
    int stopping = -1;
    for (int i = 0; i < wheels_.count(); ++i) {
      const double u = delivered_(i);
      if (u == 0.0) continue;
      const double limit = std::copysign(wheels_.momentumLimit(i), u);
      const double reached = time_ + (limit - state_.momentum(i)) / u;
      if (reached < end) {
        end = reached;
        stopping = i;
      }
    }
    if (end > time_) integrate(end - time_);
    time_ = end;
    if (stopping < 0) continue;
    state_.momentum(stopping) =
        std::copysign(wheels_.momentumLimit(stopping), delivered_(stopping));
    if (std::isnan(saturated_at_[stopping])) saturated_at_[stopping] = time_;
  }
  updateDelivered();
}

}  // namespace attitude_planner
