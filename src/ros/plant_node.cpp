#include "attitude_planner/ros/plant_node.hpp"

#include <algorithm>
#include <cmath>

#include <nav_msgs/Odometry.h>

#include "attitude_planner/io/scene.hpp"
#include "attitude_planner/ros/conversions.hpp"
#include "attitude_planner/ros/parameters.hpp"
#include "attitude_planner/ros/tracker_node.hpp"  // defaultBodyFrame: the tracker's rule

namespace attitude_planner {

namespace rc = ros_conversions;

PlantNode::PlantNode(ros::NodeHandle& nh, ros::NodeHandle& pnh) {
  auto positive = [](double v) { return std::isfinite(v) && v > 0.0; };
  auto non_negative = [](double v) { return std::isfinite(v) && v >= 0.0; };
  auto non_empty = [](const std::string& s) { return !s.empty(); };
  const std::string scene_path = readFileParam(pnh, "scene");
  if (scene_path.empty()) {
    throw InvalidParameter("parameter " + pnh.resolveName("scene") +
                           " is required: the scene whose body, initial state and effects "
                           "the plant simulates");
  }
  const std::string replay_scene = readFileParam(pnh, "replay_scene");
  const double rate = readParam<double>(pnh, "rate", 100.0, positive, "> 0 Hz");
  rate_factor_ = readParam<double>(pnh, "rate_factor", 1.0, positive, "> 0");
  double max_step = readParam<double>(pnh, "max_step", 0.0, non_negative, ">= 0 s, 0 = h / 4");
  world_frame_ = readParam<std::string>(pnh, "world_frame", "world", non_empty, "non-empty");
  body_frame_ = readParam<std::string>(pnh, "body_frame", "body");
  // Empty: the frame a tracker in this namespace flies by default, so the two pair up.
  if (body_frame_.empty()) body_frame_ = defaultBodyFrame(nh.getNamespace());
  warnUnknownParameters(pnh);
  Scene scene = loadSceneParam(pnh, "scene", scene_path);
  if (!replay_scene.empty())
    scene.effects = loadSceneParam(pnh, "replay_scene", replay_scene).effects;
  const PlanningProblem& p = scene.problem;
  if (max_step == 0.0) max_step = 0.25 * p.duration / p.steps;
  odometry_pub_ = nh.advertise<nav_msgs::Odometry>("odometry", 10);
  if (p.reaction_wheels.present()) {
    const std::string field = "parameter " + pnh.resolveName("scene") + " = " + scene_path +
                              ": actuators.reaction_wheels";
    try {
      rc::requireWheelBodyEffects(scene.effects, field);
    } catch (const std::exception& e) {
      throw InvalidParameter(e.what());
    }
    if (!p.reaction_wheels.hasSpinInertia()) {
      throw InvalidParameter(field + ".spin_inertia: needed to measure the wheels' spin rates");
    }
    wheel_plant_ = std::make_unique<WheelPlant>(
        p.inertia, p.reaction_wheels, RigidBodyState{p.initial_attitude, p.initial_velocity},
        max_step, plannableEffects(scene.effects, p.inertia));
    wheel_pub_ = nh.advertise<sensor_msgs::JointState>("wheel_measurement", 10);
    command_sub_ = nh.subscribe("wheel_command", 10, &PlantNode::onWheelCommand, this,
                                ros::TransportHints().tcpNoDelay());
  } else {
    plant_ = std::make_unique<RigidBodyPlant>(p.inertia, p.initial_attitude, p.initial_velocity,
                                              plannableEffects(scene.effects, p.inertia),
                                              actuationOf(scene.effects), max_step);
    command_sub_ = nh.subscribe("torque_command", 10, &PlantNode::onCommand, this,
                                ros::TransportHints().tcpNoDelay());
  }
  timer_ = nh.createTimer(ros::Duration(1.0 / rate), &PlantNode::onTimer, this);
  ROS_INFO(
      "attitude_plant_node: %s, %zu effects%s%s, odometry at %g Hz (rate factor %g), frames %s -> "
      "%s, waiting for %s",
      scene_path.c_str(), scene.effects.size(), replay_scene.empty() ? "" : " of ",
      replay_scene.c_str(), rate, rate_factor_, world_frame_.c_str(), body_frame_.c_str(),
      command_sub_.getTopic().c_str());
}

Scene PlantNode::loadSceneParam(const ros::NodeHandle& pnh, const std::string& name,
                                const std::string& path) {
  try {
    return loadScene(path);
  } catch (const std::exception& e) {
    throw InvalidParameter("parameter " + pnh.resolveName(name) + " = " + path + ": " + e.what());
  }
}

double PlantNode::maneuverTime(const ros::Time& stamp) const {
  if (!released_) return 0.0;
  return std::max(0.0, (stamp - *released_).toSec() * rate_factor_);
}

void PlantNode::onCommand(const geometry_msgs::WrenchStamped::ConstPtr& msg) {
  if (!msg->header.frame_id.empty() && msg->header.frame_id != body_frame_) {
    ROS_WARN_THROTTLE(1.0,
                      "torque_command refused: header.frame_id '%s' is not the body frame '%s'",
                      msg->header.frame_id.c_str(), body_frame_.c_str());
    return;
  }
  Vector3 torque;
  try {
    torque = rc::finiteVectorFromMsg(msg->wrench.torque, "torque_command.wrench.torque");
  } catch (const std::exception& e) {
    ROS_WARN_THROTTLE(1.0, "torque_command refused: %s", e.what());
    return;
  }
  // The held command acts up to this one's time; a late one acts from the plant's time.
  plant_->advanceTo(maneuverTime(commandTime(msg->header.stamp)));
  plant_->command(torque);
}

void PlantNode::onWheelCommand(const sensor_msgs::JointState::ConstPtr& msg) {
  if (!msg->header.frame_id.empty() && msg->header.frame_id != body_frame_) {
    ROS_WARN_THROTTLE(1.0, "wheel_command refused: header.frame_id '%s' is not the body frame '%s'",
                      msg->header.frame_id.c_str(), body_frame_.c_str());
    return;
  }
  Eigen::VectorXd torque;
  try {
    torque = rc::wheelJointValues(msg->name, msg->effort, wheel_plant_->wheels().count(),
                                  "wheel_command.effort");
  } catch (const std::exception& e) {
    ROS_WARN_THROTTLE(1.0, "wheel_command refused: %s", e.what());
    return;
  }
  advanceTo(maneuverTime(commandTime(msg->header.stamp)));
  wheel_plant_->command(torque);
}

ros::Time PlantNode::commandTime(const ros::Time& stamp) {
  const ros::Time now = ros::Time::now();
  const ros::Time at = stamp.isZero() ? now : std::min(stamp, now);
  if (!released_) {
    released_ = at;  // t = 0: the body is released by its first command
    ROS_INFO("attitude_plant_node: released at %.3f s", at.toSec());
  }
  return at;
}

void PlantNode::advanceTo(double t) {
  if (wheel_plant_) {
    wheel_plant_->advanceTo(t);
    const std::vector<double>& stopped = wheel_plant_->saturatedAt();
    saturation_warned_.resize(stopped.size(), false);
    for (std::size_t i = 0; i < stopped.size(); ++i) {
      if (std::isnan(stopped[i]) || saturation_warned_[i]) continue;
      saturation_warned_[i] = true;
      ROS_WARN(
          "attitude_plant_node: wheel_%zu reached its momentum limit %g N m s at t = %.6g s: "
          "held there, the torque it cannot absorb acts on the body",
          i + 1, wheel_plant_->wheels().momentumLimit(static_cast<int>(i)), stopped[i]);
    }
  } else {
    plant_->advanceTo(t);
  }
}

void PlantNode::onTimer(const ros::TimerEvent&) {
  const ros::Time now = ros::Time::now();
  advanceTo(maneuverTime(now));
  if (!wheel_plant_) {
    odometry_pub_.publish(rc::odometryToMsg(plant_->attitude(), plant_->angularVelocity(), now,
                                            world_frame_, body_frame_));
    return;
  }
  const WheelPlant& w = *wheel_plant_;
  odometry_pub_.publish(
      rc::odometryToMsg(w.attitude(), w.angularVelocity(), now, world_frame_, body_frame_));
  wheel_pub_.publish(rc::wheelJointState(
      w.deliveredTorque(), wheelSpinRates(w.wheels(), w.momentum(), w.angularVelocity()),
      body_frame_, now));
}

}  // namespace attitude_planner
