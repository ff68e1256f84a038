// rostest (tracker_constraint_health.test): constraint health of the tracker.
// - scenes/torque_limited.yaml re-planned with its torque limits active (/limited_replan) beside
//   the law alone (/limited_feedback): no failed re-plan and a terminal error no worse than
//   feedback's (before: 4 of 9 re-plans "infeasible" — planned from the body's rate at the node
//   where the paper scheme's Ω_0 is the first step's rate — and 28x feedback's error).
// - scenes/sun_keep_out.yaml's plan sent with its cone widened by 3e-3 rad (/cone_replan): the
//   body re-plans from ~3e-3 rad inside the cone; that start is projected onto the cone instead
//   of being refused by the planner ("initial.attitude: already violates constraints[0]"), and
//   `done` reports the worst keep_out violation of the published path, which the test computes
//   itself from `body_pose`.
#include <gtest/gtest.h>
#include <ros/ros.h>

#include <geometry_msgs/PoseStamped.h>
#include <tf2_msgs/TFMessage.h>

#include <mutex>

#include "attitude_planner/AttitudeManeuver.h"
#include "attitude_planner/ReplayResult.h"
#include "attitude_planner/io/scene.hpp"
#include "attitude_planner/planner.hpp"
#include "attitude_planner/ros/tracker_node.hpp"
#include "ros_test_helpers.hpp"

using namespace attitude_planner;

namespace {

/// The body attitudes a tracker publishes on `body_pose`, in order, and the newest /tf stamp of
/// its body frame.
class PoseRecorder {
 public:
  PoseRecorder(ros::NodeHandle& nh, std::string body_frame)
      : body_frame_(std::move(body_frame)),
        sub_(nh.subscribe("body_pose", 5000, &PoseRecorder::onPose, this)),
        tf_sub_(nh.subscribe("/tf", 1000, &PoseRecorder::onTf, this)) {}
  std::vector<Matrix3> attitudes() {
    std::lock_guard<std::mutex> lock(mutex_);
    return attitudes_;
  }
  ros::Time newestTf() {
    std::lock_guard<std::mutex> lock(mutex_);
    return newest_tf_;
  }

 private:
  void onPose(const geometry_msgs::PoseStamped::ConstPtr& m) {
    std::lock_guard<std::mutex> lock(mutex_);
    attitudes_.push_back(ros_conversions::attitudeFromMsg(m->pose.orientation, "body_pose"));
  }
  void onTf(const tf2_msgs::TFMessage::ConstPtr& m) {
    std::lock_guard<std::mutex> lock(mutex_);
    for (const geometry_msgs::TransformStamped& t : m->transforms) {
      if (t.child_frame_id == body_frame_) newest_tf_ = std::max(newest_tf_, t.header.stamp);
    }
  }
  std::string body_frame_;
  std::mutex mutex_;
  std::vector<Matrix3> attitudes_;
  ros::Time newest_tf_;
  ros::Subscriber sub_, tf_sub_;
};

/// /cone_replan's poses, subscribed from the start of the process (before its stream starts).
PoseRecorder* cone_poses = nullptr;

}  // namespace

TEST(TrackerConstraintHealth, ReplansWithActiveTorqueLimitsNoneFailedNoWorseThanFeedback) {
  ros::NodeHandle replan_nh("limited_replan"), feedback_nh("limited_feedback");
  ros_testing::DoneListener replan_done(replan_nh), feedback_done(feedback_nh);
  const ReplayResult::ConstPtr replanned = replan_done.wait(90.0);
  const ReplayResult::ConstPtr feedback = feedback_done.wait(30.0);
  ASSERT_TRUE(replanned && feedback) << "no done from both trackers";
  ASSERT_TRUE(feedback->success) << feedback->message;
  std::printf(
      "torque_limited.yaml: replan %d adopted, %d failed, terminal %.3g rad; feedback "
      "terminal %.3g rad\n",
      replanned->replans, replanned->replan_failures, replanned->terminal_attitude_error,
      feedback->terminal_attitude_error);
  EXPECT_TRUE(replanned->success) << replanned->message;
  EXPECT_EQ(replanned->replan_failures, 0) << replanned->replan_error;
  EXPECT_GE(replanned->replans, 1);
  EXPECT_LE(replanned->terminal_attitude_error, feedback->terminal_attitude_error)
      << replanned->message;
  // The per-axis limits are checked on the delivered torque, which the actuators saturate.
  ASSERT_EQ(replanned->constraint_names, std::vector<std::string>{"actuator_limits"});
  ASSERT_EQ(replanned->constraint_violations.size(), 1u);
  EXPECT_LE(replanned->constraint_violations[0], 1e-12);
}

TEST(TrackerConstraintHealth, ProjectsAStartInsideAConeAndReportsTheWorstViolationFlown) {
  // scenes/sun_keep_out.yaml's plan rides its cone (0.5 rad) around node 65; sent with the cone
  // widened by 3e-3 rad, the body there is ~3e-3 rad inside it: the planner refuses that start
  // ("initial.attitude: already violates constraints[0]"), the tracker moves it onto the cone
  // (~projection_tolerance 0.01 rad) and the re-plan goes around the wider cone.
  std::string scene_path;
  ASSERT_TRUE(ros::param::get("~scene", scene_path));
  Scene scene = loadScene(scene_path);
  const PlanResult plan = planManeuver(scene.problem);
  ASSERT_TRUE(plan.converged()) << plan.message();
  constexpr double kWidening = 3e-3;  // [rad]
  PlanningConstraint& cone = scene.problem.constraints.at(0);
  cone.half_angle += kWidening;
  ASSERT_LT(coneMargin(cone, plan.maneuver.attitude[65]), -0.5 * kWidening);  // inside there

  ros::NodeHandle nh("cone_replan");
  ros_testing::DoneListener done(nh);
  ros::Publisher maneuver_pub = nh.advertise<AttitudeManeuver>("maneuver", 1, true);
  const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(30.0);
  while (maneuver_pub.getNumSubscribers() == 0 && ros::WallTime::now() < deadline)
    ros::WallDuration(0.05).sleep();
  ASSERT_GT(maneuver_pub.getNumSubscribers(), 0u) << "no tracker on /cone_replan/maneuver";
  maneuver_pub.publish(ros_conversions::maneuverToMsg(plan.maneuver, scene.problem, "", "",
                                                      ros::Time::now() + ros::Duration(1.0)));
  const ReplayResult::ConstPtr result = done.wait(60.0);
  ASSERT_TRUE(result) << "no done from /cone_replan";
  EXPECT_TRUE(result->success) << result->message;
  EXPECT_EQ(result->replan_failures, 0) << result->replan_error;
  EXPECT_EQ(result->projected_replans, 1) << result->message;
  EXPECT_EQ(result->replans, 1) << result->message;
  ASSERT_EQ(result->constraint_names, std::vector<std::string>{"keep_out"});
  ASSERT_EQ(result->constraint_violations.size(), 1u);

  // The test's own worst violation over the published attitudes (every sample: the maneuver
  // started 1 s after the test had subscribed) is done's value to round-off.
  const std::vector<double> times =
      sampleTimes(scene.problem.duration, scene.problem.steps, 50.0, 6.0);
  ros::WallDuration(0.5).sleep();  // the last samples' delivery
  const std::vector<Matrix3> attitudes = cone_poses->attitudes();
  ASSERT_EQ(attitudes.size(), times.size()) << "body_pose samples missed";
  double worst = 0.0;
  for (const Matrix3& R : attitudes) worst = std::max(worst, -coneMargin(cone, R));
  std::printf(
      "widened sun_keep_out.yaml: worst keep_out violation flown %.3g rad (done %.3g "
      "rad), %d projected re-plans; %s\n",
      worst, result->constraint_violations[0], result->projected_replans, result->message.c_str());
  EXPECT_GT(worst, 0.5 * kWidening);  // the body flew inside the widened cone, as the plan did
  EXPECT_NEAR(result->constraint_violations[0], worst, 1e-9);
  EXPECT_NE(result->message.find("past constraints along the flown path: keep_out by"),
            std::string::npos)
      << result->message;
  // After the run the body's frame stays in tf at its final attitude (a condition: a transform
  // stamped a second after the last sample arrives).
  const ros::Time after = result->header.stamp + ros::Duration(1.0);
  const ros::WallTime give_up = ros::WallTime::now() + ros::WallDuration(15.0);
  while (cone_poses->newestTf() <= after && ros::WallTime::now() < give_up)
    ros::WallDuration(0.02).sleep();
  EXPECT_GT(cone_poses->newestTf(), after) << "no tf of cone_replan/body after the run";
}

int main(int argc, char** argv) {
  testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_tracker_constraint_health");
  ros::AsyncSpinner spinner(1);
  spinner.start();
  ros::NodeHandle cone_nh("cone_replan");
  PoseRecorder poses(cone_nh, "cone_replan/body");
  cone_poses = &poses;
  return RUN_ALL_TESTS();
}
