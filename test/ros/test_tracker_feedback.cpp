// rostest: the same plan of scenes/disturbed_replay.yaml (gravity gradient and a disturbance,
// planned for; actuator noise, not) driven open loop (/replay) and with the tracking law
// (/feedback), two trackers side by side in their own namespaces (tracker_feedback.test). The
// closed loop's terminal errors are an order of magnitude below the open loop's. Each tracker
// publishes its own body transform (replay/body, feedback/body: the namespace's default) and holds
// the final attitude there after its run; two more given one body frame (twin) both report the
// other and fail their runs.
#include <gtest/gtest.h>
#include <ros/ros.h>

#include <geometry_msgs/WrenchStamped.h>
#include <std_msgs/Float64.h>
#include <tf2_msgs/TFMessage.h>

#include <atomic>
#include <map>
#include <mutex>
#include <set>

#include "attitude_planner/ReplayResult.h"
#include "ros_test_helpers.hpp"

using namespace attitude_planner;

TEST(TrackerFeedback, ClosedLoopTerminalErrorsAreAnOrderOfMagnitudeBelowOpenLoop) {
  ros::NodeHandle replay_nh("replay"), feedback_nh("feedback");
  std::atomic<int> samples{0}, error_samples{0};
  ros::Subscriber torque_sub = feedback_nh.subscribe<geometry_msgs::WrenchStamped>(
      "torque", 1000, [&](const geometry_msgs::WrenchStamped::ConstPtr&) { ++samples; });
  ros::Subscriber error_sub = feedback_nh.subscribe<std_msgs::Float64>(
      "attitude_error", 1000, [&](const std_msgs::Float64::ConstPtr&) { ++error_samples; });
  // Who publishes which body transform on /tf: each tracker its own (both published
  // world -> body before the default body frame came from the namespace).
  std::mutex tf_mutex;
  std::map<std::string, std::set<std::string>> publishers_of;  // child frame -> publishers
  using TfEvent = const ros::MessageEvent<tf2_msgs::TFMessage const>&;
  ros::Subscriber tf_sub = replay_nh.subscribe<tf2_msgs::TFMessage, TfEvent>(
      "/tf", 1000, boost::function<void(TfEvent)>([&](TfEvent event) {
        std::lock_guard<std::mutex> lock(tf_mutex);
        for (const auto& t : event.getMessage()->transforms)
          publishers_of[t.child_frame_id].insert(event.getPublisherName());
      }));
  // After its run a tracker holds the final attitude on /tf (every 0.1 s): transforms of
  // feedback/body counted from its done on.
  std::atomic<bool> feedback_ended{false};
  std::atomic<int> held_after_done{0};
  ros::Subscriber held_sub = feedback_nh.subscribe<tf2_msgs::TFMessage>(
      "/tf", 1000, [&](const tf2_msgs::TFMessage::ConstPtr& m) {
        for (const auto& t : m->transforms) {
          if (t.child_frame_id == "feedback/body" && feedback_ended) ++held_after_done;
        }
      });
  ros::NodeHandle twin_a_nh("twin_a"), twin_b_nh("twin_b");
  ros_testing::DoneListener twin_a_done(twin_a_nh), twin_b_done(twin_b_nh);
  ros_testing::DoneListener replay_done(replay_nh), feedback_done(feedback_nh);
  const ReplayResult::ConstPtr open_loop = replay_done.wait(120.0);
  const ReplayResult::ConstPtr closed_loop = feedback_done.wait(120.0);
  feedback_ended = true;
  ASSERT_TRUE(open_loop && closed_loop) << "no done from both trackers";
  ASSERT_TRUE(open_loop->success) << open_loop->message;
  ASSERT_TRUE(closed_loop->success) << closed_loop->message;
  EXPECT_EQ(open_loop->mode, "replay");
  EXPECT_EQ(closed_loop->mode, "feedback");
  std::printf(
      "terminal attitude error: replay %.3g rad, feedback %.3g rad; rate error: replay "
      "%.3g rad/s, feedback %.3g rad/s; effort: replay %.4g, feedback %.4g N^2 m^2 s\n",
      open_loop->terminal_attitude_error, closed_loop->terminal_attitude_error,
      open_loop->terminal_velocity_error, closed_loop->terminal_velocity_error, open_loop->effort,
      closed_loop->effort);
  // The noise matters open loop (~1e-3 rad, docs/ros_tracker.md) ...
  EXPECT_GT(open_loop->terminal_attitude_error, 1e-3);
  // ... and the law removes most of it. (The terminal rate errors are both ~1e-5 rad/s, the
  // closed loop's set by the reference's interpolation: reported, not compared.)
  EXPECT_LT(closed_loop->terminal_attitude_error, 0.1 * open_loop->terminal_attitude_error);
  EXPECT_LT(closed_loop->terminal_velocity_error, 1e-3);  // [rad/s], against a slew of ~5e-3 rad/s
  // Feedback pays for the correction, a little: the same effort to within a few percent.
  EXPECT_GT(closed_loop->effort, 0.5 * open_loop->effort);
  EXPECT_LT(closed_loop->effort, 1.5 * open_loop->effort);
  // The stream: about rate · T / rate_factor samples (tracker_feedback.test: 10 Hz, T = 600 s,
  // rate factor 200: 30), loose; the error topic with every sample.
  const double expected = 10.0 * 600.0 / 200.0;
  ros::WallDuration(0.5).sleep();
  EXPECT_GE(samples, 0.8 * expected);
  EXPECT_LE(samples, 1.2 * expected + 2);
  EXPECT_EQ(error_samples, samples);
  // Two trackers on one body frame: both runs fail, each naming the other node and the frame.
  for (ros_testing::DoneListener* twin : {&twin_a_done, &twin_b_done}) {
    const ReplayResult::ConstPtr done = twin->wait(120.0);
    ASSERT_TRUE(done) << "no done from a twin";
    EXPECT_FALSE(done->success) << done->message;
    EXPECT_NE(done->message.find("also publishes the transform world -> twin"), std::string::npos)
        << done->message;
  }
  ros::WallDuration(0.5).sleep();
  EXPECT_GE(held_after_done, 2) << "the final attitude is not held on /tf after the run";
  std::lock_guard<std::mutex> lock(tf_mutex);
  EXPECT_EQ(publishers_of.count("replay/body"), 1u);
  EXPECT_EQ(publishers_of.count("feedback/body"), 1u);
  EXPECT_EQ(publishers_of["twin"].size(), 2u);
  for (const auto& [frame, publishers] : publishers_of) {
    if (frame == "twin") continue;
    EXPECT_EQ(publishers.size(), 1u) << publishers.size() << " nodes publish " << frame;
  }
}

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_tracker_feedback");
  ros::NodeHandle nh;
  ros::AsyncSpinner spinner(2);
  spinner.start();
  return RUN_ALL_TESTS();
}
