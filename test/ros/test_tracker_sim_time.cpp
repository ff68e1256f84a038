// rostest: attitude_tracker_node on simulated time (/use_sim_time, /clock published here, as
// `rosbag play --clock` does): every stamp is a /clock time, spaced by t_k / rate_factor.
#include <gtest/gtest.h>
#include <ros/ros.h>

#include <geometry_msgs/WrenchStamped.h>
#include <rosgraph_msgs/Clock.h>
#include <tf2_ros/transform_listener.h>

#include <atomic>
#include <mutex>
#include <thread>

#include "attitude_planner/ReplayResult.h"
#include "ros_test_helpers.hpp"

using namespace attitude_planner;
namespace rc = attitude_planner::ros_conversions;

TEST(TrackerSimTime, StampsFollowTheClockAndTheReplayEndsAtRN) {
  const int N = 32;
  const double rate_factor = 2.0;       // must match the launch file
  const ros::Time clock_start(1000.0);  // [s] simulated
  ros::NodeHandle nh;
  ASSERT_TRUE(ros::Time::isSimTime()) << "/use_sim_time must be true";

  // The clock: 10 ms of simulated time every 2 ms of wall time, in its own thread.
  ros::Publisher clock_pub = nh.advertise<rosgraph_msgs::Clock>("/clock", 10);
  std::atomic<bool> stop{false};
  std::thread clock_thread([&] {
    rosgraph_msgs::Clock c;
    c.clock = clock_start;
    while (!stop && ros::ok()) {
      clock_pub.publish(c);
      c.clock += ros::Duration(0.01);
      ros::WallDuration(0.002).sleep();
    }
  });

  tf2_ros::Buffer tf_buffer(ros::Duration(600.0));
  tf2_ros::TransformListener listener(tf_buffer);
  std::mutex mutex;
  std::vector<ros::Time> stamps;
  ReplayResult::ConstPtr done;
  ros::Subscriber torque_sub = nh.subscribe<geometry_msgs::WrenchStamped>(
      "torque", 100, [&](const geometry_msgs::WrenchStamped::ConstPtr& m) {
        std::lock_guard<std::mutex> lock(mutex);
        stamps.push_back(m->header.stamp);
      });
  ros::Subscriber done_sub =
      nh.subscribe<ReplayResult>("done", 1, [&](const ReplayResult::ConstPtr& m) {
        std::lock_guard<std::mutex> lock(mutex);
        done = m;
      });
  ros::Publisher maneuver_pub = nh.advertise<AttitudeManeuver>("maneuver", 1);
  auto waitFor = [](auto pred, double seconds) {
    const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(seconds);
    while (!pred() && ros::WallTime::now() < deadline) ros::WallDuration(0.01).sleep();
    return pred();
  };
  ASSERT_TRUE(waitFor([&] { return maneuver_pub.getNumSubscribers() > 0; }, 30.0));
  ASSERT_TRUE(waitFor([&] { return torque_sub.getNumPublishers() > 0; }, 30.0));
  ASSERT_TRUE(waitFor([&] { return !ros::Time::now().isZero(); }, 30.0)) << "no /clock";

  Maneuver plan;
  maneuver_pub.publish(ros_testing::testManeuver(N, &plan));
  ASSERT_TRUE(waitFor(
      [&] {
        std::lock_guard<std::mutex> lock(mutex);
        return bool(done);
      },
      60.0))
      << "no done message";
  ASSERT_TRUE(done->success) << done->message;
  std::vector<ros::Time> s;
  {
    std::lock_guard<std::mutex> lock(mutex);
    s = stamps;
  }
  ASSERT_EQ(s.size(), size_t(N + 1));
  EXPECT_GE(s.front(), clock_start);  // simulated, not wall, time
  EXPECT_LT(s.back(), clock_start + ros::Duration(3600.0));
  for (int k = 0; k <= N; ++k) {  // t_k / rate_factor after step 0 (to the nanosecond)
    EXPECT_NEAR((s[k] - s[0]).toSec(), plan.time[k] / rate_factor, 2e-9) << "k = " << k;
  }
  EXPECT_EQ(done->header.stamp, s.back());
  ASSERT_TRUE(waitFor([&] { return tf_buffer.canTransform("world", "body", s.back()); }, 10.0));
  const geometry_msgs::TransformStamped tf = tf_buffer.lookupTransform("world", "body", s.back());
  EXPECT_LT(
      so3::angleBetween(rc::attitudeFromMsg(tf.transform.rotation, "tf"), plan.attitude.back()),
      1e-9);
  stop = true;
  clock_thread.join();
}

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_tracker_sim_time");
  ros::AsyncSpinner spinner(2);
  spinner.start();
  return RUN_ALL_TESTS();
}
