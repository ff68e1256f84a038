// A downstream program: parses a scene (the core's YAML reader, yaml-cpp), plans it with
// planManeuver (the core), and converts the plan to the ROS message with maneuverToMsg
// (attitude_planner_ros). Exit status 0 only if all three did what they promise.
#include <cmath>
#include <cstdio>

#include "attitude_planner/io/scene.hpp"
#include "attitude_planner/planner.hpp"
#include "attitude_planner/ros/conversions.hpp"

int main() {
  using namespace attitude_planner;
  const Scene scene = parseScene(R"(
inertia: [1.0, 2.0, 3.0]
duration: 4.0
steps: 16
initial: {attitude: {axis: [0, 0, 1], angle: 0.0}, angular_velocity: [0, 0, 0]}
final:   {attitude: {axis: [0, 0, 1], angle: 0.5}, angular_velocity: [0, 0, 0]}
)",
                                 "client scene");
  const PlanResult result = planManeuver(scene.problem);
  const AttitudeManeuver msg = ros_conversions::maneuverToMsg(result.maneuver, scene.problem, "map",
                                                              "base_link", ros::Time(1.0));
  const Maneuver back = ros_conversions::maneuverFromMsg(msg);
  const bool ok = result.converged() && msg.attitude.size() == 17 && back.attitude.size() == 17 &&
                  msg.header.frame_id == "map" && msg.child_frame_id == "base_link" &&
                  std::isfinite(result.cost) && result.cost > 0.0;
  std::printf("converged %d, N = %zu, cost %.6g, message nodes %zu, frames %s -> %s\n",
              result.converged() ? 1 : 0, back.attitude.size() - 1, result.cost,
              msg.attitude.size(), msg.header.frame_id.c_str(), msg.child_frame_id.c_str());
  return ok ? 0 : 1;
}
