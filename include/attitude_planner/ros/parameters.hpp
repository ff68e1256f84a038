// Private-parameter reading shared by the nodes: explicit defaults and range checks that log and
// fall back, as imu_tools does.
#pragma once

#include <ros/ros.h>

#include <string>

namespace attitude_planner {

/// Reads a private parameter; falls back (with an error in the log) if `valid` rejects it.
template <class T, class Valid>
T readParam(ros::NodeHandle& nh, const std::string& name, const T& fallback, Valid valid,
            const std::string& requirement) {
  T value;
  nh.param(name, value, fallback);
  if (!valid(value)) {
    ROS_ERROR_STREAM("~" << name << " = " << value << " is invalid (" << requirement << "); using "
                         << fallback);
    return fallback;
  }
  return value;
}

}  // namespace attitude_planner
