// Private-parameter reading shared by the nodes: an explicit default for a parameter that is not
// set, and a start-up error for one that is set to something the node cannot use (wrong type, out
// of range, unknown name, a file that is not there). A node that ran on a default instead of what
// was asked would look as if it worked; the node mains catch InvalidParameter and exit with
// kExitInvalidParameter and the message.
#pragma once

#include <ros/package.h>
#include <ros/ros.h>

#include <sysexits.h>
#include <unistd.h>

#include <algorithm>
#include <cstdlib>
#include <mutex>
#include <set>
#include <sstream>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <vector>

#include "attitude_planner/name_table.hpp"

namespace attitude_planner {

/// A private parameter set to a value the node cannot use; what() names the parameter (fully
/// resolved), the value and the rule.
class InvalidParameter : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// Exit status of a node stopped by an InvalidParameter (sysexits.h: configuration error).
constexpr int kExitInvalidParameter = EX_CONFIG;

namespace parameter_detail {

template <class T>
const char* typeName();
template <>
inline const char* typeName<double>() {
  return "a number";
}
template <>
inline const char* typeName<int>() {
  return "an integer";
}
template <>
inline const char* typeName<bool>() {
  return "true or false";
}
template <>
inline const char* typeName<std::string>() {
  return "a string";
}

/// The parameter as stored on the parameter server, for messages ("?" if unreadable).
inline std::string storedValue(const ros::NodeHandle& nh, const std::string& name) {
  XmlRpc::XmlRpcValue raw;
  if (!nh.getParam(name, raw)) return "?";
  std::ostringstream out;
  raw.write(out);
  return out.str();
}

/// The fully resolved names the read*Param functions were asked for (set or not): the node's
/// parameters, for warnUnknownParameters.
inline std::set<std::string>& readNames() {
  static std::set<std::string> names;
  return names;
}
inline std::mutex& readNamesMutex() {
  static std::mutex mutex;
  return mutex;
}

}  // namespace parameter_detail

/// Warns (ROS_WARN, one line each) about every private parameter of `nh` on the parameter server
/// that no read*Param call asked for: a misspelt `~rat` would otherwise leave `~rate` at its
/// default without a word. Call it after the node has read all its parameters. `use_sim_time`
/// is roscpp's (replay.launch remaps /use_sim_time to a private one). Returns the unknown names.
inline std::vector<std::string> warnUnknownParameters(const ros::NodeHandle& nh) {
  std::vector<std::string> unknown, all;
  if (!ros::param::getParamNames(all)) return unknown;
  const std::string prefix = nh.getNamespace() + "/";
  std::lock_guard<std::mutex> lock(parameter_detail::readNamesMutex());
  const std::set<std::string>& read = parameter_detail::readNames();
  std::string known;
  for (const std::string& name : read) {
    if (name.compare(0, prefix.size(), prefix) == 0)
      known += (known.empty() ? "" : ", ") + name.substr(prefix.size());
  }
  for (const std::string& name : all) {
    if (name.compare(0, prefix.size(), prefix) != 0) continue;
    const std::string key =
        name.substr(prefix.size(), name.find('/', prefix.size()) - prefix.size());
    if (key == "use_sim_time" || read.count(prefix + key) ||
        std::find(unknown.begin(), unknown.end(), key) != unknown.end())
      continue;
    unknown.push_back(key);
    ROS_WARN("parameter %s%s is not one of this node's and is ignored (its parameters: %s)",
             prefix.c_str(), key.c_str(), known.c_str());
  }
  return unknown;
}

/// Reads a private parameter: `fallback` if it is not set; throws InvalidParameter if it is set
/// with the wrong type or `valid` rejects it (`requirement` says what is accepted, e.g. "> 0").
template <class T, class Valid>
T readParam(const ros::NodeHandle& nh, const std::string& name, const T& fallback, Valid valid,
            const std::string& requirement) {
  {
    std::lock_guard<std::mutex> lock(parameter_detail::readNamesMutex());
    parameter_detail::readNames().insert(nh.resolveName(name));
  }
  if (!nh.hasParam(name)) return fallback;
  T value;
  if (!nh.getParam(name, value)) {
    std::string stored_as;  // roslaunch stores value="1e-10" (no type attribute) as a string
    if (std::string text; nh.getParam(name, text) && !std::is_same<T, std::string>::value)
      stored_as = "; it is stored as a string: in a launch file give the <param> a type";
    throw InvalidParameter("parameter " + nh.resolveName(name) + " = " +
                           parameter_detail::storedValue(nh, name) + " is not " +
                           parameter_detail::typeName<T>() + " (" + requirement + ")" + stored_as);
  }
  if (!valid(value)) {
    std::ostringstream out;
    out << "parameter " << nh.resolveName(name) << " = " << value << " is invalid: must be "
        << requirement;
    throw InvalidParameter(out.str());
  }
  return value;
}

/// A parameter of any value of its type (a flag): `fallback` if not set, InvalidParameter if set
/// with the wrong type.
template <class T>
T readParam(const ros::NodeHandle& nh, const std::string& name, const T& fallback) {
  return readParam<T>(
      nh, name, fallback, [](const T&) { return true; }, std::string("any value"));
}

/// Reads a private parameter that names a value of `table` (a scheme, a solver, ...): `fallback`
/// if not set; throws InvalidParameter listing the accepted names for a name the table lacks.
template <class Enum, std::size_t N>
Enum readNamedParam(const ros::NodeHandle& nh, const std::string& name, Enum fallback,
                    const NamedValue<Enum> (&table)[N]) {
  const std::string text = readParam<std::string>(
      nh, name, nameIn(table, fallback),
      [&](const std::string& s) { return findByName(table, s).has_value(); },
      oneOf(namesOf(table)));
  return *findByName(table, text);
}

/// The directory relative file parameters are resolved against: the directory the caller
/// started roslaunch / rosrun in ($PWD, which both pass on to the node), not the node's working
/// directory (roslaunch starts nodes in ROS_HOME).
inline std::string callerDirectory() {
  const char* pwd = std::getenv("PWD");
  if (pwd && *pwd == '/') return pwd;
  char buffer[4096];
  return getcwd(buffer, sizeof buffer) ? std::string(buffer) : std::string(".");
}

/// Reads a private parameter naming a file: "" if not set or empty; an absolute path,
/// package://PACKAGE/relative/path, or a path relative to callerDirectory(). Throws
/// InvalidParameter (naming the parameter, the value and the directory a relative path was
/// resolved against) if the package is unknown or the file cannot be read.
inline std::string readFileParam(const ros::NodeHandle& nh, const std::string& name) {
  const std::string value = readParam<std::string>(nh, name, "");
  if (value.empty()) return value;
  const std::string where = "parameter " + nh.resolveName(name) + " = " + value;
  static const std::string kPackagePrefix = "package://";
  std::string path;
  if (value.rfind(kPackagePrefix, 0) == 0) {
    const std::string rest = value.substr(kPackagePrefix.size());
    const std::string package = rest.substr(0, rest.find('/'));
    const std::string package_dir = ros::package::getPath(package);
    if (package_dir.empty()) throw InvalidParameter(where + ": no package named " + package);
    path = package_dir + rest.substr(package.size());
  } else if (value.front() == '/') {
    path = value;
  } else {
    path = callerDirectory() + "/" + value;
    if (access(path.c_str(), R_OK) != 0) {
      throw InvalidParameter(where + ": no readable file " + path +
                             " (a relative path is resolved against the directory roslaunch or "
                             "rosrun was started in, " +
                             callerDirectory() + "; or use package://PACKAGE/path)");
    }
  }
  if (access(path.c_str(), R_OK) != 0) throw InvalidParameter(where + ": no readable file " + path);
  return path;
}

}  // namespace attitude_planner
