// Private-parameter reading shared by the nodes: explicit defaults and range checks that log and
// fall back, as imu_tools does.
#pragma once

#include <ros/ros.h>

#include <cstddef>
#include <string>

#include "attitude_planner/name_table.hpp"

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

/// Reads a private parameter that names a value of `table` (a scheme, a solver, ...); falls back
/// (with an error in the log listing the accepted names) for a name the table does not have.
template <class Enum, std::size_t N>
Enum readNamedParam(ros::NodeHandle& nh, const std::string& name, Enum fallback,
                    const NamedValue<Enum> (&table)[N]) {
  const std::string text = readParam<std::string>(
      nh, name, nameIn(table, fallback),
      [&](const std::string& s) { return findByName(table, s).has_value(); },
      oneOf(namesOf(table)));
  return *findByName(table, text);
}

}  // namespace attitude_planner
