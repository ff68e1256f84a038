// attitude_tracker_node: replays a planned maneuver in (ROS) real time for rviz. The torques τ_k
// of the plan are integrated again through replayPlan() (the core's DiscreteScheme via simulate(),
// or fourth_order's cubic hold on the continuous body, RKMK4), so what rviz
// shows is the rigid body's response to the planned torques, not the plan's own attitudes. The
// replay includes exactly the effects of the scene (~scene, or ~replay_scene when set; none for a
// maneuver from the topic without ~replay_scene); `done` lists them and reports the miss.
//
// A drift + two-input maneuver (seed 001, attitude_planner/DriftTwoInputManeuver on
// `drift_maneuver`, or a ~scene with system: drift_two_input) is replayed from its controls:
// ġ = g(E3 + u1 E1 + u2 E2) integrated on SO(3) by replayDriftTwoInputControls (exp-based,
// fourth order) from g(0); `control` carries (u1, u2, 0) [rad/s] and `angular_velocity` the body
// rate (u1, u2, 1) [rad/s]; `torque` is not published (a kinematic system has none); the body is
// drawn as a cube. `done` reports the replay's terminal error against the plan's g(T), the cost
// ½∫(c1 u1² + c2 u2²) dt (trapezoid on the samples) and terminal_velocity_error = 0.
//
// Subscribes  maneuver          AttitudeManeuver (rigid body)    a new maneuver replaces the
//             drift_maneuver    DriftTwoInputManeuver (seed 001) current replay
// Publishes   /tf               world → body at every step, stamped start + t_k / rate_factor
//             torque            geometry_msgs/WrenchStamped, body      τ_k [N·m] (rigid body)
//             angular_velocity  geometry_msgs/Vector3Stamped, body     Ω_k [rad/s]
//             control           geometry_msgs/Vector3Stamped, body     (u1, u2, 0) [rad/s] (drift)
//             body_marker       visualization_msgs/MarkerArray, body   box + principal axes
//             attitude_path     visualization_msgs/Marker, world       tip of the body x axis
//             constraint_markers visualization_msgs/MarkerArray, latched, when ~scene has keep_out
//                               / keep_in constraints: each cone (world) and its body axis (body)
//             done              attitude_planner/ReplayResult, latched when a replay ends
// Calls       plan_attitude_maneuver (service) when ~scene is set and ~plan_in_process is false
//             plan_drift_two_input   (service) the same, for a scene with system: drift_two_input
//
// Private parameters:
//   ~scene            string  ""       scene YAML planned at start-up (empty: wait for `maneuver`);
//                                      its effects act during the replay (gravity gradient and
//                                      disturbances as forcing, actuator_limits saturate,
//                                      torque_noise perturbs the applied torque)
//   ~replay_scene     string  ""       scene YAML whose effects act during every replay instead
//                                      (only its `effects` are used: body and plan come from the
//                                      maneuver) — replaying a plan under effects it was not made
//                                      for shows the miss in `done`
//   ~plan_in_process  bool    false    plan the scene with planManeuver() instead of the service
//   ~planner_timeout  double  30.0     wait for the planner service [s, wall]
//   ~rate_factor      double  1.0      maneuver seconds per ROS second (> 0; 2 = twice as fast)
//   ~start_delay      double  0.5      ROS seconds between receiving a maneuver and step 0 (>= 0)
//   ~world_frame      string  "world"  fixed frame of tf, path and the maneuver
//   ~body_frame       string  "body"   body frame of tf, torque, velocity and markers
//   ~body_size        double  1.0      largest edge of the drawn box [m] (> 0)
//   ~axis_length      double  0.9      length of the principal-axis arrows [m] (> 0)
//   ~path_radius      double  1.2      distance of the traced body-x tip from the origin [m] (> 0)
//   ~exit_when_done   bool    false    shut the node down after publishing `done` (demo/CI)
#pragma once

#include <atomic>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include <ros/ros.h>
#include <tf2_ros/transform_broadcaster.h>
#include <visualization_msgs/MarkerArray.h>

#include "attitude_planner/AttitudeManeuver.h"
#include "attitude_planner/DriftTwoInputManeuver.h"
#include "attitude_planner/ReplayResult.h"
#include "attitude_planner/drift_two_input/planner.hpp"
#include "attitude_planner/dynamics/maneuver.hpp"
#include "attitude_planner/io/scene.hpp"
#include "attitude_planner/planner.hpp"

namespace attitude_planner {

/// A uniform box with the principal moments of J: edges along the principal axes.
struct PrincipalBox {
  Matrix3 axes;        ///< principal axes as columns (body frame), right-handed
  Vector3 moments;     ///< principal moments [kg·m²], ascending
  Vector3 dimensions;  ///< box edges [m] along the axes, largest = `size`
};

/// Box edges a, b, c of a uniform box with principal moments J1..J3 (J1 = m (b² + c²)/12, ...),
/// scaled so that the largest edge is `size` [m] (the mass only scales the box, so it is not
/// needed). Flat or non-physical inertias (J1 + J2 < J3) get a minimum edge of 10 % of `size`.
PrincipalBox principalBox(const Matrix3& inertia, double size);

/// Markers of the body: id 0 the box, ids 1..3 arrows along the principal axes (red, green, blue
/// for the smallest, middle, largest moment), id 4 the body x axis up to the traced tip at
/// `path_radius` [m] (orange, as `attitude_path`); all in `body_frame`.
visualization_msgs::MarkerArray bodyMarkers(const PrincipalBox& box, double axis_length,
                                            double path_radius, const std::string& body_frame,
                                            const ros::Time& stamp);

/// Markers of the pointing constraints (keep_out, keep_in; others are skipped), cone i (in the
/// order of `constraints`, counting cones only) as id i: a TRIANGLE_LIST cone in `world_frame`
/// (ns "keep_out" red / "keep_in" green, translucent), apex at the origin, axis the world
/// direction s, every rim point at slant distance `length` [m] and at the half angle from s; and
/// an ARROW in `body_frame` (ns "keep_out_body_axis" / "keep_in_body_axis") from the origin to
/// `length` · b. Stamp zero: rviz draws the body axis at the latest transform.
visualization_msgs::MarkerArray constraintMarkers(
    const std::vector<PlanningConstraint>& constraints, double length,
    const std::string& world_frame, const std::string& body_frame, const ros::Time& stamp);

/// Plans a scene: via the service (if `client` is valid; the request carries the scene's
/// plannable `effects`, actuator limits and constraints) or in-process (`problem` already holds
/// them). Fills `msg` and the planner's solve time [s] and cost; returns false with `error` set if
/// planning failed.
bool planScene(const PlanningProblem& problem, const std::vector<EffectSpec>& effects,
               ros::ServiceClient* client, const std::string& world_frame,
               const std::string& body_frame, AttitudeManeuver* msg, double* solve_time,
               double* cost, std::string* error);

/// Plans a drift + two-input request: via plan_drift_two_input (if `client` is valid) or
/// in-process. Fills `msg`, the planner's solve time [s] and cost; false with `error` set if
/// planning failed.
bool planDriftScene(const DriftTwoInputRequest& request, ros::ServiceClient* client,
                    const std::string& world_frame, const std::string& body_frame,
                    DriftTwoInputManeuver* msg, double* solve_time, double* cost,
                    std::string* error);

/// The node.
class TrackerNode {
 public:
  /// Reads parameters, subscribes, and plans ~scene if it is set.
  TrackerNode(ros::NodeHandle& nh, ros::NodeHandle& private_nh);
  /// Stops a running replay.
  ~TrackerNode();

 private:
  /// One replay job, owned by the replay thread.
  struct Replay {
    AttitudeManeuver msg;             ///< the maneuver as received (rigid body)
    bool drift = false;               ///< true: replay `drift_msg` instead of `msg`
    DriftTwoInputManeuver drift_msg;  ///< the drift + two-input maneuver as received
    double plan_solve_time = -1.0;    ///< [s], −1 if unknown
    double plan_cost = -1.0;          ///< [N²·m²], −1 if unknown
    std::vector<EffectSpec> effects;  ///< effects acting during the replay (rigid body only)
    /// ~scene's constraintMarkers (empty for a maneuver from the topic), re-published with every
    /// pose so rviz finds the body frame at their stamp.
    visualization_msgs::MarkerArray constraint_markers;
  };

  /// `maneuver` callback: replaces the running replay.
  void onManeuver(const AttitudeManeuver::ConstPtr& msg);
  /// `drift_maneuver` callback: replaces the running replay.
  void onDriftManeuver(const DriftTwoInputManeuver::ConstPtr& msg);
  /// Stops the current replay (if any) and starts a new one in its own thread (under
  /// ~replay_scene's effects if that is set).
  void startReplay(Replay replay);
  /// Stops the running replay and joins its thread (within ~10 ms).
  void stopReplay();
  /// The replay thread's body; returns early when stop_ is set.
  void runReplay(Replay replay);
  /// runReplay for a drift + two-input maneuver.
  void runDriftReplay(const Replay& replay);
  /// Sleeps until ROS time `t` (sim-time friendly); false if stopped meanwhile.
  bool sleepUntil(const ros::Time& t);
  /// Waits for a valid ROS clock (sim time); sets the replay's start = now + ~start_delay. False
  /// if stopped meanwhile.
  bool waitForClock(ros::Time* start);
  /// The empty `attitude_path` LINE_STRIP.
  visualization_msgs::Marker pathMarker() const;
  /// tf world → body, the body markers, the path's next point and (if any) the constraint
  /// markers at `stamp`.
  void publishPose(const Matrix3& R, const ros::Time& stamp, const PrincipalBox& box,
                   visualization_msgs::Marker* path,
                   visualization_msgs::MarkerArray* constraint_markers = nullptr);
  /// Publishes `done` (latched); with ~exit_when_done, then shuts the node down.
  void publishDone(ReplayResult result);

  ros::NodeHandle nh_;             ///< public handle: topics and the service resolve here
  ros::Subscriber maneuver_sub_;   ///< `maneuver`
  ros::Subscriber drift_sub_;      ///< `drift_maneuver`
  ros::Publisher control_pub_;     ///< `control` (u1, u2, 0) [rad/s], frame body (drift only)
  ros::Publisher torque_pub_;      ///< `torque` τ_k [N·m], frame body
  ros::Publisher velocity_pub_;    ///< `angular_velocity` Ω_k [rad/s], frame body
  ros::Publisher marker_pub_;      ///< `body_marker`
  ros::Publisher path_pub_;        ///< `attitude_path`
  ros::Publisher done_pub_;        ///< `done` (latched)
  ros::Publisher constraint_pub_;  ///< `constraint_markers` (latched)
  tf2_ros::TransformBroadcaster tf_broadcaster_;  ///< world → body
  double rate_factor_ = 1.0;                      ///< maneuver seconds per ROS second
  double start_delay_ = 0.5;                      ///< [s] ROS time before step 0
  std::string world_frame_;                       ///< fixed frame
  std::string body_frame_;                        ///< body frame
  double body_size_ = 1.0;                        ///< largest box edge [m]
  double axis_length_ = 0.9;                      ///< principal-axis arrow length [m]
  double path_radius_ = 1.2;                      ///< distance of the traced body-x tip [m]
  bool exit_when_done_ = false;                   ///< shut down after `done`
  /// ~replay_scene's effects, if set: they act during every replay instead of ~scene's own.
  std::optional<std::vector<EffectSpec>> replay_scene_effects_;

  std::mutex replay_mutex_;        ///< guards replay_thread_ (start/stop from callbacks)
  std::thread replay_thread_;      ///< runs runReplay()
  std::atomic<bool> stop_{false};  ///< asks the replay thread to return
};

}  // namespace attitude_planner
