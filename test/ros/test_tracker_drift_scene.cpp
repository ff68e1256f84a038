// rostest: attitude_tracker_node plans a drift + two-input scene (~scene with system:
// drift_two_input, through plan_drift_two_input) and replays its controls open loop; the final
// tf must be the scene's g1, `control` must carry (u1, u2, 0), streamed at ~rate.
#include <gtest/gtest.h>
#include <ros/ros.h>

#include <geometry_msgs/Vector3Stamped.h>
#include <tf2_ros/transform_listener.h>

#include <mutex>

#include "attitude_planner/ReplayResult.h"
#include "attitude_planner/ros/conversions.hpp"
#include "ros_test_helpers.hpp"

using namespace attitude_planner;
namespace rc = attitude_planner::ros_conversions;

TEST(TrackerDriftScene, FinalTransformIsTheScenesTargetAttitude) {
  ros::NodeHandle nh;
  tf2_ros::Buffer tf_buffer(ros::Duration(60.0));
  tf2_ros::TransformListener listener(tf_buffer);
  std::mutex mutex;
  ros_testing::DoneListener listener_done(nh);
  int controls = 0;
  double max_abs_z = 0.0, max_abs_u = 0.0;
  ros::Subscriber control_sub = nh.subscribe<geometry_msgs::Vector3Stamped>(
      "control", 2000, [&](const geometry_msgs::Vector3Stamped::ConstPtr& m) {
        std::lock_guard<std::mutex> lock(mutex);
        ++controls;
        max_abs_z = std::max(max_abs_z, std::abs(m->vector.z));
        max_abs_u = std::max(max_abs_u, std::hypot(m->vector.x, m->vector.y));
      });
  const ReplayResult::ConstPtr done = listener_done.wait(45.0);
  ASSERT_TRUE(done) << "no done message";
  ASSERT_TRUE(done->success) << done->message;
  EXPECT_EQ(done->steps, 1000);
  EXPECT_NEAR(done->duration, 3.0, 1e-12);
  EXPECT_GT(done->plan_solve_time, 0.0);  // the tracker asked for the plan [s]
  // Trapezoid cost of the samples vs the planner's quadrature: agree to O(h²).
  EXPECT_NEAR(done->cost, done->plan_cost, 1e-4 * done->plan_cost);
  EXPECT_LT(done->terminal_attitude_error, 1e-8);  // replay vs plan [rad]
  EXPECT_EQ(done->terminal_velocity_error, 0.0);   // not a boundary condition here
  const Matrix3 target = so3::fromAxisAngle(Vector3(1, 1, 0), 1.2);  // the scene's g1
  EXPECT_LT(so3::angleBetween(rc::attitudeFromMsg(done->final_attitude, "final"), target), 1e-8);
  const ros::WallTime tf_deadline = ros::WallTime::now() + ros::WallDuration(10.0);
  while (!tf_buffer.canTransform("world", "body", done->header.stamp) &&
         ros::WallTime::now() < tf_deadline) {
    ros::WallDuration(0.05).sleep();
  }
  const geometry_msgs::TransformStamped tf =
      tf_buffer.lookupTransform("world", "body", done->header.stamp);
  const double tf_error =
      so3::angleBetween(rc::attitudeFromMsg(tf.transform.rotation, "tf"), target);
  RecordProperty("final_tf_error_rad", std::to_string(tf_error));
  std::printf("final tf error %.3g rad, replay vs plan %.3g rad\n", tf_error,
              done->terminal_attitude_error);
  EXPECT_LT(tf_error, 1e-8);
  std::lock_guard<std::mutex> lock(mutex);
  // Streamed at ~rate (50 Hz of ROS time, rate factor 4: one sample per 0.08 s of the 3 s, plus
  // T: 39), not at the plan's 1001 nodes.
  EXPECT_GE(controls, 0.8 * 50.0 * 3.0 / 4.0);
  EXPECT_LE(controls, 1.2 * 50.0 * 3.0 / 4.0 + 2);
  EXPECT_EQ(max_abs_z, 0.0);  // (u1, u2, 0)
  EXPECT_GT(max_abs_u, 0.1);  // the controls are not all zero
}

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_tracker_drift_scene");
  ros::AsyncSpinner spinner(2);
  spinner.start();
  return RUN_ALL_TESTS();
}
