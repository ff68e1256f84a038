// attitude_tracker_node: replays a maneuver (topic `maneuver` or ~scene) as tf, torque and markers.
#include <signal.h>
#include <unistd.h>

#include <fstream>
#include <iterator>
#include <string>

#include "attitude_planner/ros/parameters.hpp"
#include "attitude_planner/ros/tracker_node.hpp"

namespace {

/// True if process `pid` runs roslaunch (its command line has an argument named roslaunch).
bool isRoslaunch(pid_t pid) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/cmdline");
  const std::string cmdline((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::string::size_type begin = 0;
  while (begin < cmdline.size()) {
    const std::string arg = cmdline.substr(begin, cmdline.find('\0', begin) - begin);
    if (arg.substr(arg.find_last_of('/') + 1) == "roslaunch") return true;
    begin += arg.size() + 1;
  }
  return false;
}

}  // namespace

int main(int argc, char** argv) {
  ros::init(argc, argv, "attitude_tracker_node");
  ros::NodeHandle nh, private_nh("~");
  bool exit_when_done = false;
  try {
    exit_when_done = attitude_planner::readParam<bool>(private_nh, "exit_when_done", false);
    attitude_planner::TrackerNode node(nh, private_nh);
    ros::spin();
  } catch (const attitude_planner::InvalidParameter& e) {
    ROS_FATAL("%s", e.what());  // a bad private parameter stops the node at start-up
    return attitude_planner::kExitInvalidParameter;
  }
  // ~exit_when_done: the tracker shut itself down after /done. Started by roslaunch, it ends the
  // launch the way Ctrl-C would (every node stopped with SIGINT, rosbag record closes its bag),
  // with no "REQUIRED process has died" error; under rosrun or rostest it only exits.
  if (exit_when_done && isRoslaunch(getppid())) kill(getppid(), SIGINT);
  return 0;
}
