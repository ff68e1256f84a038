// rostest: attitude_tracker_node plans the seed scene at start-up (~scene; through the planner
// service or in-process, per launch file) and replays it; the final tf must be the scene's R_N
// (for a pointing scene: aim its boresight at its direction).
#include <gtest/gtest.h>
#include <ros/ros.h>
#include <vector>

#include <ros/topic.h>
#include <tf2_ros/transform_listener.h>
#include <visualization_msgs/MarkerArray.h>

#include "attitude_planner/ReplayResult.h"
#include "attitude_planner/ros/conversions.hpp"
#include "ros_test_helpers.hpp"

using namespace attitude_planner;
namespace rc = attitude_planner::ros_conversions;

TEST(TrackerScene, FinalTransformIsTheScenesTargetAttitude) {
  ros::NodeHandle nh;
  tf2_ros::Buffer tf_buffer(ros::Duration(60.0));
  tf2_ros::TransformListener listener(tf_buffer);
  ros_testing::DoneListener listener_done(nh);
  const ReplayResult::ConstPtr done = listener_done.wait(90.0);
  ASSERT_TRUE(done) << "no done message";
  ASSERT_TRUE(done->success) << done->message;
  // The replay integrates the plan's own discrete equations (to round-off), except fourth_order's
  // cubic hold on the continuous body (RKMK4, O(h⁴)): its launch file widens both tolerances.
  ros::NodeHandle private_nh("~");
  const double replay_tolerance = private_nh.param("replay_tolerance", 1e-12);
  const double target_tolerance = private_nh.param("target_tolerance", 1e-8);
  EXPECT_EQ(done->steps, 128);
  EXPECT_GT(done->plan_solve_time, 0.0);  // the tracker asked for the plan [s]
  EXPECT_GT(done->plan_cost, 0.0);
  EXPECT_NEAR(done->cost, done->plan_cost, 1e-9 * done->plan_cost);
  EXPECT_LT(done->terminal_attitude_error, replay_tolerance);  // replay vs plan [rad]
  // scenes/rest_to_rest.yaml: R_N = exp(π/3 e1^).
  const Matrix3 target = so3::fromAxisAngle(Vector3::UnitX(), M_PI / 3);
  const ros::WallTime tf_deadline = ros::WallTime::now() + ros::WallDuration(10.0);
  while (!tf_buffer.canTransform("world", "body", done->header.stamp) &&
         ros::WallTime::now() < tf_deadline) {
    ros::WallDuration(0.05).sleep();
  }
  const geometry_msgs::TransformStamped tf =
      tf_buffer.lookupTransform("world", "body", done->header.stamp);
  const Matrix3 flown = rc::attitudeFromMsg(tf.transform.rotation, "tf");
  // A pointing scene (~pointing_body_axis, ~pointing_world_direction): the boresight is aimed,
  // the twist about it is the planner's.
  std::vector<double> b, d;
  if (private_nh.getParam("pointing_body_axis", b) &&
      private_nh.getParam("pointing_world_direction", d)) {
    ASSERT_EQ(b.size(), 3u);
    ASSERT_EQ(d.size(), 3u);
    const Vector3 aimed = flown * Vector3(b[0], b[1], b[2]).normalized();
    const Vector3 direction = Vector3(d[0], d[1], d[2]).normalized();
    EXPECT_LT((aimed - direction).norm(), target_tolerance);
    // `done` reports the pointing error of the flown body, and the target direction is drawn
    // (latched with the maneuver's world markers), along d.
    EXPECT_NEAR(done->pointing_error,
                std::atan2(aimed.cross(direction).norm(), aimed.dot(direction)), 1e-9);
    const auto world = ros::topic::waitForMessage<visualization_msgs::MarkerArray>(
        "constraint_markers", nh, ros::Duration(10.0));
    ASSERT_TRUE(world) << "no constraint_markers";
    int targets = 0;
    for (const visualization_msgs::Marker& m : world->markers) {
      if (m.ns != "pointing_target") continue;
      ++targets;
      ASSERT_EQ(m.points.size(), 2u);
      const Vector3 tip(m.points[1].x, m.points[1].y, m.points[1].z);
      EXPECT_LT((tip.normalized() - direction).norm(), 1e-12);
    }
    EXPECT_EQ(targets, 1);
    return;
  }
  EXPECT_EQ(done->pointing_error, 0.0);  // not a pointing scene
  EXPECT_LT(so3::angleBetween(flown, target), target_tolerance);
}

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_tracker_scene");
  ros::AsyncSpinner spinner(2);
  spinner.start();
  return RUN_ALL_TESTS();
}
