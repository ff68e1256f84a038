// attitude_plant_node: a rigid body for the tracker's external plant mode (~plant external,
// docs/ros_tracker.md), standing in for the user's simulator or vehicle. Thin: the integration is
// the core's RigidBodyPlant (analysis/tracking.hpp: the continuous body Ṙ = RΩ^,
// JΩ̇ = JΩ × Ω + u + τ_e(R, t), RKMK4, the integrator of the tracker's feedback mode), under the
// effects of ~scene (gravity gradient and disturbances as forcing; actuator_limits saturate and
// torque_noise perturbs each command once, as they do inside the tracker).
//
// The body starts at ~scene's initial attitude and rate and is held there until the first
// command arrives: that command's header.stamp is the plant's t = 0 (the effects' clock; the
// tracker stamps its first command with the maneuver's t_0, so both clocks agree). From then on
// maneuver time runs at ~rate_factor maneuver seconds per ROS second. A command acts from its
// header.stamp (clamped to [the plant's time, now]) until the next one: zero-order hold.
//
// A scene with reaction wheels (actuators.reaction_wheels, with spin_inertia) is body + wheels
// instead: the core's WheelPlant (analysis/wheel_plant.hpp: Ṙ = RΩ^, JΩ̇ = −Ω × (JΩ + A h_w) −
// A u + τ_e, ḣ_w = u, RK4), commanded by wheel torques u on `wheel_command` (each cut to its
// max_torque; a wheel stops at its max_momentum, the torque it cannot absorb acting on the body,
// with a warning once per wheel), measured by the wheels' spin rates relative to the body on
// `wheel_measurement` beside `odometry` (same stamp), under ~scene's gravity gradient and
// disturbance torques acting on the body (τ_e(R, t) in the body equation: they change the total
// momentum by their impulse); actuator_limits and torque_noise (on a body torque no wheel makes)
// are refused by name; torque_command is not subscribed.
//
// Subscribes  torque_command  geometry_msgs/WrenchStamped, body frame   u [N·m] (wrench.torque;
//                             the force is ignored); a frame_id other than ~body_frame or empty
//                             is refused with a warning naming it
// Publishes   odometry        nav_msgs/Odometry at ~rate   header.frame_id ~world_frame,
//                             child_frame_id ~body_frame, pose.orientation R (body → world),
//                             twist.angular Ω (body frame) [rad/s]; position, linear velocity
//                             and covariances zero
//             (wheels) wheel_command  sensor_msgs/JointState   u_i [N m] in `effort`, by the
//                             names wheel_1 .. wheel_n; a bad one is refused with a warning
//             (wheels) wheel_measurement  sensor_msgs/JointState at ~rate, frame ~body_frame:
//                             `velocity` the spin rates w_i = h_w,i / J_s,i − a_i·Ω [rad/s],
//                             `effort` the torques delivered [N m]
//
// Private parameters (a bad value stops the node with exit status 78, naming it):
//   ~scene        string  (required)  scene YAML: inertia, initial state, effects
//   ~replay_scene string  ""          scene YAML whose effects act instead of ~scene's (its body
//                                     and states are not used: as the tracker's ~replay_scene)
//   ~rate         double  100.0       odometry messages per ROS second [Hz] (> 0)
//   ~rate_factor  double  1.0         maneuver seconds per ROS second (> 0; the tracker's)
//   ~max_step     double  0.0         largest integration step [s, maneuver time] (>= 0;
//                                     0 = a quarter of the scene's time step T / N)
//   ~world_frame  string  "world"     odometry header.frame_id
//   ~body_frame   string  "body"      odometry child_frame_id, and the command's frame; "" =
//                                     the tracker's default in this namespace (defaultBodyFrame:
//                                     "body" in the root namespace, "NS/body" in /NS)
#pragma once

#include <memory>
#include <optional>
#include <string>

#include <geometry_msgs/WrenchStamped.h>
#include <ros/ros.h>
#include <sensor_msgs/JointState.h>

#include "attitude_planner/analysis/tracking.hpp"
#include "attitude_planner/analysis/wheel_plant.hpp"
#include "attitude_planner/io/scene.hpp"

namespace attitude_planner {

/// The node.
class PlantNode {
 public:
  /// Reads the parameters and ~scene (throws InvalidParameter naming a bad one), subscribes,
  /// advertises and starts the ~rate timer.
  PlantNode(ros::NodeHandle& nh, ros::NodeHandle& private_nh);

 private:
  /// The scene of parameter `name` (at `path`); InvalidParameter naming it if it does not load.
  static Scene loadSceneParam(const ros::NodeHandle& pnh, const std::string& name,
                              const std::string& path);
  /// `torque_command`: integrates up to the command's time, then holds the new command.
  void onCommand(const geometry_msgs::WrenchStamped::ConstPtr& msg);
  /// `wheel_command` (a scene with wheels): integrates up to its time, then holds the torques.
  void onWheelCommand(const sensor_msgs::JointState::ConstPtr& msg);
  /// The time a command of `stamp` acts from (clamped to now), releasing the body at the first.
  ros::Time commandTime(const ros::Time& stamp);
  /// Integrates whichever plant there is to maneuver time t; warns once per wheel that stops at
  /// its momentum limit.
  void advanceTo(double t);
  /// ~rate timer: integrates up to now and publishes `odometry`.
  void onTimer(const ros::TimerEvent& event);
  /// Maneuver time [s] of ROS time `stamp` (0 before the first command).
  double maneuverTime(const ros::Time& stamp) const;

  ros::Subscriber command_sub_;
  ros::Publisher odometry_pub_;
  ros::Timer timer_;
  std::unique_ptr<RigidBodyPlant> plant_;    ///< a scene without wheels
  std::unique_ptr<WheelPlant> wheel_plant_;  ///< a scene with wheels (body + wheels)
  std::vector<bool> saturation_warned_;      ///< per wheel: its stop at H_i was logged
  ros::Publisher wheel_pub_;                 ///< `wheel_measurement` (wheels)
  std::optional<ros::Time> released_;        ///< ROS time of t = 0 (the first command's stamp)
  double rate_factor_ = 1.0;
  std::string world_frame_, body_frame_;
};

}  // namespace attitude_planner
