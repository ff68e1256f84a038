// rostest: the tracker honours the message and streams at ~rate (tracker_stream.test: rate 20 Hz,
// rate factor 4). Frames come from header.frame_id / child_frame_id, a stamp in the future is
// t_0, time[] must agree with time_step (refused by name, the node keeps serving), the maneuver's
// constraints are drawn, and the number of samples is about rate · T / rate_factor.
#include <gtest/gtest.h>
#include <ros/ros.h>

#include <geometry_msgs/PoseStamped.h>
#include <geometry_msgs/WrenchStamped.h>
#include <std_msgs/Float64.h>
#include <tf2_ros/transform_listener.h>
#include <visualization_msgs/MarkerArray.h>

#include <mutex>

#include "attitude_planner/ReplayResult.h"
#include "ros_test_helpers.hpp"

using namespace attitude_planner;
namespace rc = attitude_planner::ros_conversions;

namespace {

constexpr int kSteps = 32;           // N, h = 0.1 s: T = 3.2 s
constexpr double kRate = 20.0;       // must match tracker_stream.test [Hz]
constexpr double kRateFactor = 4.0;  // must match tracker_stream.test

template <class Pred>
bool waitFor(Pred pred, double seconds) {
  const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(seconds);
  while (!pred() && ros::ok() && ros::WallTime::now() < deadline) ros::WallDuration(0.01).sleep();
  return pred();
}

}  // namespace

class TrackerStream : public ::testing::Test {
 protected:
  void SetUp() override {
    maneuver_pub_ = nh_.advertise<AttitudeManeuver>("maneuver", 1);
    torque_sub_ = nh_.subscribe<geometry_msgs::WrenchStamped>(
        "torque", 1000, [this](const geometry_msgs::WrenchStamped::ConstPtr& m) {
          std::lock_guard<std::mutex> lock(mutex_);
          torques_.push_back(*m);
        });
    reference_sub_ = nh_.subscribe<geometry_msgs::PoseStamped>(
        "reference_pose", 1000, [this](const geometry_msgs::PoseStamped::ConstPtr& m) {
          std::lock_guard<std::mutex> lock(mutex_);
          references_.push_back(*m);
        });
    error_sub_ = nh_.subscribe<std_msgs::Float64>("attitude_error", 1000,
                                                  [this](const std_msgs::Float64::ConstPtr& m) {
                                                    std::lock_guard<std::mutex> lock(mutex_);
                                                    errors_.push_back(m->data);
                                                  });
    cone_sub_ = nh_.subscribe<visualization_msgs::MarkerArray>(
        "constraint_markers", 10, [this](const visualization_msgs::MarkerArray::ConstPtr& m) {
          std::lock_guard<std::mutex> lock(mutex_);
          cones_ = m;
        });
    done_sub_ = nh_.subscribe<ReplayResult>("done", 10, [this](const ReplayResult::ConstPtr& m) {
      std::lock_guard<std::mutex> lock(mutex_);
      done_.push_back(*m);
    });
    ASSERT_TRUE(waitFor([&] { return maneuver_pub_.getNumSubscribers() > 0; }, 30.0));
    ASSERT_TRUE(waitFor([&] { return torque_sub_.getNumPublishers() > 0; }, 30.0));
  }
  /// Publishes `m` and waits for the `done` it causes: `done` is latched, so a subscriber made
  /// for this test may first receive the previous test's, stamped before this one was sent.
  ReplayResult run(const AttitudeManeuver& m) {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      torques_.clear();
      references_.clear();
      errors_.clear();
    }
    const ros::Time sent = ros::Time::now();
    maneuver_pub_.publish(m);
    const auto answered = [&] {
      std::lock_guard<std::mutex> lock(mutex_);
      return !done_.empty() && done_.back().header.stamp >= sent;
    };
    EXPECT_TRUE(waitFor(answered, 60.0)) << "no done message";
    ros::WallDuration(0.3).sleep();  // the last samples on the other topics
    std::lock_guard<std::mutex> lock(mutex_);
    return done_.empty() ? ReplayResult() : done_.back();
  }

  ros::NodeHandle nh_;
  ros::Publisher maneuver_pub_;
  ros::Subscriber torque_sub_, reference_sub_, error_sub_, cone_sub_, done_sub_;
  std::mutex mutex_;
  std::vector<geometry_msgs::WrenchStamped> torques_;
  std::vector<geometry_msgs::PoseStamped> references_;
  std::vector<double> errors_;
  visualization_msgs::MarkerArray::ConstPtr cones_;
  std::vector<ReplayResult> done_;
};

TEST_F(TrackerStream, FramesStampAndConstraintsComeFromTheMessage) {
  tf2_ros::Buffer tf_buffer(ros::Duration(60.0));
  tf2_ros::TransformListener listener(tf_buffer);
  Maneuver plan;
  AttitudeManeuver m = ros_testing::testManeuver(kSteps, &plan);
  m.header.frame_id = "map";
  m.child_frame_id = "base_link";
  m.header.stamp = ros::Time::now() + ros::Duration(2.0);  // in the future: t_0
  Constraint cone;
  cone.type = Constraint::KEEP_OUT;
  cone.body_axis.z = 1.0;
  cone.world_direction.x = 1.0;
  cone.half_angle = 0.4;
  m.constraints.push_back(cone);
  const ReplayResult done = run(m);
  ASSERT_TRUE(done.success) << done.message;
  EXPECT_EQ(done.mode, "replay");
  EXPECT_EQ(done.header.frame_id, "map");
  EXPECT_LT(done.terminal_attitude_error, 1e-12);  // its own plan, no effects: lands exactly

  std::lock_guard<std::mutex> lock(mutex_);
  ASSERT_FALSE(torques_.empty());
  EXPECT_EQ(torques_.front().header.stamp, m.header.stamp);  // t_0 = header.stamp exactly
  for (const auto& t : torques_) EXPECT_EQ(t.header.frame_id, "base_link");
  ASSERT_FALSE(references_.empty());
  EXPECT_EQ(references_.back().header.frame_id, "map");
  EXPECT_LT(so3::angleBetween(rc::attitudeFromMsg(references_.back().pose.orientation, "ref"),
                              plan.attitude.back()),
            1e-9);
  ASSERT_TRUE(tf_buffer.canTransform("map", "base_link", done.header.stamp, ros::Duration(5.0)));
  EXPECT_FALSE(tf_buffer._frameExists("body")) << "the default frame was published";
  ASSERT_TRUE(cones_) << "no constraint_markers for a maneuver that carries a keep_out cone";
  // The previous maneuver's cleared, the cone, its world direction (the Sun arrow); the body
  // axis is drawn per sample in the world frame (body_marker), needing no tf.
  ASSERT_EQ(cones_->markers.size(), 3u);
  EXPECT_EQ(cones_->markers[0].action, visualization_msgs::Marker::DELETEALL);
  EXPECT_EQ(cones_->markers[1].header.frame_id, "map");
  EXPECT_EQ(cones_->markers[1].ns, "keep_out");
  EXPECT_EQ(cones_->markers[2].header.frame_id, "map");
  EXPECT_EQ(cones_->markers[2].ns, "keep_out_direction");
  // Open loop on its own plan: the error topic reads zero to round-off all along.
  ASSERT_FALSE(errors_.empty());
  for (double e : errors_) EXPECT_LT(e, 1e-9);
}

TEST_F(TrackerStream, SamplesAreStreamedAtTheRateNotAtTheNodes) {
  Maneuver plan;
  const ReplayResult done = run(ros_testing::testManeuver(kSteps, &plan));
  ASSERT_TRUE(done.success) << done.message;
  const double expected = kRate * (kSteps * 0.1) / kRateFactor;  // 16 samples + the end
  std::lock_guard<std::mutex> lock(mutex_);
  EXPECT_GE(torques_.size(), 0.8 * expected);
  EXPECT_LE(torques_.size(), 1.2 * expected + 2);
  EXPECT_NE(torques_.size(), std::size_t(kSteps + 1));  // not one per node
  // A maneuver without cones after one with: the stale cones are deleted (a DELETEALL alone).
  ASSERT_TRUE(cones_);
  ASSERT_EQ(cones_->markers.size(), 1u);
  EXPECT_EQ(cones_->markers[0].action, visualization_msgs::Marker::DELETEALL);
  // Evenly spaced in ROS time, 1 / rate apart (the last one at T).
  for (std::size_t j = 1; j + 1 < torques_.size(); ++j) {
    EXPECT_NEAR((torques_[j].header.stamp - torques_[j - 1].header.stamp).toSec(), 1.0 / kRate,
                1e-6);
  }
}

TEST_F(TrackerStream, TimesThatDisagreeWithTheStepAreRefusedByNameAndTheNodeKeepsServing) {
  Maneuver plan;
  AttitudeManeuver bad = ros_testing::testManeuver(kSteps, &plan);
  bad.time[5] += 0.05;
  const ReplayResult refused = run(bad);
  EXPECT_FALSE(refused.success);
  EXPECT_NE(refused.message.find("maneuver.time[5]"), std::string::npos) << refused.message;
  const ReplayResult served = run(ros_testing::testManeuver(kSteps, &plan));
  EXPECT_TRUE(served.success) << served.message;
}

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_tracker_stream");
  ros::NodeHandle nh;
  ros::AsyncSpinner spinner(2);
  spinner.start();
  return RUN_ALL_TESTS();
}
