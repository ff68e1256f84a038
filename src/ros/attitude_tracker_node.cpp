// attitude_tracker_node: replays a maneuver (topic `maneuver` or ~scene) as tf, torque and markers.
#include "attitude_planner/ros/tracker_node.hpp"

int main(int argc, char** argv) {
  ros::init(argc, argv, "attitude_tracker_node");
  ros::NodeHandle nh, private_nh("~");
  attitude_planner::TrackerNode node(nh, private_nh);
  ros::spin();
  return 0;
}
