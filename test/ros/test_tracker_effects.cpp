// rostest: attitude_tracker_node plans a scene with effects through the planner service and
// replays it under exactly the effects of its scene (or of ~replay_scene). The launch file sets
// what `done` must show:
//   ~expected_effects  string  comma-separated scene keys the replay applied, in order
//   ~max_miss          double  upper bound of the terminal attitude miss [rad] (plan lands)
//   ~min_miss          double  lower bound of the miss [rad] (unplanned effects show)
#include <gtest/gtest.h>
#include <ros/ros.h>

#include <sstream>

#include "attitude_planner/ReplayResult.h"
#include "ros_test_helpers.hpp"

using namespace attitude_planner;

TEST(TrackerEffects, ReplayAppliesTheScenesEffectsAndReportsTheMiss) {
  ros::NodeHandle nh, pnh("~");
  std::string expected_effects;
  double max_miss = 1e300, min_miss = 0.0;
  ASSERT_TRUE(pnh.getParam("expected_effects", expected_effects));
  pnh.getParam("max_miss", max_miss);
  pnh.getParam("min_miss", min_miss);
  ros_testing::DoneListener listener_done(nh);
  const ReplayResult::ConstPtr done = listener_done.wait(90.0);
  ASSERT_TRUE(done) << "no done message";
  ASSERT_TRUE(done->success) << done->message;
  std::ostringstream applied;
  for (std::size_t i = 0; i < done->replay_effects.size(); ++i) {
    applied << (i ? "," : "") << done->replay_effects[i];
  }
  EXPECT_EQ(applied.str(), expected_effects);
  EXPECT_GT(done->plan_cost, 0.0);  // the tracker had the scene planned
  EXPECT_LE(done->terminal_attitude_error, max_miss);
  EXPECT_GE(done->terminal_attitude_error, min_miss);
}

int main(int argc, char** argv) {
  ::testing::InitGoogleTest(&argc, argv);
  ros::init(argc, argv, "test_tracker_effects");
  ros::AsyncSpinner spinner(2);
  spinner.start();
  return RUN_ALL_TESTS();
}
