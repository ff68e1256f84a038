// rostest: attitude_tracker_node with a ~scene that has a keep_out cone (scenes/sun_keep_out.yaml,
// planned through the planner service): `constraint_markers` carries the cone (world frame, apex
// at the origin, axis the world direction, the half angle at every rim point) and its direction,
// `body_marker` the constrained body axis (world frame, every sample), and the plan it replays is
// the constrained one.
#include <gtest/gtest.h>
#include <ros/ros.h>

#include <visualization_msgs/MarkerArray.h>
#include <mutex>
#include <vector>

#include "attitude_planner/io/scene.hpp"
#include "attitude_planner/planner.hpp"
#include "attitude_planner/ros/conversions.hpp"
#include "ros_test_helpers.hpp"

using namespace attitude_planner;
namespace rc = attitude_planner::ros_conversions;

namespace {

constexpr double kPathRadius = 1.2;  // tracker's ~path_radius default [m]: the cone's slant

Scene testScene() {
  std::string path;
  EXPECT_TRUE(ros::param::get("~scene", path)) << "test parameter ~scene missing";
  return loadScene(path);
}

Vector3 vec(const geometry_msgs::Point& p) {
  return Vector3(p.x, p.y, p.z);
}

}  // namespace

TEST(TrackerConstraints, ConeAndBodyAxisMarkersHaveTheConstraintsGeometry) {
  const Scene scene = testScene();
  ASSERT_EQ(scene.problem.constraints.size(), 1u);
  const PlanningConstraint& cone = scene.problem.constraints[0];
  ros::NodeHandle nh;
  std::mutex mutex;
  visualization_msgs::MarkerArray::ConstPtr got;
  ros::Subscriber sub = nh.subscribe<visualization_msgs::MarkerArray>(
      "constraint_markers", 1, [&](const visualization_msgs::MarkerArray::ConstPtr& m) {
        std::lock_guard<std::mutex> lock(mutex);
        got = m;
      });
  const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(60.0);
  while (ros::WallTime::now() < deadline) {
    {
      std::lock_guard<std::mutex> lock(mutex);
      if (got) break;
    }
    ros::WallDuration(0.05).sleep();
  }
  std::lock_guard<std::mutex> lock(mutex);
  ASSERT_TRUE(got) << "no constraint_markers";
  // A DELETEALL first (the previous maneuver's cones go), then the cone and its world direction.
  ASSERT_EQ(got->markers.size(), 3u);
  EXPECT_EQ(got->markers[0].action, visualization_msgs::Marker::DELETEALL);
  const visualization_msgs::Marker& c = got->markers[1];
  EXPECT_EQ(c.header.frame_id, "world");
  EXPECT_EQ(c.ns, "keep_out");
  EXPECT_EQ(c.type, visualization_msgs::Marker::TRIANGLE_LIST);
  ASSERT_GE(c.points.size(), 3u * 16);
  ASSERT_EQ(c.points.size() % 3, 0u);
  Vector3 rim_sum = Vector3::Zero();
  for (std::size_t i = 0; i < c.points.size(); ++i) {
    const Vector3 p = vec(c.points[i]);
    if (i % 3 == 0) {  // every triangle's apex: the body origin
      EXPECT_EQ(p, Vector3::Zero()) << i;
      continue;
    }
    EXPECT_NEAR(p.norm(), kPathRadius, 1e-12) << i;
    const double angle =
        std::atan2(p.cross(cone.world_direction).norm(), p.dot(cone.world_direction));
    EXPECT_NEAR(angle, cone.half_angle, 1e-12) << i;  // on the cone's surface
    rim_sum += p;
  }
  // Rim points spread evenly around the axis: their mean lies on the world direction.
  EXPECT_LT((rim_sum.normalized() - cone.world_direction).norm(), 1e-9);
  const visualization_msgs::Marker& a = got->markers[2];  // the Sun arrow
  EXPECT_EQ(a.header.frame_id, "world");
  EXPECT_EQ(a.ns, "keep_out_direction");
  EXPECT_EQ(a.type, visualization_msgs::Marker::ARROW);
  ASSERT_EQ(a.points.size(), 2u);
  EXPECT_EQ(vec(a.points[0]), Vector3::Zero());
  EXPECT_LT((vec(a.points[1]).normalized() - cone.world_direction.normalized()).norm(), 1e-12);
}

TEST(TrackerConstraints, TheConstrainedBodyAxisIsDrawnInTheWorldAtEverySample) {
  // Drawn from the body's attitude in the world frame, so rviz needs no transform of the body
  // frame for it (before: a frame-locked arrow in the body frame, latched before tf had that
  // frame, never drawn). Along the constrained plan it stays outside the cone.
  const Scene scene = testScene();
  const PlanningConstraint& cone = scene.problem.constraints[0];
  ros::NodeHandle nh;
  std::mutex mutex;
  std::vector<visualization_msgs::Marker> axes;
  ros::Subscriber sub = nh.subscribe<visualization_msgs::MarkerArray>(
      "body_marker", 100, [&](const visualization_msgs::MarkerArray::ConstPtr& array) {
        std::lock_guard<std::mutex> lock(mutex);
        for (const visualization_msgs::Marker& m : array->markers) {
          if (m.ns == "keep_out_body_axis") axes.push_back(m);
        }
      });
  const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(60.0);
  while (ros::WallTime::now() < deadline) {
    {
      std::lock_guard<std::mutex> lock(mutex);
      if (axes.size() >= 20) break;
    }
    ros::WallDuration(0.05).sleep();
  }
  std::lock_guard<std::mutex> lock(mutex);
  ASSERT_GE(axes.size(), 20u) << "the constrained body axis is not streamed on body_marker";
  for (const visualization_msgs::Marker& a : axes) {
    EXPECT_EQ(a.header.frame_id, "world");
    EXPECT_FALSE(a.frame_locked);
    ASSERT_EQ(a.points.size(), 2u);
    const Vector3 tip = vec(a.points[1]);
    EXPECT_NEAR(tip.norm(), kPathRadius, 1e-9);
    const double angle =
        std::atan2(tip.cross(cone.world_direction).norm(), tip.dot(cone.world_direction));
    EXPECT_GE(angle, cone.half_angle - 1e-6);  // the constrained plan keeps out of the cone
  }
}

TEST(TrackerConstraints, TheServicePlanIsTheConstrainedOne) {
  // The tracker's request carries the cone: its plan costs what planManeuver's constrained plan
  // of the same scene costs in-process, and the replay lands.
  ros::NodeHandle nh;
  ros_testing::DoneListener listener(nh);
  const ReplayResult::ConstPtr done = listener.wait(90.0);
  ASSERT_TRUE(done) << "no done message";
  ASSERT_TRUE(done->success) << done->message;
  const Scene scene = testScene();
  const PlanResult in_process = planManeuver(scene.problem);
  ASSERT_TRUE(in_process.converged()) << in_process.message();
  EXPECT_EQ(in_process.solver, "interior_point");  // the cone binds
  EXPECT_NEAR(done->plan_cost, in_process.cost, 1e-9 * in_process.cost);
  EXPECT_LT(done->terminal_attitude_error, 1e-9);
}

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_tracker_constraints");
  ros::AsyncSpinner spinner(2);
  spinner.start();
  return RUN_ALL_TESTS();
}
