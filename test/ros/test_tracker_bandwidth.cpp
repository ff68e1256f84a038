// rostest: what the tracker sends to rviz grows linearly with the number of samples, not
// quadratically (a path re-sent whole at every step would make an N = 3000 bag ~100 MB).
// tracker_bandwidth.test runs one sample per plan node (~rate 0), so N + 1 samples: the bytes of
// every marker topic are counted (serialized length, what a bag stores) for N = 250 and N = 1000;
// linear growth gives a ratio near 4, the old quadratic one near 16.
#include <gtest/gtest.h>
#include <ros/ros.h>

#include <visualization_msgs/Marker.h>
#include <visualization_msgs/MarkerArray.h>

#include <atomic>
#include <mutex>

#include "attitude_planner/ReplayResult.h"
#include "ros_test_helpers.hpp"

using namespace attitude_planner;
namespace rc = attitude_planner::ros_conversions;

namespace {

template <class Pred>
bool waitFor(Pred pred, double seconds) {
  const ros::WallTime deadline = ros::WallTime::now() + ros::WallDuration(seconds);
  while (!pred() && ros::ok() && ros::WallTime::now() < deadline) ros::WallDuration(0.01).sleep();
  return pred();
}

/// The seed body turned by smooth torques whose size falls like 1/N² so that every N gives the
/// same gentle motion (h = 0.1 s, T = N h; paper scheme).
AttitudeManeuver gentleManeuver(int steps) {
  PlanningProblem p;
  p.inertia = rc::inertiaFromMsg(ros_testing::seedInertia());
  SimulationInput input;
  input.torque.assign(steps + 1, Vector3::Zero());
  const double scale = 64.0 / (static_cast<double>(steps) * steps);
  for (int k = 1; k < steps; ++k) {
    const double s = std::sin(M_PI * k / steps);
    input.torque[k] = scale * Vector3(2.0 * s, -1.0 * s * s, 0.5);
  }
  const Maneuver plan = simulate(DiscreteScheme(SchemeKind::Paper, p.inertia, 0.1), input);
  return rc::maneuverToMsg(plan, p, "world", "body", ros::Time::now());
}

}  // namespace

class TrackerBandwidth : public ::testing::Test {
 protected:
  /// Counts the serialized bytes of every message on a marker topic.
  template <class M>
  ros::Subscriber count(const std::string& topic) {
    return nh_.subscribe<M>(topic, 5000, [this](const typename M::ConstPtr& m) {
      bytes_ += ros::serialization::serializationLength(*m);
    });
  }
  void SetUp() override {
    subs_.push_back(count<visualization_msgs::MarkerArray>("body_marker"));
    subs_.push_back(count<visualization_msgs::MarkerArray>("ghost_markers"));
    subs_.push_back(count<visualization_msgs::MarkerArray>("constraint_markers"));
    subs_.push_back(count<visualization_msgs::Marker>("attitude_path"));
    subs_.push_back(count<visualization_msgs::Marker>("attitude_trail"));
    subs_.push_back(count<visualization_msgs::Marker>("status_text"));
    subs_.push_back(
        nh_.subscribe<ReplayResult>("done", 10, [this](const ReplayResult::ConstPtr& m) {
          std::lock_guard<std::mutex> lock(mutex_);
          done_.push_back(*m);
        }));
    maneuver_pub_ = nh_.advertise<AttitudeManeuver>("maneuver", 1);
    ASSERT_TRUE(waitFor([&] { return maneuver_pub_.getNumSubscribers() > 0; }, 30.0));
    ASSERT_TRUE(waitFor([&] { return subs_[0].getNumPublishers() > 0; }, 30.0));
  }
  /// Marker bytes received while the tracker runs an N-step maneuver.
  std::size_t markerBytes(int steps) {
    ros::WallDuration(0.5).sleep();  // what is still in flight from before
    bytes_ = 0;
    // `done` is latched: an earlier maneuver's may arrive late, stamped before this one was sent.
    const ros::Time sent = ros::Time::now();
    maneuver_pub_.publish(gentleManeuver(steps));
    EXPECT_TRUE(waitFor(
        [&] {
          std::lock_guard<std::mutex> lock(mutex_);
          return !done_.empty() && done_.back().header.stamp >= sent;
        },
        120.0))
        << "no done for N = " << steps;
    ros::WallDuration(0.5).sleep();
    std::lock_guard<std::mutex> lock(mutex_);
    EXPECT_TRUE(!done_.empty() && done_.back().success);
    return bytes_;
  }

  ros::NodeHandle nh_;
  std::vector<ros::Subscriber> subs_;
  ros::Publisher maneuver_pub_;
  std::atomic<std::size_t> bytes_{0};
  std::mutex mutex_;
  std::vector<ReplayResult> done_;
};

TEST_F(TrackerBandwidth, MarkerBytesGrowLinearlyWithTheSamples) {
  const std::size_t small = markerBytes(250);
  const std::size_t large = markerBytes(1000);
  ASSERT_GT(small, 0u);
  const double ratio = static_cast<double>(large) / static_cast<double>(small);
  RecordProperty("bytes_250", std::to_string(small));
  RecordProperty("bytes_1000", std::to_string(large));
  std::printf("marker bytes: N = 250: %zu, N = 1000: %zu (ratio %.2f; 4 linear, 16 quadratic)\n",
              small, large, ratio);
  EXPECT_LT(ratio, 6.0) << small << " -> " << large << " bytes";
  EXPECT_GT(ratio, 2.0) << "the samples were not all received";
  // Per sample a bounded amount (body markers, a trail of at most kTrailPoints points, one text).
  EXPECT_LT(large / 1001.0, 8000.0) << "bytes per sample";
}

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_tracker_bandwidth");
  ros::NodeHandle nh;
  ros::AsyncSpinner spinner(2);
  spinner.start();
  return RUN_ALL_TESTS();
}
