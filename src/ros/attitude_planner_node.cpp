// attitude_planner_node: service plan_attitude_maneuver + action plan_attitude_maneuver_action.
#include "attitude_planner/ros/parameters.hpp"
#include "attitude_planner/ros/planner_node.hpp"

int main(int argc, char** argv) {
  ros::init(argc, argv, "attitude_planner_node");
  ros::NodeHandle nh, private_nh("~");
  try {
    attitude_planner::PlannerNode node(nh, private_nh);
    ros::AsyncSpinner spinner(node.threads());  // concurrent service requests
    spinner.start();
    ros::waitForShutdown();
  } catch (const attitude_planner::InvalidParameter& e) {
    ROS_FATAL("%s", e.what());  // a bad private parameter stops the node at start-up
    return attitude_planner::kExitInvalidParameter;
  }
  return 0;
}
