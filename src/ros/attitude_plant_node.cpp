// attitude_plant_node: a simulated rigid body for the tracker's ~plant external (torque_command in,
// odometry out; src/ros/plant_node.hpp, docs/ros_tracker.md).
#include "attitude_planner/ros/parameters.hpp"
#include "attitude_planner/ros/plant_node.hpp"

int main(int argc, char** argv) {
  ros::init(argc, argv, "attitude_plant_node");
  ros::NodeHandle nh, private_nh("~");
  try {
    attitude_planner::PlantNode node(nh, private_nh);
    ros::spin();
  } catch (const attitude_planner::InvalidParameter& e) {
    ROS_FATAL("%s", e.what());  // a bad private parameter stops the node at start-up
    return attitude_planner::kExitInvalidParameter;
  }
  return 0;
}
