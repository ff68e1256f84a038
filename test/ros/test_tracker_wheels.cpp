// rostest (tracker_wheels.test): the tracker flies a reaction-wheel scene planned through the
// service with its wheel torques through body + wheels: `wheel_states` (JointState wheel_1..4,
// effort = the wheel torques within their limit), `wheel_momentum` and the momentum bars per
// sample; `done` carries each wheel's peaks along the flown path against its limits, and the
// flight lands on the plan's target. A feedback-mode tracker refuses the same scene by name.
#include <gtest/gtest.h>
#include <ros/ros.h>

#include <algorithm>
#include <cmath>
#include <mutex>
#include <set>
#include <vector>

#include <sensor_msgs/JointState.h>
#include <std_msgs/Float64MultiArray.h>
#include <visualization_msgs/MarkerArray.h>

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
  // The continuous body + wheels from the wheel torques lands on the plan's target to O(h²)
  // (N = 128 over 20 s).
  EXPECT_LT(done->terminal_attitude_error, 1e-3);
  EXPECT_LT(done->max_attitude_deviation, 1e-3);
  ASSERT_EQ(done->reaction_wheels.wheels.size(), 4u);
  double closest = 1.0;
  for (const WheelPeak& w : done->reaction_wheels.wheels) {
    EXPECT_EQ(w.max_momentum, ros_testing::kWheelMomentumLimit);
    EXPECT_EQ(w.max_torque, ros_testing::kWheelTorqueLimit);
    EXPECT_EQ(w.momentum_margin, w.max_momentum - w.peak_momentum);
    EXPECT_EQ(w.torque_margin, w.max_torque - w.peak_torque);
    // The plan's node torques meet U exactly; the flown momenta between nodes to O(h²).
    EXPECT_GE(w.torque_margin, -1e-9 * w.max_torque) << w.name;
    EXPECT_GE(w.momentum_margin, -1e-3 * w.max_momentum) << w.name;
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

TEST(TrackerWheels, FeedbackModeRefusesAWheelManeuverByName) {
  ros::NodeHandle nh("feedback");
  ros_testing::DoneListener listener(nh);
  const ReplayResult::ConstPtr done = listener.wait(60.0);
  ASSERT_TRUE(done) << "no done from /feedback";
  EXPECT_FALSE(done->success);
  EXPECT_NE(done->message.find("maneuver.reaction_wheels"), std::string::npos) << done->message;
  EXPECT_NE(done->message.find("~mode replay only"), std::string::npos) << done->message;
  EXPECT_NE(done->message.find("feedback"), std::string::npos) << done->message;
}

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_tracker_wheels");
  ros::AsyncSpinner spinner(2);
  spinner.start();
  return RUN_ALL_TESTS();
}
