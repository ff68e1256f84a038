// Shared pieces of the rostest gtests: the seed request (seed 000, example 1) at small N.
#pragma once

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <mutex>
#include <string>

#include <diagnostic_msgs/DiagnosticArray.h>
#include <ros/ros.h>

#include "../support/paper_equations.hpp"
#include "attitude_planner/AttitudeManeuver.h"
#include "attitude_planner/Constraint.h"
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

/// An anytime answer to fillSeedRequest's slew at `steps` steps (TIMED_OUT or CANCELLED with the
/// plan the solve had reached): flagged unconverged, N + 1 unit quaternions, the request's boundary
/// data R_0 = I, Ω_0 = 0, R_N, Ω_{N−1} = 0, the paper scheme's equations of motion to round-off
/// (checked here from the rows, seed 000 eq. 18) and its residuals: step_residual met, max_residual
/// above the request's tolerance.
template <class Response>
void expectSeedAnytimePlan(const Response& res, int steps, double tolerance,
                           double angle = M_PI / 3) {
  namespace rc = ros_conversions;
  EXPECT_FALSE(res.success);
  EXPECT_TRUE(res.unconverged_plan) << res.message;
  const AttitudeManeuver& m = res.maneuver;
  ASSERT_EQ(m.attitude.size(), static_cast<std::size_t>(steps + 1)) << res.message;
  for (const geometry_msgs::Quaternion& q : m.attitude) {
    EXPECT_NEAR(std::sqrt(q.w * q.w + q.x * q.x + q.y * q.y + q.z * q.z), 1.0, 1e-12);
  }
  const Maneuver plan = rc::maneuverFromMsg(m);
  EXPECT_LT(so3::angleBetween(plan.attitude.front(), Matrix3::Identity()), 1e-12);
  EXPECT_LT(so3::angleBetween(plan.attitude.back(), so3::fromAxisAngle(Vector3::UnitX(), angle)),
            1e-12);
  EXPECT_LT(plan.angular_velocity.front().norm(), 1e-12);
  EXPECT_LT(plan.angular_velocity[steps - 1].norm(), 1e-12);
  Matrix3 inertia;
  for (int i = 0; i < 9; ++i) inertia(i / 3, i % 3) = seedInertia()[i];
  EXPECT_LT(test_support::paperEquationMiss(inertia, plan), 1e-11);
  EXPECT_LE(res.step_residual, 1e-8);
  EXPECT_TRUE(std::isfinite(res.max_residual));
  EXPECT_GT(res.max_residual, tolerance);
  EXPECT_GT(res.cost, 0.0);
  // Handed over without its open-loop replay, said as data: the replay figures not measured.
  EXPECT_FALSE(res.replay_measured);
  EXPECT_TRUE(std::isnan(res.replay_miss));
}

/// scenes/sun_keep_out.yaml as a request at `steps` steps, plus |τ_k| ≤ 0.095 N m: a π/2 slew
/// about world z in T = 60 s (J = diag(20, 25, 30) kg·m²) whose straight path crosses a keep-out
/// cone of 0.5 rad around the Sun (body x); the plan around the cone alone peaks at ~0.10 N m
/// (N = 16, 32), so both constraints bind.
constexpr double kConstrainedTorqueNorm = 0.095;  // [N m]
inline Vector3 constrainedRequestSun() {
  return Vector3(0.7035741925769524, 0.7035741925769523, 0.09983341664682815);
}
constexpr double kConstrainedHalfAngle = 0.5;  // [rad]

template <class Request>
void fillConstrainedRequest(Request* r, int steps = 32) {
  r->inertia = {20, 0, 0, 0, 25, 0, 0, 0, 30};
  r->initial_attitude.w = 1.0;
  r->final_attitude =
      ros_conversions::attitudeToMsg(so3::fromAxisAngle(Vector3::UnitZ(), M_PI / 2));
  r->duration = 60.0;
  r->steps = steps;
  Constraint norm;
  norm.type = Constraint::MAX_TORQUE_NORM;
  norm.limit = kConstrainedTorqueNorm;
  Constraint sun;
  sun.type = Constraint::KEEP_OUT;
  sun.body_axis.x = 1.0;
  sun.world_direction = ros_conversions::vectorToMsg(constrainedRequestSun());
  sun.half_angle = kConstrainedHalfAngle;
  r->constraints = {norm, sun};
}

/// The wheel limits of fillWheelRequest (test/ros/wheel_pyramid.yaml): U [N m], H [N m s].
inline constexpr double kWheelTorqueLimit = 0.3, kWheelMomentumLimit = 0.9;

/// The momentum-limited slew of test/ros/wheel_pyramid.yaml as a request: J = [[13, −2, 1],
/// [−2, 16, 0.5], [1, 0.5, 18]], rest to rest through exp((0.4, −0.7, 0.9)^) in 20 s,
/// second_order, a four-wheel pyramid with U = 0.3 N m, H = 0.9 N m s and the bias h_w(0) =
/// (0.3, −0.2, 0.5, 0.1) N m s (the momentum limit binds).
template <class Request>
void fillWheelRequest(Request* r, int steps = 128) {
  r->inertia = {13, -2, 1, -2, 16, 0.5, 1, 0.5, 18};
  r->initial_attitude.w = 1.0;
  r->final_attitude = ros_conversions::attitudeToMsg(so3::exp(Vector3(0.4, -0.7, 0.9)));
  r->duration = 20.0;
  r->steps = steps;
  r->scheme = "second_order";
  const double s = std::sqrt(2.0 / 3.0), c = std::sqrt(1.0 / 3.0);
  for (const Vector3& a :
       {Vector3(s, 0, c), Vector3(0, s, c), Vector3(-s, 0, c), Vector3(0, -s, c)})
    r->reaction_wheels.spin_axes.push_back(ros_conversions::vectorToMsg(a));
  r->reaction_wheels.max_torque = {kWheelTorqueLimit};
  r->reaction_wheels.max_momentum = {kWheelMomentumLimit};
  r->reaction_wheels.initial_momentum = {0.3, -0.2, 0.5, 0.1};
}

/// Checks a wheel answer (fillWheelRequest, every node returned): the wheel rows' shape, the
/// initial momenta, every wheel within its limits at every row, the momentum limit binding, and
/// the summary's peaks and margins equal to the ones scanned here from the rows.
template <class Response>
void expectWheelAnswer(const Response& res, int steps) {
  ASSERT_TRUE(res.success) << res.message;
  EXPECT_NE(std::find(res.constraints.begin(), res.constraints.end(), "reaction_wheels"),
            res.constraints.end());
  const AttitudeManeuver& m = res.maneuver;
  const std::size_t rows = steps + 1, n = 4;
  ASSERT_EQ(m.reaction_wheels.spin_axes.size(), n);
  ASSERT_EQ(m.wheel_torque.size(), rows * n);
  ASSERT_EQ(m.wheel_momentum.size(), rows * n);
  const double bias[4] = {0.3, -0.2, 0.5, 0.1};
  for (std::size_t i = 0; i < n; ++i) EXPECT_NEAR(m.wheel_momentum[i], bias[i], 1e-12);
  ASSERT_EQ(res.reaction_wheels.wheels.size(), n);
  double closest = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < n; ++i) {
    double peak_h = 0.0, peak_u = 0.0;
    for (std::size_t k = 0; k < rows; ++k) {
      peak_h = std::max(peak_h, std::abs(m.wheel_momentum[k * n + i]));
      peak_u = std::max(peak_u, std::abs(m.wheel_torque[k * n + i]));  // second_order: every row
    }
    const WheelPeak& w = res.reaction_wheels.wheels[i];
    EXPECT_EQ(w.name, "wheel_" + std::to_string(i + 1));
    EXPECT_EQ(w.peak_momentum, peak_h) << w.name;
    EXPECT_EQ(w.peak_torque, peak_u) << w.name;
    EXPECT_EQ(w.max_momentum, kWheelMomentumLimit);
    EXPECT_EQ(w.max_torque, kWheelTorqueLimit);
    EXPECT_EQ(w.momentum_margin, kWheelMomentumLimit - peak_h);
    EXPECT_EQ(w.torque_margin, kWheelTorqueLimit - peak_u);
    EXPECT_LE(peak_h, kWheelMomentumLimit * (1 + 1e-9)) << w.name;
    EXPECT_LE(peak_u, kWheelTorqueLimit * (1 + 1e-9)) << w.name;
    closest = std::min(closest, w.momentum_margin);
  }
  EXPECT_LT(closest, 1e-6) << "the momentum limit binds on some wheel";
  EXPECT_FALSE(res.reaction_wheels.has_momentum_norm_limit);
  EXPECT_GT(res.reaction_wheels.peak_momentum_norm, 0.0);
  // The effort named minimized is the one the answer's cost sums (second_order's trapezoidal
  // weights), computed here from the rows: the body torques', not the wheels'.
  double body = 0.0, wheel = 0.0;
  for (std::size_t k = 0; k < rows; ++k) {
    const double w = (k == 0 || k + 1 == rows) ? 0.5 : 1.0;
    body += w * 0.5 * ros_conversions::vectorFromMsg(m.torque[k]).squaredNorm();
    for (std::size_t i = 0; i < n; ++i) wheel += w * 0.5 * std::pow(m.wheel_torque[k * n + i], 2);
  }
  EXPECT_EQ(res.reaction_wheels.effort_minimized, "body_torque");
  EXPECT_NEAR(res.cost, body, 1e-9 * body);
  EXPECT_GT(std::abs(res.cost - wheel), 1e-3 * body) << "the wheels' effort differs";
}

/// The smallest slacks of fillConstrainedRequest's constraints over a returned maneuver's nodes,
/// computed here from its rows: 0.095 N m − |τ_k| and angle(R_k x, Sun) − 0.5 rad (≥ 0: met).
struct ConstrainedSlacks {
  double torque = std::numeric_limits<double>::infinity();
  double cone = std::numeric_limits<double>::infinity();
};
inline ConstrainedSlacks constrainedRequestSlacks(const AttitudeManeuver& m) {
  const Vector3 sun = constrainedRequestSun();
  ConstrainedSlacks out;
  for (const geometry_msgs::Vector3& t : m.torque) {
    out.torque =
        std::min(out.torque, kConstrainedTorqueNorm - ros_conversions::vectorFromMsg(t).norm());
  }
  for (const geometry_msgs::Quaternion& q : m.attitude) {
    const Vector3 x = ros_conversions::attitudeFromMsg(q, "attitude") * Vector3::UnitX();
    out.cone =
        std::min(out.cone, std::atan2(x.cross(sun).norm(), x.dot(sun)) - kConstrainedHalfAngle);
  }
  return out;
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

/// The newest /diagnostics status named `name` (empty name: none yet), kept by a subscription.
class StatusWatch {
 public:
  explicit StatusWatch(std::string name) : name_(std::move(name)) {
    sub_ = nh_.subscribe("/diagnostics", 10, &StatusWatch::onArray, this);
  }
  /// The named status's value of `key` once `accept` holds for it, waiting up to `seconds`.
  std::string waitFor(const std::string& key, const std::function<bool(const std::string&)>& accept,
                      double seconds) {
    const ros::WallTime until = ros::WallTime::now() + ros::WallDuration(seconds);
    for (;;) {  // looks at least once, even with no time to wait
      {
        std::lock_guard<std::mutex> lock(mutex_);
        for (const diagnostic_msgs::KeyValue& pair : newest_.values) {
          if (pair.key == key && accept(pair.value)) return pair.value;
        }
      }
      if (ros::WallTime::now() >= until) break;
      ros::WallDuration(0.05).sleep();
    }
    return "(not seen)";
  }

 private:
  void onArray(const diagnostic_msgs::DiagnosticArray::ConstPtr& array) {
    for (const diagnostic_msgs::DiagnosticStatus& status : array->status) {
      if (status.name != name_) continue;
      std::lock_guard<std::mutex> lock(mutex_);
      newest_ = status;
    }
  }
  std::string name_;
  ros::NodeHandle nh_;
  ros::Subscriber sub_;
  std::mutex mutex_;
  diagnostic_msgs::DiagnosticStatus newest_;
};

}  // namespace ros_testing
}  // namespace attitude_planner
