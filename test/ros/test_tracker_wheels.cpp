// rostest (tracker_wheels.test): the tracker flies a reaction-wheel scene planned through the
// service with its wheel torques through body + wheels on the plan's scheme: `wheel_states`
// (JointState wheel_1..4, effort = the wheel torques within their limit), `wheel_momentum` and the
// momentum bars per sample; `done` carries each wheel's peaks along the flown path against its
// limits, and the flight lands on the plan's target. A feedback-mode tracker flies it with the
// law's torque distributed over the wheels; torque noise during the run (an actuator effect on a
// body torque no wheel makes) is refused by name. With the
// wheels' spin inertias, wheel_states.velocity is each wheel's spin rate relative to the body.
#include <gtest/gtest.h>
#include <ros/ros.h>

#include <algorithm>
#include <cmath>
#include <mutex>
#include <set>
#include <vector>

#include <geometry_msgs/PoseStamped.h>
#include <geometry_msgs/Vector3Stamped.h>
#include <sensor_msgs/JointState.h>
#include <std_msgs/Float64MultiArray.h>
#include <visualization_msgs/MarkerArray.h>
#include <map>

#include "attitude_planner/ReplayResult.h"
#include "attitude_planner/ros/conversions.hpp"
#include "ros_test_helpers.hpp"

using namespace attitude_planner;
namespace rc = attitude_planner::ros_conversions;

namespace {

/// Everything the wheel topics carried during the run.
struct WheelTopics {
  std::mutex mutex;
  int joint_messages = 0, marker_messages = 0, momentum_messages = 0;
  std::set<std::string> names;
  double peak_effort = 0.0, peak_momentum = 0.0;
  bool velocity_empty = true, shapes_right = true;
  std::set<std::string> marker_namespaces;
};

/// /spin's wheel spin rates, body rates and attitudes by stamp [s], collected from the start.
struct SpinSamples {
  std::mutex mutex;
  std::map<double, std::vector<double>> spin;
  std::map<double, Vector3> rate;
  std::map<double, Matrix3> attitude;
  std::vector<ros::Subscriber> subscribers;

  void subscribe(ros::NodeHandle& nh) {
    subscribers.push_back(nh.subscribe<sensor_msgs::JointState>(
        "wheel_states", 1000, [this](const sensor_msgs::JointState::ConstPtr& m) {
          std::lock_guard<std::mutex> lock(mutex);
          spin[m->header.stamp.toSec()] = m->velocity;
        }));
    subscribers.push_back(nh.subscribe<geometry_msgs::Vector3Stamped>(
        "angular_velocity", 1000, [this](const geometry_msgs::Vector3Stamped::ConstPtr& m) {
          std::lock_guard<std::mutex> lock(mutex);
          rate[m->header.stamp.toSec()] = rc::vectorFromMsg(m->vector);
        }));
    subscribers.push_back(nh.subscribe<geometry_msgs::PoseStamped>(
        "body_pose", 1000, [this](const geometry_msgs::PoseStamped::ConstPtr& m) {
          std::lock_guard<std::mutex> lock(mutex);
          attitude[m->header.stamp.toSec()] = rc::attitudeFromMsg(m->pose.orientation, "body_pose");
        }));
  }
};
SpinSamples* spin_samples = nullptr;

}  // namespace

TEST(TrackerWheels, TheWheelTorquesFlyTheSceneWithinTheLimitsAndDoneReportsThePeaks) {
  ros::NodeHandle nh("wheels");
  WheelTopics seen;
  const ros::Subscriber joints = nh.subscribe<sensor_msgs::JointState>(
      "wheel_states", 100, [&](const sensor_msgs::JointState::ConstPtr& m) {
        std::lock_guard<std::mutex> lock(seen.mutex);
        ++seen.joint_messages;
        seen.shapes_right = seen.shapes_right && m->name.size() == 4 && m->effort.size() == 4;
        seen.velocity_empty = seen.velocity_empty && m->velocity.empty();
        seen.names.insert(m->name.begin(), m->name.end());
        for (double u : m->effort) seen.peak_effort = std::max(seen.peak_effort, std::abs(u));
      });
  const ros::Subscriber momenta = nh.subscribe<std_msgs::Float64MultiArray>(
      "wheel_momentum", 100, [&](const std_msgs::Float64MultiArray::ConstPtr& m) {
        std::lock_guard<std::mutex> lock(seen.mutex);
        ++seen.momentum_messages;
        seen.shapes_right = seen.shapes_right && m->data.size() == 4;
        for (double h : m->data) seen.peak_momentum = std::max(seen.peak_momentum, std::abs(h));
      });
  const ros::Subscriber bars = nh.subscribe<visualization_msgs::MarkerArray>(
      "wheel_momentum_markers", 100, [&](const visualization_msgs::MarkerArray::ConstPtr& m) {
        std::lock_guard<std::mutex> lock(seen.mutex);
        ++seen.marker_messages;
        seen.shapes_right = seen.shapes_right && m->markers.size() == 8;
        for (const auto& marker : m->markers) seen.marker_namespaces.insert(marker.ns);
      });
  ros_testing::DoneListener listener(nh);
  const ReplayResult::ConstPtr done = listener.wait(100.0);
  ASSERT_TRUE(done) << "no done from /wheels";
  ASSERT_TRUE(done->success) << done->message;
  EXPECT_EQ(done->mode, "replay");
  EXPECT_NE(done->message.find("4 reaction wheels"), std::string::npos) << done->message;
  // Body + wheels from the wheel torques on the plan's own scheme (the Lie group integrator the
  // plan was made with) reproduce the plan to round-off; the continuous RK4 flight flown here
  // before missed by O(h²), 1e-5 rad and more at N = 128 over 20 s.
  EXPECT_NE(done->message.find("on the plan's scheme second_order"), std::string::npos)
      << done->message;
  EXPECT_LT(done->terminal_attitude_error, 1e-10);
  EXPECT_LT(done->max_attitude_deviation, 1e-10);
  EXPECT_EQ(done->reaction_wheels.effort_minimized, "") << "a flown path minimizes nothing";
  ASSERT_EQ(done->reaction_wheels.wheels.size(), 4u);
  double closest = 1.0;
  for (const WheelPeak& w : done->reaction_wheels.wheels) {
    EXPECT_EQ(w.max_momentum, ros_testing::kWheelMomentumLimit);
    EXPECT_EQ(w.max_torque, ros_testing::kWheelTorqueLimit);
    EXPECT_EQ(w.momentum_margin, w.max_momentum - w.peak_momentum);
    EXPECT_EQ(w.torque_margin, w.max_torque - w.peak_torque);
    // The plan's node torques meet U exactly, its momenta H: so does the flight, to round-off.
    EXPECT_GE(w.torque_margin, -1e-9 * w.max_torque) << w.name;
    EXPECT_GE(w.momentum_margin, -1e-9 * w.max_momentum) << w.name;
    closest = std::min(closest, std::abs(w.momentum_margin));
  }
  EXPECT_LT(closest, 1e-3) << "the momentum limit binds on the flown path too";
  // The constraint health lists the wheels last, with the worst excess over every wheel limit.
  ASSERT_FALSE(done->constraint_names.empty());
  EXPECT_EQ(done->constraint_names.back(), "reaction_wheels");
  ASSERT_EQ(done->constraint_violations.size(), done->constraint_names.size());
  double worst = 0.0;
  for (const WheelPeak& w : done->reaction_wheels.wheels)
    worst = std::max({worst, -w.momentum_margin, -w.torque_margin});
  EXPECT_EQ(done->constraint_violations.back(), worst);
  std::lock_guard<std::mutex> lock(seen.mutex);
  // 20 s / rate_factor 2 at 20 Hz: 200 samples (each topic's first ones may precede this
  // subscriber's connection on a loaded machine).
  EXPECT_GT(seen.joint_messages, 100);
  EXPECT_GT(seen.momentum_messages, 100);
  EXPECT_GT(seen.marker_messages, 100);
  EXPECT_TRUE(seen.shapes_right);
  EXPECT_TRUE(seen.velocity_empty) << "no spin inertia: no wheel speed";
  EXPECT_EQ(seen.names, (std::set<std::string>{"wheel_1", "wheel_2", "wheel_3", "wheel_4"}));
  EXPECT_LE(seen.peak_effort, ros_testing::kWheelTorqueLimit * (1 + 1e-9));
  EXPECT_GT(seen.peak_effort, 0.0);
  // The published momenta are the flight's (at the samples): never above its peak.
  double flown_peak = 0.0;
  for (const WheelPeak& w : done->reaction_wheels.wheels)
    flown_peak = std::max(flown_peak, w.peak_momentum);
  EXPECT_LE(seen.peak_momentum, flown_peak * (1 + 1e-12));
  EXPECT_GT(seen.peak_momentum, 0.5 * flown_peak);
  EXPECT_EQ(seen.marker_namespaces,
            (std::set<std::string>{"wheel_momentum", "wheel_momentum_limit"}));
}

TEST(TrackerWheels, FeedbackModeFliesTheLawThroughTheWheelsWithinTheirTorqueLimits) {
  // The law's torque distributed over the wheels (minimum norm), each cut to its limit: the loop
  // lands on the plan's target, and no wheel torque exceeds U = 0.3 N m (cut exactly).
  ros::NodeHandle nh("feedback");
  ros_testing::DoneListener listener(nh);
  const ReplayResult::ConstPtr done = listener.wait(100.0);
  ASSERT_TRUE(done) << "no done from /feedback";
  ASSERT_TRUE(done->success) << done->message;
  EXPECT_EQ(done->mode, "feedback");
  EXPECT_NE(done->message.find("feedback through 4 reaction wheels"), std::string::npos)
      << done->message;
  EXPECT_NE(done->message.find("samples cut at a wheel limit"), std::string::npos) << done->message;
  EXPECT_LT(done->terminal_attitude_error, 1e-3);
  ASSERT_EQ(done->reaction_wheels.wheels.size(), 4u);
  for (const WheelPeak& w : done->reaction_wheels.wheels) {
    EXPECT_GE(w.torque_margin, 0.0) << w.name;
    EXPECT_GT(w.peak_torque, 0.0) << w.name;
  }
  EXPECT_EQ(done->constraint_names.back(), "reaction_wheels");
}

TEST(TrackerWheels, ActuatorEffectsDuringTheRunAreRefusedByName) {
  ros::NodeHandle nh("noisy");
  ros_testing::DoneListener listener(nh);
  const ReplayResult::ConstPtr done = listener.wait(60.0);
  ASSERT_TRUE(done) << "no done from /noisy";
  EXPECT_FALSE(done->success);
  EXPECT_NE(done->message.find("maneuver.reaction_wheels, effects during the run: torque_noise"),
            std::string::npos)
      << done->message;
}

TEST(TrackerWheels, SpinRatesWithTheBodyRateConserveTheGyrostatsMomentum) {
  // test/ros/wheel_pyramid_spin.yaml: J_s = [0.2, 0.25, 0.2, 0.3] kg m^2. From the published
  // relative spin rates w_i, the body rate Ω and the attitude R (three topics matched by stamp),
  // the gyrostat's momentum R ((J + Σ J_s,i a_i a_iᵀ) Ω + Σ a_i J_s,i w_i) is the total momentum
  // π₀ = R_0 (J Ω_0 + A h_w(0)) = A h_w(0) of the scene (at rest, R_0 = I): conserved, no effects.
  // A wrong sign of a_i·Ω in w_i would move it by 2 Σ J_s,i a_i (a_i·Ω), ~0.05 N m s here.
  // Subscribed from the start of the program (main): this test runs after the others, when the
  // /spin run may have ended.
  ros::NodeHandle nh("spin");
  SpinSamples& seen = *spin_samples;
  ros_testing::DoneListener listener(nh);
  const ReplayResult::ConstPtr done = listener.wait(100.0);
  ASSERT_TRUE(done) << "no done from /spin";
  ASSERT_TRUE(done->success) << done->message;
  const double s = std::sqrt(2.0 / 3.0), c = std::sqrt(1.0 / 3.0);
  const Vector3 axes[4] = {Vector3(s, 0, c), Vector3(0, s, c), Vector3(-s, 0, c),
                           Vector3(0, -s, c)};
  const double spin_inertia[4] = {0.2, 0.25, 0.2, 0.3};
  const double initial_momentum[4] = {0.3, -0.2, 0.5, 0.1};
  Matrix3 locked;
  locked << 13, -2, 1, -2, 16, 0.5, 1, 0.5, 18;
  Vector3 total = Vector3::Zero();
  for (int i = 0; i < 4; ++i) {
    locked += spin_inertia[i] * axes[i] * axes[i].transpose();
    total += axes[i] * initial_momentum[i];
  }
  std::lock_guard<std::mutex> lock(seen.mutex);
  int matched = 0;
  double worst = 0.0, fastest = 0.0;
  for (const auto& [stamp, w] : seen.spin) {
    ASSERT_EQ(w.size(), 4u) << "velocity: one spin rate per wheel";
    const auto rate = seen.rate.find(stamp);
    const auto attitude = seen.attitude.find(stamp);
    if (rate == seen.rate.end() || attitude == seen.attitude.end()) continue;
    Vector3 body = locked * rate->second;
    for (int i = 0; i < 4; ++i) {
      body += axes[i] * spin_inertia[i] * w[i];
      fastest = std::max(fastest, std::abs(w[i]));
    }
    worst = std::max(worst, (attitude->second * body - total).norm());
    ++matched;
  }
  std::printf(
      "%d samples matched: worst |R H_gyrostat - pi_0| %.3g N m s (|pi_0| %.3g), fastest "
      "wheel %.3g rad/s\n",
      matched, worst, total.norm(), fastest);
  EXPECT_GT(matched, 100);
  EXPECT_GT(fastest, 0.5);
  EXPECT_LT(worst, 1e-4);  // measured 6.6e-6 N m s over 201 samples
}

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_tracker_wheels");
  ros::AsyncSpinner spinner(2);
  spinner.start();
  SpinSamples spin;
  ros::NodeHandle spin_nh("spin");
  spin.subscribe(spin_nh);
  spin_samples = &spin;
  return RUN_ALL_TESTS();
}
