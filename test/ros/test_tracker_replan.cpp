// rostest (tracker_replan.test): ~mode replan. scenes/disturbed_replay.yaml at N = 1200 (gravity
// gradient and a disturbance, planned for; actuator noise, not) re-planned through the planner
// node's service every 60 s of its 600 s (/replan), beside the same plan flown by the law alone
// (/feedback); and a tracker whose re-plans all fail (/orphan: no planner in its namespace).
#include <gtest/gtest.h>
#include <ros/ros.h>

#include <geometry_msgs/WrenchStamped.h>

#include <atomic>

#include "attitude_planner/AttitudeManeuver.h"
#include "attitude_planner/ReplayResult.h"
#include "ros_test_helpers.hpp"

using namespace attitude_planner;

TEST(TrackerReplan, ReplansThroughTheServiceWithoutStallingTheStreamAndLandsAsFeedbackDoes) {
  ros::NodeHandle replan_nh("replan"), feedback_nh("feedback");
  std::atomic<int> samples{0};
  ros::Subscriber torque_sub = replan_nh.subscribe<geometry_msgs::WrenchStamped>(
      "torque", 2000, [&](const geometry_msgs::WrenchStamped::ConstPtr&) { ++samples; });
  ros_testing::DoneListener replan_done(replan_nh), feedback_done(feedback_nh);
  const ReplayResult::ConstPtr replanned = replan_done.wait(200.0);
  const ReplayResult::ConstPtr feedback = feedback_done.wait(30.0);
  ASSERT_TRUE(replanned && feedback) << "no done from both trackers";
  ASSERT_TRUE(replanned->success) << replanned->message;
  ASSERT_TRUE(feedback->success) << feedback->message;
  EXPECT_EQ(replanned->mode, "replan");
  std::printf(
      "%s\nterminal attitude error: replan %.3g rad, feedback %.3g rad; rate error: replan %.3g "
      "rad/s, feedback %.3g rad/s; effort: replan %.5g, feedback %.5g N^2 m^2 s; %d samples "
      "during re-plans\n",
      replanned->message.c_str(), replanned->terminal_attitude_error,
      feedback->terminal_attitude_error, replanned->terminal_velocity_error,
      feedback->terminal_velocity_error, replanned->effort, feedback->effort,
      replanned->samples_during_replans);
  // Re-plans were made and flown (from nodes 120, 240, ..., 1080 of 1200: up to 9; one still in
  // flight at the end is not adopted), none failed.
  EXPECT_GE(replanned->replans, 1);
  EXPECT_LE(replanned->replans, 9);
  EXPECT_EQ(replanned->replan_failures, 0) << replanned->replan_error;
  // The stream did not wait for the planner: samples went out while a re-plan was in flight
  // (a service call made in the streaming thread would leave this at 0).
  EXPECT_GE(replanned->samples_during_replans, 1);
  // Every sample was published: rate · T / rate_factor = 200 · 600 / 100 = 1200, plus T itself.
  ros::WallDuration(0.5).sleep();
  EXPECT_EQ(samples, 1201);
  // Each re-plan starts from the body's own state (as the scheme's boundary data), to the same
  // target under the same effects: the body lands as the law alone makes it land, far inside the
  // open loop's ~1e-3 rad miss (tracking_study: 3.45e-6 against feedback's 3.41e-6 at N = 1200;
  // docs/ros_tracker.md). Bound: 1e-4 rad, or 3x feedback's should that be larger (a tenth of
  // the open loop's miss): adoption timing under load moves it.
  EXPECT_LT(replanned->terminal_attitude_error,
            std::max(3.0 * feedback->terminal_attitude_error, 1e-4));
  EXPECT_LT(replanned->terminal_velocity_error, 1e-3);  // [rad/s], a slew of ~5e-3 rad/s
  EXPECT_GT(replanned->effort, 0.5 * feedback->effort);
  EXPECT_LT(replanned->effort, 1.5 * feedback->effort);
}

TEST(TrackerReplan, AFailedReplanKeepsThePlanInForce) {
  ros::NodeHandle orphan_nh("orphan");
  ros_testing::DoneListener done(orphan_nh);
  ros::Publisher pub = orphan_nh.advertise<AttitudeManeuver>("maneuver", 1, true);
  Maneuver plan;
  const AttitudeManeuver msg = ros_testing::testManeuver(40, &plan);  // h = 0.1 s, T = 4 s
  pub.publish(msg);
  const ReplayResult::ConstPtr result = done.wait(120.0);
  ASSERT_TRUE(result) << "no done from /orphan";
  ASSERT_TRUE(result->success) << result->message;
  EXPECT_EQ(result->mode, "replan");
  // Re-plans from nodes 10, 20, 30 (period 1 s = 10 steps; 4 steps at least must be left): all
  // fail (no /orphan/plan_attitude_maneuver), the first error kept, none adopted.
  EXPECT_EQ(result->replans, 0);
  EXPECT_GE(result->replan_failures, 1);
  EXPECT_LE(result->replan_failures, 3);
  EXPECT_NE(result->replan_error.find("orphan/plan_attitude_maneuver"), std::string::npos)
      << result->replan_error;
  // The plan in force was flown by the law to its end: no effects, so it lands (the law's
  // sampled control on a paper plan: a small discretization miss, not a failure).
  EXPECT_LT(result->terminal_attitude_error, 1e-2) << result->message;
}

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_tracker_replan");
  ros::NodeHandle nh;
  ros::AsyncSpinner spinner(2);
  spinner.start();
  return RUN_ALL_TESTS();
}
