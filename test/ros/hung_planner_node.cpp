// A planner that hangs (tracker_takeover.test): advertises plan_attitude_maneuver and never
// answers, so every call of the tracker (re-plans) waits forever unless the tracker bounds it.
#include <ros/ros.h>

#include "attitude_planner/PlanAttitudeManeuver.h"

namespace {

bool neverAnswer(attitude_planner::PlanAttitudeManeuver::Request&,
                 attitude_planner::PlanAttitudeManeuver::Response&) {
  ROS_INFO("hung_planner: a call arrived; it will not be answered");
  while (ros::ok()) ros::WallDuration(0.1).sleep();
  return false;
}

}  // namespace

int main(int argc, char** argv) {
  ros::init(argc, argv, "hung_planner");
  ros::NodeHandle nh;
  ros::ServiceServer server = nh.advertiseService("plan_attitude_maneuver", neverAnswer);
  ros::AsyncSpinner spinner(4);  // several calls hang at once
  spinner.start();
  ros::waitForShutdown();
  return 0;
}
