// rostest: feeds attitude_tracker_node a maneuver on `maneuver` and checks what it publishes
// (tf, torque, done) and what `rosbag record` wrote (read back with the rosbag C++ API).
// The maneuver is simulated here from known torques, so this test needs no planner.
#include <gtest/gtest.h>
#include <ros/ros.h>

#include <geometry_msgs/WrenchStamped.h>
#include <rosbag/bag.h>
#include <rosbag/view.h>
#include <tf2_msgs/TFMessage.h>
#include <tf2_ros/transform_listener.h>
#include <boost/filesystem.hpp>

#include <atomic>
#include <mutex>

#include "attitude_planner/ReplayResult.h"
#include "attitude_planner/dynamics/simulation.hpp"
#include "ros_test_helpers.hpp"

using namespace attitude_planner;
namespace rc = attitude_planner::ros_conversions;

namespace {

constexpr int kSteps = 32;  // N

/// Waits (wall time, generous) until `pred` holds; returns it.
template <class Pred>
bool waitFor(Pred pred, double seconds) {
  const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(seconds);
  while (!pred() && ros::ok() && ros::WallTime::now() < deadline) ros::WallDuration(0.01).sleep();
  return pred();
}

/// True if a node whose name contains `node` is registered as a subscriber of `topic`.
bool isSubscribed(const std::string& topic, const std::string& node) {
  XmlRpc::XmlRpcValue args, result, payload;
  args[0] = ros::this_node::getName();
  if (!ros::master::execute("getSystemState", args, result, payload, true)) return false;
  XmlRpc::XmlRpcValue& subscribers = payload[1];
  for (int i = 0; i < subscribers.size(); ++i) {
    if (std::string(subscribers[i][0]) != topic) continue;
    for (int j = 0; j < subscribers[i][1].size(); ++j) {
      if (std::string(subscribers[i][1][j]).find(node) != std::string::npos) return true;
    }
  }
  return false;
}

}  // namespace

class Tracker : public ::testing::Test {
 protected:
  void SetUp() override {
    maneuver_pub_ = nh_.advertise<AttitudeManeuver>("maneuver", 1);
    torque_sub_ = nh_.subscribe<geometry_msgs::WrenchStamped>(
        "torque", 100, [this](const geometry_msgs::WrenchStamped::ConstPtr& m) {
          std::lock_guard<std::mutex> lock(mutex_);
          torques_.push_back(*m);
        });
    done_sub_ = nh_.subscribe<ReplayResult>("done", 10, [this](const ReplayResult::ConstPtr& m) {
      std::lock_guard<std::mutex> lock(mutex_);
      done_.push_back(*m);
    });
    ASSERT_TRUE(waitFor([&] { return maneuver_pub_.getNumSubscribers() > 0; }, 30.0));
    ASSERT_TRUE(waitFor([&] { return torque_sub_.getNumPublishers() > 0; }, 30.0));
  }
  size_t doneCount() {
    std::lock_guard<std::mutex> lock(mutex_);
    return done_.size();
  }

  ros::NodeHandle nh_;
  ros::Publisher maneuver_pub_;
  ros::Subscriber torque_sub_, done_sub_;
  std::mutex mutex_;
  std::vector<geometry_msgs::WrenchStamped> torques_;
  std::vector<ReplayResult> done_;
};

TEST_F(Tracker, ReplayEndsAtThePlannedAttitudeAndIsRecorded) {
  std::string bag_path;
  ASSERT_TRUE(ros::param::get("~bag", bag_path)) << "~bag (recorded bag path) not set";
  for (const char* topic : {"/tf", "/torque", "/angular_velocity"}) {
    ASSERT_TRUE(waitFor([&] { return isSubscribed(topic, "record"); }, 30.0))
        << "rosbag record never subscribed to " << topic;
  }
  ros::WallDuration(1.0).sleep();  // let the recorder's connections to the tracker come up
  tf2_ros::Buffer tf_buffer(ros::Duration(60.0));
  tf2_ros::TransformListener listener(tf_buffer);

  Maneuver plan;
  maneuver_pub_.publish(ros_testing::testManeuver(kSteps, &plan));
  ASSERT_TRUE(waitFor([&] { return doneCount() > 0; }, 60.0)) << "no done message";
  ReplayResult done;
  {
    std::lock_guard<std::mutex> lock(mutex_);
    done = done_.back();
  }
  ASSERT_TRUE(done.success) << done.message;
  EXPECT_EQ(done.steps, kSteps);
  EXPECT_NEAR(done.duration, 3.2, 1e-12);          // N h [s]
  EXPECT_LT(done.terminal_attitude_error, 1e-12);  // same torques, same integrator [rad]
  EXPECT_LT(done.max_attitude_deviation, 1e-12);
  EXPECT_EQ(done.plan_solve_time, -1.0);  // not planned by the tracker
  const Matrix3 R_N = plan.attitude.back();
  EXPECT_LT(so3::angleBetween(rc::attitudeFromMsg(done.final_attitude, "final"), R_N), 1e-12);

  // The last tf world → body is R_N (stamped with the last step's time).
  ASSERT_TRUE(
      waitFor([&] { return tf_buffer.canTransform("world", "body", done.header.stamp); }, 10.0));
  const geometry_msgs::TransformStamped tf =
      tf_buffer.lookupTransform("world", "body", done.header.stamp);
  EXPECT_LT(so3::angleBetween(rc::attitudeFromMsg(tf.transform.rotation, "tf"), R_N), 1e-9);
  EXPECT_EQ(tf.transform.translation.x, 0.0);

  // Every step's torque arrived, in the body frame, in order.
  {
    std::lock_guard<std::mutex> lock(mutex_);
    ASSERT_EQ(torques_.size(), size_t(kSteps + 1));
    for (int k = 0; k <= kSteps; ++k) {
      EXPECT_EQ(torques_[k].header.frame_id, "body");
      EXPECT_EQ(rc::vectorFromMsg(torques_[k].wrench.torque), plan.torque[k]) << "k = " << k;
      if (k > 0) EXPECT_GT(torques_[k].header.stamp, torques_[k - 1].header.stamp);
    }
  }

  // rosbag record (--limit N+1) closes the bag after the last step: read it back.
  ASSERT_TRUE(waitFor([&] { return boost::filesystem::exists(bag_path); }, 30.0))
      << "bag " << bag_path << " was not written";
  rosbag::Bag bag(bag_path, rosbag::bagmode::Read);
  rosbag::View torque_view(bag, rosbag::TopicQuery(std::vector<std::string>{"/torque"}));
  std::vector<geometry_msgs::WrenchStamped> recorded;
  for (const rosbag::MessageInstance& m : torque_view) {
    recorded.push_back(*m.instantiate<geometry_msgs::WrenchStamped>());
  }
  ASSERT_EQ(recorded.size(), size_t(kSteps + 1));
  for (int k = 0; k <= kSteps; ++k) {
    EXPECT_EQ(rc::vectorFromMsg(recorded[k].wrench.torque), plan.torque[k]) << "k = " << k;
    EXPECT_EQ(recorded[k].header.frame_id, "body");
  }
  rosbag::View tf_view(bag, rosbag::TopicQuery(std::vector<std::string>{"/tf"}));
  std::vector<tf2_msgs::TFMessage> tfs;
  for (const rosbag::MessageInstance& m : tf_view)
    tfs.push_back(*m.instantiate<tf2_msgs::TFMessage>());
  ASSERT_EQ(tfs.size(), size_t(kSteps + 1));
  EXPECT_LT(so3::angleBetween(
                rc::attitudeFromMsg(tfs.back().transforms.at(0).transform.rotation, "bag tf"), R_N),
            1e-9);
  bag.close();
}

TEST_F(Tracker, DiagnosticsSayTheModeAndCountTheFinishedRuns) {
  // The tracker's status on /diagnostics (every second): its mode and plant, and one more finished
  // run once a maneuver's `done` is out, the body idle again.
  ros_testing::StatusWatch watch("/attitude_tracker: tracker");
  const auto any = [](const std::string&) { return true; };
  const std::string before = watch.waitFor("runs finished", any, 5.0);
  ASSERT_NE(before, "(not seen)") << "no status named '/attitude_tracker: tracker' on /diagnostics";
  EXPECT_EQ(watch.waitFor("mode", any, 0.0), "replay");
  EXPECT_EQ(watch.waitFor("plant", any, 0.0), "internal");
  Maneuver plan;
  maneuver_pub_.publish(ros_testing::testManeuver(kSteps, &plan));
  const int finished = std::stoi(before) + 1;
  EXPECT_NE(
      watch.waitFor(
          "runs finished", [&](const std::string& v) { return std::stoi(v) == finished; }, 60.0),
      "(not seen)");
  EXPECT_EQ(watch.waitFor("running", any, 0.0), "false");
}

TEST_F(Tracker, InconsistentManeuverIsRejectedWithAReason) {
  Maneuver plan;
  AttitudeManeuver bad = ros_testing::testManeuver(kSteps, &plan);
  bad.torque.pop_back();
  // `done` is latched: the previous test's may arrive first, stamped before this one was sent.
  const ros::Time sent = ros::Time::now();
  maneuver_pub_.publish(bad);
  ASSERT_TRUE(waitFor(
      [&] {
        std::lock_guard<std::mutex> lock(mutex_);
        return !done_.empty() && done_.back().header.stamp >= sent;
      },
      30.0))
      << "no done message";
  std::lock_guard<std::mutex> lock(mutex_);
  EXPECT_FALSE(done_.back().success);
  EXPECT_NE(done_.back().message.find("arrays disagree"), std::string::npos)
      << done_.back().message;
}

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_tracker");
  ros::NodeHandle nh;
  ros::AsyncSpinner spinner(2);
  spinner.start();
  return RUN_ALL_TESTS();
}
