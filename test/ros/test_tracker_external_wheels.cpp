// rostest (tracker_external_wheels.test): the tracker's external plant mode with reaction wheels.
// The plan of test/ros/wheel_pyramid_spin.yaml flown by the tracking law through the wheels on
// the tracker's own body (/internal_wheels) and on the measured state of attitude_plant_node over
// ROS topics (/external_wheels: odometry and the wheels' spin rates in, wheel torques out): the
// external loop lands within 2x the internal one's terminal attitude error, every command within
// the wheels' torque limits, named wheel_1..4; without spin inertias (/nospin) the external mode
// is refused by name; without a plant (/unmeasured_wheels), or with a stale wheel_measurement
// (/stale_wheels), every wheel command is zero and `done` fails: nothing blocks.
#include <gtest/gtest.h>
#include <ros/ros.h>

#include <diagnostic_msgs/DiagnosticArray.h>
#include <nav_msgs/Odometry.h>
#include <sensor_msgs/JointState.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <mutex>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include "attitude_planner/ReplayResult.h"
#include "ros_test_helpers.hpp"

using namespace attitude_planner;

namespace {

/// Counts the JointStates on `topic`: messages, the names seen, the largest |effort|, and
/// whether every message carried one velocity per name.
struct JointCounter {
  JointCounter(ros::NodeHandle& nh, const std::string& topic)
      : sub(nh.subscribe(topic, 1000, &JointCounter::onJoints, this)) {}
  void onJoints(const sensor_msgs::JointState::ConstPtr& m) {
    std::lock_guard<std::mutex> lock(mutex);
    ++count;
    names.insert(m->name.begin(), m->name.end());
    for (double e : m->effort) largest_effort = std::max(largest_effort, std::abs(e));
    if (m->velocity.size() != m->name.size()) velocity_per_name = false;
  }
  std::mutex mutex;
  int count = 0;
  std::set<std::string> names;
  double largest_effort = 0.0;
  bool velocity_per_name = true;
  ros::Subscriber sub;
};

/// /stale_wheels' measurements: odometry of the right frames stamped now and wheel_measurement
/// (every wheel at rest relative to the body) stamped `kAge` seconds old, both at 50 Hz; and the
/// tracker's /diagnostics statuses while it flies (level, the two measurement ages).
struct StaleWheelSource {
  static constexpr double kAge = 1.5;  // [s], three times the tracker's ~measurement_timeout
  StaleWheelSource()
      : nh("stale_wheels"),
        odometry(nh.advertise<nav_msgs::Odometry>("odometry", 10)),
        wheels(nh.advertise<sensor_msgs::JointState>("wheel_measurement", 10)),
        diagnostics(
            ros::NodeHandle().subscribe("/diagnostics", 100, &StaleWheelSource::onStatus, this)),
        thread([this] { publish(); }) {}
  ~StaleWheelSource() {
    stop = true;
    thread.join();
  }
  void publish() {
    nav_msgs::Odometry body;
    body.header.frame_id = "world";
    body.child_frame_id = "stale_wheels_body";
    body.pose.pose.orientation.w = 1.0;
    sensor_msgs::JointState spin;
    spin.header.frame_id = "stale_wheels_body";
    spin.name = {"wheel_1", "wheel_2", "wheel_3", "wheel_4"};
    spin.velocity.assign(4, 0.0);
    while (!stop && ros::ok()) {
      body.header.stamp = ros::Time::now();
      spin.header.stamp = body.header.stamp - ros::Duration(kAge);
      odometry.publish(body);
      wheels.publish(spin);
      ros::WallDuration(0.02).sleep();
    }
  }
  void onStatus(const diagnostic_msgs::DiagnosticArray::ConstPtr& array) {
    for (const diagnostic_msgs::DiagnosticStatus& s : array->status) {
      if (s.name.find("/stale_wheels/") != 0) continue;
      bool running = false;
      double body_age = -1.0, wheel_age = -1.0;
      for (const diagnostic_msgs::KeyValue& kv : s.values) {
        if (kv.key == "running") running = kv.value == "true";
        if (kv.key == "measurement age [s]") body_age = std::stod(kv.value);
        if (kv.key == "wheel measurement age [s]") wheel_age = std::stod(kv.value);
      }
      if (!running) continue;
      std::lock_guard<std::mutex> lock(mutex);
      levels.push_back(s.level);
      body_ages.push_back(body_age);
      wheel_ages.push_back(wheel_age);
    }
  }
  ros::NodeHandle nh;
  ros::Publisher odometry, wheels;
  ros::Subscriber diagnostics;
  std::atomic<bool> stop{false};
  std::mutex mutex;
  std::vector<int> levels;                    ///< the tracker's status levels while it flew
  std::vector<double> body_ages, wheel_ages;  ///< the odometry's and the wheels' ages [s]
  std::thread thread;
};

/// The topics every test reads, subscribed (and /stale_wheels' measurements published) in main
/// before any run starts (the runs go on while the tests before one wait).
struct Counters {
  ros::NodeHandle external{"external_wheels"}, unmeasured{"unmeasured_wheels"},
      stale{"stale_wheels"};
  JointCounter commands{external, "wheel_command"}, measured{external, "wheel_measurement"};
  JointCounter unmeasured_commands{unmeasured, "wheel_command"};
  JointCounter stale_commands{stale, "wheel_command"};
  StaleWheelSource stale_source;
};
Counters* counters = nullptr;

/// A ~mode replan run (namespace `replan`) against the feedback run it is measured by
/// (`reference`): re-planned at least once, no re-plan failed, the terminal attitude error within
/// twice the reference's, and every wheel command within its torque limit.
void expectReplansLandWithinTwice(const std::string& reference, const std::string& replan,
                                  const std::string& label) {
  ros::NodeHandle reference_nh(reference), nh(replan);
  ros_testing::DoneListener reference_done(reference_nh), listener(nh);
  const ReplayResult::ConstPtr feedback = reference_done.wait(120.0);
  const ReplayResult::ConstPtr done = listener.wait(60.0);
  ASSERT_TRUE(feedback && done) << "no done from /" << reference << " and /" << replan;
  ASSERT_TRUE(done->success) << done->message;
  EXPECT_EQ(done->mode, "replan");
  std::printf("%s: %d re-plans, %d failed, terminal attitude error %.3g rad (feedback %.3g rad)\n",
              label.c_str(), done->replans, done->replan_failures, done->terminal_attitude_error,
              feedback->terminal_attitude_error);
  EXPECT_GE(done->replans, 1);
  EXPECT_EQ(done->replan_failures, 0) << done->replan_error;
  EXPECT_LE(done->terminal_attitude_error, 2.0 * feedback->terminal_attitude_error);
  ASSERT_EQ(done->reaction_wheels.wheels.size(), 4u);
  for (const WheelPeak& w : done->reaction_wheels.wheels)
    EXPECT_GE(w.torque_margin, -1e-12 * w.max_torque) << w.name << ": commands cut to U";
}

}  // namespace

TEST(TrackerExternalWheels, MeasuredWheelLoopLandsWithinTwiceTheInternalError) {
  ros::NodeHandle internal_nh("internal_wheels"), external_nh("external_wheels");
  JointCounter& commands = counters->commands;
  JointCounter& measured = counters->measured;
  ros_testing::DoneListener internal_done(internal_nh), external_done(external_nh);
  const ReplayResult::ConstPtr internal = internal_done.wait(120.0);
  const ReplayResult::ConstPtr external = external_done.wait(30.0);
  ASSERT_TRUE(internal && external) << "no done from both trackers";
  ASSERT_TRUE(internal->success) << internal->message;
  ASSERT_TRUE(external->success) << external->message;
  EXPECT_EQ(external->mode, "feedback");
  EXPECT_NE(external->message.find("through 4 reaction wheels on the measured state"),
            std::string::npos)
      << external->message;
  std::printf(
      "wheels, terminal attitude error: internal %.3g rad, external %.3g rad (ratio %.3g); rate "
      "error: internal %.3g, external %.3g rad/s; effort: internal %.5g, external %.5g\n",
      internal->terminal_attitude_error, external->terminal_attitude_error,
      external->terminal_attitude_error / internal->terminal_attitude_error,
      internal->terminal_velocity_error, external->terminal_velocity_error, internal->effort,
      external->effort);
  EXPECT_LE(external->terminal_attitude_error, 2.0 * internal->terminal_attitude_error);
  EXPECT_LT(external->terminal_attitude_error, 1e-2);
  ASSERT_EQ(external->reaction_wheels.wheels.size(), 4u);
  for (const WheelPeak& w : external->reaction_wheels.wheels) {
    EXPECT_GE(w.torque_margin, -1e-12 * w.max_torque) << w.name << ": commands cut to U";
    EXPECT_GT(w.peak_momentum, 0.0) << w.name;
  }
  ASSERT_FALSE(external->constraint_names.empty());
  EXPECT_EQ(external->constraint_names.back(), "reaction_wheels");
  std::lock_guard<std::mutex> c(commands.mutex), m(measured.mutex);
  const std::set<std::string> wheels{"wheel_1", "wheel_2", "wheel_3", "wheel_4"};
  EXPECT_EQ(commands.names, wheels);
  EXPECT_GT(commands.count, 200) << "one command per sample (20 s at 12.5 samples per s)";
  EXPECT_LE(commands.largest_effort, ros_testing::kWheelTorqueLimit * (1 + 1e-12));
  EXPECT_GT(commands.largest_effort, 0.0);
  EXPECT_EQ(measured.names, wheels);
  EXPECT_GT(measured.count, 200) << "the plant measures at its rate";
  EXPECT_TRUE(measured.velocity_per_name) << "a spin rate per wheel";
}

TEST(TrackerExternalWheels, ReplanModeReplansFromTheMeasuredBodyAndWheelMomenta) {
  // ~mode replan with wheels on the plant: re-plans from the measured body and wheel momenta
  // (the planner's initial_momentum) every 5 s, adopted, none failed, and the law on the plan in
  // force, distributed over the wheels, lands within twice the internal feedback mode's error.
  expectReplansLandWithinTwice("internal_wheels", "external_wheels_replan",
                               "wheels, external replan");
}

TEST(TrackerExternalWheels, ReplayModeCommandsThePlansWheelTorquesOpenLoop) {
  ros::NodeHandle nh("external_replay");
  ros_testing::DoneListener listener(nh);
  const ReplayResult::ConstPtr done = listener.wait(90.0);
  ASSERT_TRUE(done) << "no done from /external_replay";
  ASSERT_TRUE(done->success) << done->message;
  EXPECT_EQ(done->mode, "replay");
  EXPECT_NE(done->message.find("commanded 128 steps through 4 reaction wheels"), std::string::npos)
      << done->message;
  std::printf("wheels, open loop on the plant: terminal attitude error %.3g rad\n",
              done->terminal_attitude_error);
  // Open loop, the plant's continuous body against the plan's discrete one: no feedback removes
  // the gap. Each sample commands the mean of the plan's u over its hold (measured 2.6e-4, 5.2e-5
  // rad); commanding u(t) at the sample and holding it lagged half a sample (1.65e-2 rad).
  EXPECT_LT(done->terminal_attitude_error, 2e-3);
  ASSERT_EQ(done->reaction_wheels.wheels.size(), 4u);
  for (const WheelPeak& w : done->reaction_wheels.wheels) {
    EXPECT_GE(w.torque_margin, -1e-9 * w.max_torque) << w.name << ": the plan's u meets U";
  }
}

TEST(TrackerExternalWheels, WithoutSpinInertiasTheExternalModeIsRefusedByName) {
  ros::NodeHandle nh("nospin");
  ros_testing::DoneListener listener(nh);
  const ReplayResult::ConstPtr done = listener.wait(60.0);
  ASSERT_TRUE(done) << "no done from /nospin";
  EXPECT_FALSE(done->success);
  EXPECT_NE(done->message.find("maneuver.reaction_wheels.spin_inertia"), std::string::npos)
      << done->message;
}

TEST(TrackerExternalWheels, WithoutMeasurementsEveryWheelCommandIsZeroAndDoneFails) {
  ros::NodeHandle nh("unmeasured_wheels");
  JointCounter& commands = counters->unmeasured_commands;
  ros_testing::DoneListener listener(nh);
  const ReplayResult::ConstPtr done = listener.wait(90.0);
  ASSERT_TRUE(done) << "no done from /unmeasured_wheels";
  EXPECT_FALSE(done->success);
  EXPECT_NE(done->message.find("had no fresh measurement and got a zero command"),
            std::string::npos)
      << done->message;
  EXPECT_NE(done->message.find("/unmeasured_wheels/odometry"), std::string::npos) << done->message;
  std::lock_guard<std::mutex> lock(commands.mutex);
  EXPECT_GT(commands.count, 200) << "the stream keeps its rate without measurements";
  EXPECT_EQ(commands.largest_effort, 0.0);
  EXPECT_EQ(commands.names, (std::set<std::string>{"wheel_1", "wheel_2", "wheel_3", "wheel_4"}));
}

TEST(TrackerExternalWheels, AStaleWheelMeasurementGivesZeroCommandsAWarningAndAFailedDone) {
  // Fresh odometry, but every wheel_measurement stamped 1.5 s old (~measurement_timeout 0.5 s):
  // the wheels' momenta are unknown, so the same as a stale odometry. Every sample commands zero,
  // the tracker's status warns with the wheels' age past the timeout (the body's is fresh),
  // `done` fails; the stream keeps its rate.
  ros::NodeHandle nh("stale_wheels");
  JointCounter& commands = counters->stale_commands;
  StaleWheelSource& source = counters->stale_source;
  ros_testing::DoneListener listener(nh);
  const ReplayResult::ConstPtr done = listener.wait(120.0);
  ASSERT_TRUE(done) << "no done from /stale_wheels";
  EXPECT_FALSE(done->success);
  EXPECT_NE(done->message.find("had no fresh measurement and got a zero command"),
            std::string::npos)
      << done->message;
  ros::WallDuration(0.5).sleep();  // the final zero command
  {
    std::lock_guard<std::mutex> lock(commands.mutex);
    EXPECT_GT(commands.count, 200) << "one command per sample (20 s at 12.5 samples per s)";
    EXPECT_EQ(commands.largest_effort, 0.0);
    EXPECT_EQ(commands.names, (std::set<std::string>{"wheel_1", "wheel_2", "wheel_3", "wheel_4"}));
  }
  std::lock_guard<std::mutex> lock(source.mutex);
  // About 10 statuses over the 10 s run (1 Hz); the first may precede the first sample.
  ASSERT_GE(source.levels.size(), 4u) << "too few /diagnostics statuses from /stale_wheels";
  for (std::size_t i = 1; i < source.levels.size(); ++i) {
    EXPECT_EQ(source.levels[i], diagnostic_msgs::DiagnosticStatus::WARN) << "status " << i;
    EXPECT_GT(source.wheel_ages[i], 0.5) << "status " << i << ": the wheels' stamps, stale";
    EXPECT_LT(source.wheel_ages[i], 2.0 * StaleWheelSource::kAge) << "status " << i;
    // Measured (not the -1 of none) and fresh: stamped about when the sample was taken.
    EXPECT_LT(std::abs(source.body_ages[i]), 0.5) << "status " << i << ": odometry fresh";
  }
}

// tracker_wheels_loop.test (this binary filtered to TrackerWheelsLoop.*): the spin scene's plan
// flown through the wheels under a constant world-frame disturbance it never saw.
TEST(TrackerWheelsLoop, DisturbedPlantLandsWithinTwiceTheInternalLoopAndFarInsideTheOpenLoop) {
  // The same law under the same disturbance on attitude_plant_node's body + wheels and on the
  // tracker's own (the in-process WheelPlant): within 2x. Open loop the disturbance carries the
  // body far past either (it acted, and the law rejects it).
  ros::NodeHandle internal_nh("internal_wheels_disturbed"),
      external_nh("external_wheels_disturbed"), open_nh("internal_replay_disturbed");
  ros_testing::DoneListener internal_done(internal_nh), external_done(external_nh),
      open_done(open_nh);
  const ReplayResult::ConstPtr internal = internal_done.wait(120.0);
  const ReplayResult::ConstPtr external = external_done.wait(30.0);
  const ReplayResult::ConstPtr open = open_done.wait(30.0);
  ASSERT_TRUE(internal && external && open) << "no done from the three disturbed runs";
  ASSERT_TRUE(internal->success) << internal->message;
  ASSERT_TRUE(external->success) << external->message;
  ASSERT_TRUE(open->success) << open->message;
  EXPECT_EQ(internal->replay_effects, std::vector<std::string>{"disturbance_torque"});
  EXPECT_EQ(open->replay_effects, std::vector<std::string>{"disturbance_torque"});
  std::printf(
      "wheels under an unplanned disturbance, terminal attitude error: internal %.3g rad, "
      "external %.3g rad (ratio %.3g), open loop %.3g rad\n",
      internal->terminal_attitude_error, external->terminal_attitude_error,
      external->terminal_attitude_error / internal->terminal_attitude_error,
      open->terminal_attitude_error);
  EXPECT_LE(external->terminal_attitude_error, 2.0 * internal->terminal_attitude_error);
  EXPECT_GT(open->terminal_attitude_error, 10.0 * external->terminal_attitude_error);
  EXPECT_GT(open->terminal_attitude_error, 10.0 * internal->terminal_attitude_error);
  for (const ReplayResult::ConstPtr& done : {internal, external}) {
    ASSERT_EQ(done->reaction_wheels.wheels.size(), 4u);
    for (const WheelPeak& w : done->reaction_wheels.wheels)
      EXPECT_GE(w.torque_margin, -1e-12 * w.max_torque) << w.name << ": commands cut to U";
  }
}

TEST(TrackerWheelsLoop, InternalReplanModeReplansFromTheSimulatedBodyAndWheelMomenta) {
  // ~mode replan with wheels on the tracker's own body + wheels: re-planned every 5 s from the
  // simulated body and wheel momenta (with the disturbance in the re-planned problem), adopted,
  // none failed, landing within twice the feedback mode's error under the same disturbance.
  expectReplansLandWithinTwice("internal_wheels_disturbed", "internal_wheels_replan",
                               "wheels, internal replan under the disturbance");
}

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_tracker_external_wheels");
  ros::NodeHandle nh;
  ros::AsyncSpinner spinner(2);
  spinner.start();
  Counters subscribed;
  counters = &subscribed;
  return RUN_ALL_TESTS();
}
