// Shared pieces of the rostest gtests: the seed request (seed 000, example 1) at small N.
#pragma once

#include <cmath>
#include <mutex>

#include <ros/ros.h>

#include "attitude_planner/AttitudeManeuver.h"
#include "attitude_planner/ReplayResult.h"
#include "attitude_planner/dynamics/simulation.hpp"
#include "attitude_planner/ros/conversions.hpp"

namespace attitude_planner {
namespace ros_testing {

/// Holds the tracker's latched `done` message once it arrives (callbacks from a spinner thread).
class DoneListener {
 public:
  explicit DoneListener(ros::NodeHandle& nh)
      : sub_(nh.subscribe("done", 1, &DoneListener::onDone, this)) {}
  /// Waits up to `seconds` of wall time for `done`; null if none arrived.
  ReplayResult::ConstPtr wait(double seconds) {
    const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(seconds);
    while (ros::WallTime::now() < deadline) {
      {
        std::lock_guard<std::mutex> lock(mutex_);
        if (done_) return done_;
      }
      ros::WallDuration(0.05).sleep();
    }
    return nullptr;
  }

 private:
  void onDone(const ReplayResult::ConstPtr& m) {
    std::lock_guard<std::mutex> lock(mutex_);
    done_ = m;
  }
  std::mutex mutex_;
  ReplayResult::ConstPtr done_;
  ros::Subscriber sub_;  ///< last: unsubscribed before the rest is destroyed
};

/// Seed 000's inertia J [kg·m²], row-major.
inline boost::array<double, 9> seedInertia() {
  return {13.25, -7.80, -11.40, -7.80, 16.25, 4.71, -11.40, 4.71, 18.37};
}

/// Fills a service request / action goal with the seed's rest-to-rest slew by `angle` [rad]
/// about body x in T = 12.8 s and `steps` steps.
template <class Request>
void fillSeedRequest(Request* r, int steps = 32, double angle = M_PI / 3) {
  r->inertia = seedInertia();
  r->allow_nonphysical_inertia = true;  // the seed's J violates J1 + J2 >= J3
  r->initial_attitude.w = 1.0;
  r->final_attitude = ros_conversions::attitudeToMsg(so3::fromAxisAngle(Vector3::UnitX(), angle));
  r->duration = 12.8;
  r->steps = steps;
}

/// A test maneuver needing no planner: the seed body driven by smooth known torques τ_k [N·m],
/// h = 0.1 s, `steps` steps (the paper scheme); `plan` receives the simulated maneuver.
inline AttitudeManeuver testManeuver(int steps, Maneuver* plan) {
  PlanningProblem p;
  p.inertia = ros_conversions::inertiaFromMsg(seedInertia());
  const DiscreteScheme scheme(SchemeKind::Paper, p.inertia, 0.1);
  SimulationInput input;
  input.torque.assign(steps + 1, Vector3::Zero());
  for (int k = 1; k < steps; ++k) {
    const double s = std::sin(M_PI * k / steps);
    input.torque[k] = Vector3(2.0 * s, -1.0 * s * s, 0.5 * std::sin(2 * M_PI * k / steps));
  }
  *plan = simulate(scheme, input);
  return ros_conversions::maneuverToMsg(*plan, p, "world", "body", ros::Time::now());
}

}  // namespace ros_testing
}  // namespace attitude_planner
