// attitude_tracker_node: drives a simulated rigid body along a planned maneuver and shows it in
// rviz (docs/ros_tracker.md). ~mode replay (default) integrates the plan's torques τ_k again
// through replayPlan() (the core's DiscreteScheme via simulate(), or fourth_order's cubic hold on
// the continuous body, RKMK4): open loop, what the planned torques alone do. ~mode feedback tracks
// the plan with the geometric law on SO(3) (dynamics/tracking_controller.hpp; feed-forward τ(t)
// plus PD on e_R, e_Ω, gyroscopic terms) closed around the continuous body
// (analysis/tracking.hpp: simulateTracking). ~mode replan adds receding-horizon re-planning
// (analysis/replanning.hpp): every ~replan_period of maneuver time the rest of the maneuver is
// re-planned from the body's simulated state at the current node, warm-started with the rest of
// the plan in force (the request's initial_guess), on a worker thread (through the service, or
// planManeuver with ~plan_in_process) while the stream goes on; the answer is adopted at the first
// node after it arrives and the law flies it from there; a failed re-plan keeps the plan in force
// (ROS_WARN once per failure, the status text and `done` count it). Either way the body acts under
// exactly the effects of the scene (~scene, or ~replay_scene when set; none for a maneuver from the
// topic without ~replay_scene): gravity gradient and disturbances as forcing, actuator_limits
// saturate, torque_noise perturbs the delivered torque. The body (actual) and the plan (reference)
// are streamed at ~rate [Hz of ROS time] with the scheme's own interpolation between nodes
// (ManeuverInterpolation); `done` reports the terminal attitude and rate errors against the plan.
//
// A maneuver with reaction wheels (its `reaction_wheels`, internal plant) is flown with its wheel
// torques through body + wheels in ~mode replay (analysis/wheel_flight.hpp: flyWithWheels), and
// with the tracking law's torque distributed over the wheels and cut to their limits in ~mode
// feedback (trackWithWheels); with ~plant external the wheel torques go out on `wheel_command`
// and the wheels' speeds come in on `wheel_measurement` (runExternalWheels; in ~mode replan the
// re-plans start from the measured body and wheel momenta and the law on the plan in force is
// distributed over the wheels). With the internal plant, ~mode replan or effects during the run
// (gravity gradient, disturbance torques) fly the same loop on the tracker's own body + wheels
// (a WheelPlant under the run's effects, read exactly at every sample instead of measured);
// actuator_limits and torque_noise with wheels are refused by name.
// The message is honoured: tf, markers and topics use header.frame_id / child_frame_id
// (~world_frame / ~body_frame only when they are empty); a header.stamp in the future is the start
// of the maneuver (else now + ~start_delay); time[] must be the uniform grid k · time_step (refused
// with an error naming the row otherwise; the node keeps running); cones are drawn for the
// maneuver's `constraints`.
//
// A drift + two-input maneuver (seed 001, attitude_planner/DriftTwoInputManeuver on
// `drift_maneuver`, or a ~scene with system: drift_two_input) is replayed from its controls:
// ġ = g(E3 + u1 E1 + u2 E2) integrated on SO(3) by replayDriftTwoInputControls (exp-based,
// fourth order) from g(0), streamed at ~rate like a rigid-body plan (between nodes the replay's own
// motion, replayedDriftTwoInputAt); `control` carries (u1, u2, 0) [rad/s] and `angular_velocity`
// the body rate (u1, u2, 1) [rad/s]; `torque` is not published (a kinematic system has none); the
// body is drawn as a cube. `done` reports the replay's terminal error against the plan's g(T), the
// cost ½∫(c1 u1² + c2 u2²) dt (trapezoid on the samples) and terminal_velocity_error = 0.
//
// Bandwidth is bounded: per sample a constant amount (tf, torque, rates, body markers, a trail of
// at most kTrailPoints points, one text marker); per maneuver once (latched) the planned path
// decimated to at most kMaxPathPoints points, the start/target ghosts and the cones. A recording
// grows linearly with the number of samples, never with N² (test/ros/test_tracker_bandwidth.cpp).
//
// Subscribes  maneuver           AttitudeManeuver (rigid body)   a new maneuver replaces the
//             drift_maneuver     DriftTwoInputManeuver (seed 001) current replay
// Publishes   /tf                header.frame_id → child_frame_id, the body, at every sample
//             torque             geometry_msgs/WrenchStamped, body   delivered τ(t) [N·m]
//             angular_velocity   geometry_msgs/Vector3Stamped, body  Ω(t) [rad/s] (actual)
//             control            geometry_msgs/Vector3Stamped, body  (u1, u2, 0) [rad/s] (drift)
//             reference_pose     geometry_msgs/PoseStamped, world    R_d(t), the plan [rigid body]
//             attitude_error     std_msgs/Float64   ‖log(R_d(t)ᵀ R(t))‖ [rad] (rqt_plot)
//             angular_velocity_error std_msgs/Float64  |Ω − RᵀR_d Ω_d| [rad/s] (rqt_plot)
//             body_pose          geometry_msgs/PoseStamped, world   R(t), the body (stamped state)
//             attitude_error_vector geometry_msgs/Vector3Stamped, body   log(R_dᵀR) [rad], the
//                                rotation from the reference to the body (norm: attitude_error)
//             angular_velocity_error_vector geometry_msgs/Vector3Stamped, body   e_Ω [rad/s]
//             body_marker        visualization_msgs/MarkerArray, body   box, principal axes, traced
//             axis attitude_trail     visualization_msgs/Marker, world   the traced axis' last
//             kTrailPoints tips status_text        visualization_msgs/Marker, world   "t / T, angle
//             to go, |τ|, mode" attitude_path      visualization_msgs/Marker, world, latched   the
//             PLANNED path of the
//                                traced tip, once per maneuver (≤ kMaxPathPoints points)
//             ghost_markers      visualization_msgs/MarkerArray, world, latched   start and target
//             constraint_markers visualization_msgs/MarkerArray, latched, when the maneuver (or
//                                ~scene) has keep_out / keep_in constraints: each cone (world) and
//                                its body axis (body, frame-locked)
//             wheel_states       sensor_msgs/JointState, body   a maneuver with reaction wheels
//                                (replay mode): names wheel_1.., effort = wheel torque [N·m]
//             wheel_momentum     std_msgs/Float64MultiArray   the wheel momenta [N·m·s]
//             wheel_momentum_markers visualization_msgs/MarkerArray, world   a bar per wheel
//                                against its limit (markers.hpp: wheelMomentumMarkers)
//             done               attitude_planner/ReplayResult, latched when a run ends
//             /diagnostics       diagnostic_msgs/DiagnosticArray, every second (wall): the status
//                                `<node>: tracker` (ros/diagnostics.hpp)
// Calls       plan_attitude_maneuver (service) when ~scene is set and ~plan_in_process is false
//             plan_drift_two_input   (service) the same, for a scene with system: drift_two_input
//
// Private parameters:
//   ~mode             string  "replay" replay | feedback | replan; an unknown mode stops the node
//                                      with an error naming it (exit 78, as every bad parameter)
//   ~rate             double  50.0     samples per ROS second (>= 0); 0 = one sample per plan node
//   ~replan_period    double  0.0      [s, maneuver time] between re-plans (>= 0; replan), rounded
//                                      to whole plan steps (at least one); 0 = T / 10
//   ~trace_axis       string  "auto"   body axis traced by the path: x | y | z | auto (the one
//                                      most perpendicular to the maneuver's rotation axis)
//   ~feedback_frequency double 0.0     ω_n of the law [rad/s] (>= 0; 0 = 40 / T)
//   ~feedback_damping double  1.0      ζ of the law (> 0)
//   ~scene            string  ""       scene YAML planned at start-up (empty: wait for `maneuver`);
//                                      its effects act during the run
//   ~replay_scene     string  ""       scene YAML whose effects act during every run instead
//                                      (only its `effects` are used: body and plan come from the
//                                      maneuver) — shows the miss of a plan under effects it was
//                                      not made for, and in feedback mode how much of it the law
//                                      removes
//   ~plan_in_process  bool    false    plan the scene with planManeuver() instead of the service
//   ~planner_timeout  double  30.0     [s, wall] wait for the planner service; also the bound
//                                      on the start-up plan call and on each re-plan (a planner
//                                      that does not answer in time is abandoned: roscpp cannot
//                                      cancel a call, its thread is left waiting)
//   ~takeover_tolerance double 0.25    [rad] a maneuver arriving mid-run whose R_0 is farther than
//                                      this from the body is refused (`done` says so; the run
//                                      goes on); a nearer one is flown from the body's state
//   ~rate_factor      double  1.0      maneuver seconds per ROS second (> 0; 2 = twice as fast)
//   ~start_delay      double  0.5      ROS seconds between receiving a maneuver and t_0 (>= 0)
//   ~world_frame      string  "world"  fixed frame when the maneuver's header.frame_id is empty
//   ~body_frame       string  ""       body frame when the maneuver's child_frame_id is empty;
//                                      "" = defaultBodyFrame(namespace): "body" in the root
//                                      namespace, "NS/body" in namespace /NS (one per vehicle).
//                                      Another node publishing the same transform (seen on /tf)
//                                      is an error: ROS_ERROR and the run's `done` fails
//   ~body_size        double  1.0      largest edge of the drawn box [m] (> 0)
//   ~axis_length      double  0.9      length of the principal-axis arrows [m] (> 0)
//   ~path_radius      double  1.2      distance of the traced tip from the origin [m] (> 0)
//   ~exit_when_done   bool    false    shut the node down after publishing `done` (demo/CI)
//   ~plant            string  "internal" internal: the tracker simulates the body itself (above);
//                                      external: the body is the user's — the tracker subscribes
//                                      to its measured state (`odometry`) and publishes the
//                                      command (`torque_command`) at ~rate (docs/ros_tracker.md);
//                                      tracker.launch's plant:=node is external on an
//                                      attitude_plant_node the launch starts in the namespace
//   ~measurement_timeout double 0.5    [s, ROS time] an `odometry` older than this at a sample
//                                      is stale: zero command, a warning, `done` fails (external)
//
// ~plant external (every mode): at every sample the tracker takes the newest
// `odometry` (nav_msgs/Odometry: pose.orientation the body → world attitude, twist.angular the
// body rate; header.frame_id must be the maneuver's world frame and child_frame_id its body
// frame, empty ones are taken as those), moves it to the sample's time under the command held
// meanwhile and the known effects (predictState: the measurement's age is transport and sampling
// lag), and publishes on
// `torque_command` (geometry_msgs/WrenchStamped, body frame) the law's command on it
// (TrackingLaw, feedback; the law on the plan in force, replan, re-planned from the measured
// state) or the plan's torque τ(t) (replay). tf, markers and errors show the
// measured body. After the last sample a zero command is sent, and tf follows the newest
// measured attitude until the next maneuver.
#pragma once

#include <atomic>
#include <deque>
#include <functional>
#include <future>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include <nav_msgs/Odometry.h>
#include <ros/ros.h>
#include <sensor_msgs/JointState.h>
#include <tf2_msgs/TFMessage.h>
#include <tf2_ros/transform_broadcaster.h>
#include <visualization_msgs/MarkerArray.h>

#include "attitude_planner/AttitudeManeuver.h"
#include "attitude_planner/DriftTwoInputManeuver.h"
#include "attitude_planner/PlanAttitudeManeuver.h"
#include "attitude_planner/ReplayResult.h"
#include "attitude_planner/analysis/constraint_health.hpp"
#include "attitude_planner/analysis/replanning.hpp"
#include "attitude_planner/analysis/tracking.hpp"
#include "attitude_planner/analysis/wheel_flight.hpp"
#include "attitude_planner/analysis/wheel_plant.hpp"
#include "attitude_planner/drift_two_input/planner.hpp"
#include "attitude_planner/dynamics/maneuver.hpp"
#include "attitude_planner/io/scene.hpp"
#include "attitude_planner/planner.hpp"
#include "attitude_planner/ros/conversions.hpp"
#include "attitude_planner/ros/diagnostics.hpp"

namespace attitude_planner {

/// Most points of the latched planned path (`attitude_path`): longer plans are decimated.
inline constexpr int kMaxPathPoints = 400;
/// Points of the live trail (`attitude_trail`), the newest samples' traced tips.
inline constexpr int kTrailPoints = 60;

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

/// Markers of the body: id 0 the box (ns "body"), ids 1..3 arrows along the principal axes (ns
/// "principal_axis_smallest" / "_middle" / "_largest": red, green, blue), id 4 the traced body axis
/// `trace_axis` (unit) up to the traced tip at `path_radius` [m] (ns "traced_axis", orange, as
/// `attitude_path`); all in `body_frame`, coloured by markerMeanings() (markers.hpp).
visualization_msgs::MarkerArray bodyMarkers(const PrincipalBox& box, double axis_length,
                                            double path_radius, const std::string& body_frame,
                                            const ros::Time& stamp,
                                            const Vector3& trace_axis = Vector3::UnitX());

/// Markers of the pointing constraints (keep_out, keep_in; others are skipped), cone i (in the
/// order of `constraints`, counting cones only) as id i: a TRIANGLE_LIST cone in `world_frame`
/// (ns "keep_out" / "keep_in", translucent, their legend colours: markers.hpp), apex at the
/// origin, axis the world direction s, every rim point at slant distance `length` [m] and at the
/// half angle from s. The constrained body axes are drawn per sample in the world frame
/// (bodyAxisMarkers), the directions once (worldDirectionMarkers).
visualization_msgs::MarkerArray constraintMarkers(
    const std::vector<PlanningConstraint>& constraints, double length,
    const std::string& world_frame, const ros::Time& stamp);

/// The body axis to trace: e_x, e_y, e_z for `name` "x", "y", "z"; for "auto" the principal
/// direction e_i least aligned with the maneuver's rotation axis log(R_0ᵀ R_N) (body frame), so
/// the turn shows (e_x if R_N = R_0). Throws InvalidInput naming ~trace_axis for another name.
Vector3 traceAxis(const std::string& name, const Matrix3& initial, const Matrix3& final);

/// The default body frame of a tracker in namespace `ns`: "body" in the root namespace, else the
/// namespace without its leading slash followed by "/body" ("/sat1" -> "sat1/body"), so that two
/// trackers in two namespaces never publish the same world -> body transform.
std::string defaultBodyFrame(const std::string& ns);

/// Up to `max_points` indices of 0..n, evenly spread, 0 and n always included, increasing.
std::vector<int> decimatedIndices(int n, int max_points);

/// Maneuver times [s] of the published samples: t_j = j · rate_factor / rate while below T, then
/// T itself; with rate = 0 the node times k h, k = 0..N.
std::vector<double> sampleTimes(double duration, int steps, double rate, double rate_factor);

/// `done`'s constraint health: the names and worst violations of `health`, and the message
/// extended with the constraints the flown path went past (by how much).
void reportConstraintHealth(const ConstraintHealth& health, ReplayResult* result);

/// Plans a scene: via the service (if `client` is valid; the request carries the scene's
/// plannable `effects`, actuator limits and constraints) or in-process (`problem` already holds
/// them). Fills `msg` (with the constraints it was planned under) and the planner's solve time
/// [s] and cost; returns false with `error` set if planning failed.
bool planScene(const PlanningProblem& problem, const std::vector<EffectSpec>& effects,
               ros::ServiceClient* client, const std::string& world_frame,
               const std::string& body_frame, AttitudeManeuver* msg, double* solve_time,
               double* cost, std::string* error);

/// Plans a drift + two-input request: via plan_drift_two_input (if `client` is valid) or
/// in-process. Fills `msg`, the planner's solve time [s] and cost; false with `error` set if
/// planning failed.
/// The service request that plans `problem` with the scene's `effects` (torque noise left out:
/// the plan cannot know it), its actuator limits and constraints.
PlanAttitudeManeuver::Request planRequestOf(const PlanningProblem& problem,
                                            const std::vector<EffectSpec>& effects);

/// Where the body the tracker drives lives (~plant).
enum class PlantKind {
  Internal,  ///< simulated by the tracker itself (the default; the behaviour before ~plant)
  External,  ///< the user's: measured state in (`odometry`), command out (`torque_command`)
};
inline constexpr NamedValue<PlantKind> kPlantNames[] = {
    {PlantKind::Internal, "internal"},
    {PlantKind::External, "external"},
};

/// The newest measured state as the tracker saw it at a sample (~plant external).
struct MeasurementAtSample {
  bool fresh = false;    ///< received, frames right, not older than ~measurement_timeout
  RigidBodyState state;  ///< moved to the sample's time (when fresh; else the last usable one)
  std::string problem;   ///< why not fresh (for the warning and `done`)
  double time = 0.0;     ///< maneuver time [s] of the measurement (when fresh)
  double age = 0.0;      ///< maneuver seconds from the measurement to the sample (when fresh)
};

/// A re-plan's answer (replan mode).
struct ReplanAnswer {
  bool ok = false;          ///< a converged plan is in `plan`
  Maneuver plan;            ///< its nodes (rows 0..N − k from the node it was planned from)
  double solve_time = 0.0;  ///< planner wall time [s]
  std::string error;        ///< why not, when !ok
};

/// Plans `rest` (remainderProblem: the rest of the maneuver from t = start_time) warm-started with
/// `guess`: through the service with `effects` and start_time when `client` is valid, else
/// planManeuver in-process with rest's own (time-shifted) effects. Never throws.
ReplanAnswer planRemainder(const PlanningProblem& rest, const std::vector<EffectSpec>& effects,
                           double start_time, const Maneuver& guess, ros::ServiceClient client);

bool planDriftScene(const DriftTwoInputRequest& request, ros::ServiceClient* client,
                    const std::string& world_frame, const std::string& body_frame,
                    DriftTwoInputManeuver* msg, double* solve_time, double* cost,
                    std::string* error);

/// The node.
class TrackerNode {
 public:
  /// Reads parameters, subscribes, and plans ~scene if it is set. A bad ~mode stops the node.
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
    /// Cones to draw when the message carries none (~scene's, for a drift scene's frames).
    std::vector<PlanningConstraint> scene_constraints;
    /// The problem the maneuver solves (~scene's, with its effects), for re-plans; unset for a
    /// maneuver from the topic (rebuilt from the message and ~replay_scene's effects).
    std::optional<PlanningProblem> problem;
    /// A maneuver that replaces a running one: the body's state at the running one's next sample
    /// (the internal body starts there, not at the plan's R_0) and that sample's stamp (the new
    /// run's t_0 unless its header.stamp is in the future: the stream goes on at its rate).
    std::optional<RigidBodyState> takeover;
    ros::Time continue_at;
    /// A pointing scene's end condition (the boresight and target drawn, the pointing error on
    /// the status text and in `done`); the maneuver itself flies to the attitude its plan chose.
    std::optional<EndCondition> pointing;
  };

  /// What a rigid-body run streams: the plan (reference) and the body (actual), both
  /// interpolated, the frames, the sample times and the result so far.
  struct Playback {
    std::shared_ptr<const EffectModel> effects;        ///< known effects (kept alive)
    std::unique_ptr<ManeuverInterpolation> reference;  ///< the plan
    std::unique_ptr<ManeuverInterpolation> actual;     ///< the body
    std::vector<double> times;                         ///< maneuver times of the samples [s]
    std::string world_frame, body_frame;               ///< from the message
    PrincipalBox box;                                  ///< the drawn body
    Vector3 trace_axis = Vector3::UnitX();             ///< traced body axis (unit)
    std::vector<PlanningConstraint> constraints;       ///< cones to draw
    ReplayResult result;                               ///< filled before streaming
    /// replan mode: the closed loop whose plan is replaced (else null), the problem it re-plans
    /// and the effects a re-plan request carries.
    std::shared_ptr<RecedingHorizonRun> horizon;
    PlanningProblem problem;
    std::vector<EffectSpec> effects_specs;
    std::string replan_status;  ///< the status text's re-plan line (replan mode)
    /// The worst violation of each constraint at the published samples (fresh measurements when
    /// the plant is external); shared so the const publishing path can update it.
    std::shared_ptr<ConstraintHealth> health;
    int replan_period_steps = 1;           ///< plan steps between re-plans (replanPeriodSteps)
    std::optional<EndCondition> pointing;  ///< Replay::pointing
    /// The maneuver's reaction wheels (empty: none) and, with them, the flight of the body and
    /// the wheels from the plan's wheel torques (what `actual` shows; null without wheels).
    ReactionWheels wheels;
    std::shared_ptr<const WheelFlight> wheel_flight;
    /// ~plant external with wheels: the plan's wheel torques u_k (replay mode's command, held
    /// linearly between nodes) and the peaks of the measured momenta and the commanded torques.
    std::vector<Eigen::VectorXd> plan_wheel_torque;
    std::optional<WheelPeaks> measured_wheel_peaks;
    /// ~plant internal with wheels in replan mode or under effects: the tracker's own body +
    /// wheels, flown by the external plant's loop (runExternalWheels) instead of measured.
    std::shared_ptr<WheelPlant> wheel_plant;
  };
  /// A re-plan in flight (replan mode).
  struct ReplanState {
    int period_steps = 1;  ///< ~replan_period in plan steps
    int next_node = 1;     ///< the next node to re-plan from
    bool pending = false;  ///< a request is in flight
    int pending_from = 0;  ///< its node
    ros::WallTime sent;    ///< when it was sent (abandoned after ~planner_timeout)
    /// Set by a detached thread: dropping it abandons the answer (never waits for it).
    std::future<ReplanAnswer> answer;
  };

  /// Advertises the topics (and, with ~plant external, `torque_command` and `odometry`).
  void advertiseTopics();
  /// `maneuver` callback: replaces the running replay.
  void onManeuver(const AttitudeManeuver::ConstPtr& msg);
  /// `drift_maneuver` callback: replaces the running replay.
  void onDriftManeuver(const DriftTwoInputManeuver::ConstPtr& msg);
  /// Plans ~scene (through the service or in-process) and starts its replay; false with
  /// `error` set if it could not.
  bool planAndStartScene(const std::string& scene, bool plan_in_process, double planner_timeout,
                         std::string* error);
  /// Stops the current replay (if any) and starts a new one in its own thread (under
  /// ~replay_scene's effects if that is set).
  void startReplay(Replay replay);
  /// Stops the running replay and joins its thread (within ~10 ms).
  void stopReplay();
  /// The replay thread's body; returns early when stop_ is set.
  void runReplay(Replay replay);
  /// Builds the playback of a rigid-body maneuver in ~mode (replay or closed loop) and its
  /// result (terminal errors, effort); throws InvalidInput / StepTooLarge naming what is wrong.
  Playback preparePlayback(const Replay& replay) const;
  /// The open-loop or closed-loop run of `playback`'s plan: fills playback->actual (or
  /// playback->horizon) and the result's errors and effort.
  void runBody(const Replay& replay, const Maneuver& plan, const Matrix3& inertia,
               SchemeKind scheme, Playback* playback) const;
  /// replan mode, before the sample at maneuver time t: adopts an answer that has arrived (at the
  /// first node ≥ t), or sends the next re-plan when its node has passed and none is in flight,
  /// from the state `state_at_node` gives at that node (default: the simulated body's), with
  /// the wheels' momenta `momentum_at_node` gives as its initial_momentum (a maneuver with wheels).
  void serviceReplans(double t, Playback* playback, ReplanState* state,
                      const std::function<RigidBodyState(int)>& state_at_node = nullptr,
                      const std::function<Eigen::VectorXd(int)>& momentum_at_node = nullptr);
  /// replan mode: moves a re-plan's start `body` (at maneuver time t) onto the constraints when it
  /// is past them within ~projection_tolerance (counted in done.projected_replans); false, with a
  /// failed re-plan counted and said, when it is farther (the planner would refuse that start).
  bool projectReplanStart(double t, RigidBodyState* body, Playback* playback) const;
  /// ~plant external: streams `playback` from `start`, commanding the measured body; fills the
  /// result (terminal errors of the last measurement, effort of the commands, stale samples).
  /// False if stopped meanwhile.
  bool runExternal(const ros::Time& start, Playback* playback, ReplanState* replans);
  /// `/tf` callback: notes another node that publishes this tracker's body transform.
  void onTf(const ros::MessageEvent<tf2_msgs::TFMessage const>& event);
  /// Sets the frame pair the current run publishes; returns the conflict seen since the last
  /// call ("" if none) and clears it.
  std::string claimFrames(const std::string& world_frame, const std::string& body_frame);
  struct HeldPose;
  /// The newest `odometry`'s attitude when its frames are `frames`' (empty ones taken as those)
  /// and its quaternion is usable; none otherwise.
  std::optional<Matrix3> measuredAttitude(const HeldPose& frames);
  /// `odometry` callback: keeps the newest measurement.
  void onOdometry(const nav_msgs::Odometry::ConstPtr& msg);
  /// The newest measurement at the sample stamped `stamp` of the run started at `start`, moved
  /// to the sample's time under `held_command` (the last command sent) and the known effects.
  /// `predict` false: the measurement as taken (time and age set), not moved.
  MeasurementAtSample measurementAt(const Playback& playback, const ros::Time& start,
                                    const ros::Time& stamp, const Vector3& held_command,
                                    bool predict = true);
  /// ~plant external with wheels: the newest odometry and `wheel_measurement` (spin rates
  /// relative to the body, turned into momenta with the measured rate), moved together to the
  /// sample's time under the wheel torques held meanwhile (predictWheelState).
  MeasurementAtSample wheelMeasurementAt(const Playback& playback, const ros::Time& start,
                                         const ros::Time& stamp, const Eigen::VectorXd& held,
                                         Eigen::VectorXd* momentum);
  /// ~plant external with wheels: at every sample the wheel torques u on the measured body and
  /// wheels (the law's torque distributed and cut, wheelTorquesFor, on the plan, or in replan
  /// mode on the plan in force, re-planned from the measured body and momenta; or the plan's u
  /// averaged over the sample) out on `wheel_command`; stale measurements give a zero command.
  /// With playback->wheel_plant (internal plant) the same loop on that plant: its state at the
  /// sample instead of a measurement, u commanded to it instead of published. False if stopped
  /// meanwhile.
  bool runExternalWheels(const ros::Time& start, Playback* playback, ReplanState* replans);
  /// The internal wheel plant at maneuver time t, as a measurement: exact, fresh, no age.
  MeasurementAtSample simulatedWheelState(WheelPlant* plant, double t, Eigen::VectorXd* momentum);
  /// An external run's `done` figures from the last measured state: the terminal errors against
  /// the plan's R_N and Ω_N, the final attitude, the cost, the re-plans adopted, success (no
  /// stale sample).
  void finishFromMeasuredEnd(const Playback& playback, int stale, ReplayResult* result) const;
  /// runExternalWheels' `done` after the stream: terminal errors of the last measurement, the
  /// samples that were stale or cut at a wheel limit, the measured wheel peaks.
  void finishExternalWheelsResult(Playback* playback, int stale, int cut_samples,
                                  const std::string& first_problem) const;
  /// `wheel_measurement` callback: keeps the newest.
  void onWheelMeasurement(const sensor_msgs::JointState::ConstPtr& msg);
  /// Publishes the body (`body`, its torque the delivered or commanded one) and the reference
  /// (`plan`) at maneuver time t, stamped `stamp`.
  void publishState(const Playback& playback, const ManeuverSample& body,
                    const ManeuverSample& plan, double t, const ros::Time& stamp,
                    std::deque<Vector3>* trail);
  /// A maneuver with reaction wheels: refuses, naming the setting, what is not flown with wheels
  /// (~plant external without spin inertias, actuator effects during the run:
  /// requireWheelBodyEffects) and checks the array (validateReactionWheels, field
  /// maneuver.reaction_wheels).
  void requireWheelFlight(const ReactionWheels& wheels,
                          const std::vector<EffectSpec>& effects) const;
  /// replay mode with wheels: flies the plan's wheel torques (the message's wheel_torque, or the
  /// plan's own wheelStates when it carries none) through body + wheels from `start`; fills
  /// playback->actual, wheel_flight and the result (errors, effort, the wheels' peaks and margins).
  void flyWheels(const AttitudeManeuver& msg, const Maneuver& plan, const Matrix3& inertia,
                 SchemeKind scheme, const RigidBodyState& start, Playback* playback) const;
  /// feedback mode with wheels: the tracking law's torque distributed over the wheels and cut to
  /// their limits (trackWithWheels) from `start`; fills playback->actual, wheel_flight and the
  /// result (effort, deviation, the samples cut at a limit, the wheels' peaks and margins).
  void trackWheels(int steps, const Matrix3& inertia, SchemeKind scheme,
                   const RigidBodyState& start, Playback* playback) const;
  /// The wheels' peaks and margins of a flight into the result, and a limit it went past into
  /// its message.
  void reportWheelPeaks(const WheelFlight& flight, Playback* playback) const;
  /// With wheels: `wheel_states` (JointState: effort u_i(t); velocity the spin rates relative to
  /// the body, wheelSpinRates with the body rate `body_rate`, when the array has spin_inertia),
  /// `wheel_momentum` (h_w(t)) and the momentum bars at maneuver time t, stamped `stamp`.
  void publishWheels(const Playback& playback, double t, const Vector3& body_rate,
                     const ros::Time& stamp);
  /// The same topics for wheel torques u and momenta h_w given directly (external plant).
  void publishWheelValues(const Playback& playback, const Eigen::VectorXd& torque,
                          const Eigen::VectorXd& momentum, const Vector3& body_rate,
                          const ros::Time& stamp);
  /// `body_pose` (R), `attitude_error_vector` (log(R_dᵀR)) and `angular_velocity_error_vector`
  /// (e_Ω), stamped `stamp`.
  void publishStampedErrors(const Playback& playback, const Matrix3& body, const Matrix3& reference,
                            const TrackingErrors& errors, const ros::Time& stamp);
  /// replan mode, after the stream: the terminal errors and effort of the re-planned closed loop.
  void finishReplanResult(Playback* playback) const;
  /// Publishes one sample at maneuver time t, stamped `stamp`.
  void publishSample(const Playback& playback, double t, const ros::Time& stamp,
                     std::deque<Vector3>* trail);
  /// Publishes (latched, once) the planned path, the start and target ghosts and the cones.
  void publishManeuverMarkers(const Playback& playback);
  /// runReplay for a drift + two-input maneuver (at its nodes).
  void runDriftReplay(const Replay& replay);
  /// Sleeps until ROS time `t` (sim-time friendly); false if stopped meanwhile.
  bool sleepUntil(const ros::Time& t);
  /// Waits for a valid ROS clock (sim time); sets the run's start: `stamp` if it is in the future,
  /// else now + ~start_delay. False if stopped meanwhile.
  bool waitForClock(const ros::Time& stamp, ros::Time* start);
  /// The `attitude_path` LINE_STRIP through `tips` (world frame `frame`).
  visualization_msgs::Marker pathMarker(const std::string& frame, const std::string& ns,
                                        const std::vector<Vector3>& tips, float alpha) const;
  /// tf frame → body, the body markers and the trail at `stamp`.
  void publishPose(const Matrix3& R, const ros::Time& stamp, const std::string& world_frame,
                   const std::string& body_frame, const PrincipalBox& box,
                   const Vector3& trace_axis, std::deque<Vector3>* trail,
                   const visualization_msgs::MarkerArray& world_axes = {});
  /// After a rigid-body run: publishes world → body at the run's final attitude (external plant:
  /// the newest measured one) every 0.1 s (wall) until the next maneuver or shutdown (the replay
  /// thread's last job).
  void holdFinalAttitude();
  /// Publishes `done` (latched); with ~exit_when_done, then shuts the node down.
  void publishDone(ReplayResult result);
  /// Publishes the node's status on /diagnostics (the wall timer's callback).
  void publishDiagnostics();
  /// Remembers the body's state at the running run's next sample and that sample's stamp (what a
  /// new maneuver takes over from); `running` false: no run in progress.
  void noteNextSample(bool running, const RigidBodyState& body = {},
                      const ros::Time& stamp = ros::Time());

  ros::NodeHandle nh_;               ///< public handle: topics and the service resolve here
  ros::Subscriber maneuver_sub_;     ///< `maneuver`
  ros::Subscriber drift_sub_;        ///< `drift_maneuver`
  ros::Publisher control_pub_;       ///< `control` (u1, u2, 0) [rad/s], frame body (drift only)
  ros::Publisher torque_pub_;        ///< `torque` τ(t) [N·m], frame body
  ros::Publisher velocity_pub_;      ///< `angular_velocity` Ω(t) [rad/s], frame body
  ros::Publisher reference_pub_;     ///< `reference_pose` R_d(t)
  ros::Publisher error_pub_;         ///< `attitude_error` [rad]
  ros::Publisher rate_error_pub_;    ///< `angular_velocity_error` [rad/s]
  ros::Publisher marker_pub_;        ///< `body_marker`
  ros::Publisher trail_pub_;         ///< `attitude_trail`
  ros::Publisher text_pub_;          ///< `status_text`
  ros::Publisher path_pub_;          ///< `attitude_path` (latched)
  ros::Publisher ghost_pub_;         ///< `ghost_markers` (latched)
  ros::Publisher done_pub_;          ///< `done` (latched)
  ros::Publisher constraint_pub_;    ///< `constraint_markers` (latched)
  ros::Publisher legend_pub_;        ///< `legend` (latched): one text line per colour
  ros::Publisher command_pub_;       ///< `torque_command` (~plant external) [N·m], frame body
  ros::Publisher body_pose_pub_;     ///< `body_pose` R(t), frame world
  ros::Publisher error_vector_pub_;  ///< `attitude_error_vector` log(R_dᵀR) [rad], body
  ros::Publisher rate_error_vector_pub_;  ///< `angular_velocity_error_vector` e_Ω [rad/s], body
  ros::Subscriber odometry_sub_;          ///< `odometry` (~plant external)
  ros::Publisher diagnostics_pub_;        ///< /diagnostics
  ros::Publisher wheel_state_pub_;        ///< `wheel_states` sensor_msgs/JointState (with wheels)
  ros::Publisher wheel_momentum_pub_;     ///< `wheel_momentum` h_w(t) [N m s] (with wheels)
  ros::Publisher wheel_marker_pub_;       ///< `wheel_momentum_markers` bars (with wheels)
  ros::WallTimer diagnostics_timer_;      ///< every kDiagnosticsPeriod
  std::mutex health_mutex_;               ///< guards health_ (stream vs timer)
  TrackerHealth health_;                  ///< the newest sample's figures, for /diagnostics
  ros::Subscriber tf_sub_;                ///< /tf: who else publishes our body transform
  std::mutex frames_mutex_;               ///< guards the three below
  std::string claimed_world_, claimed_body_;      ///< the pair the current run publishes
  std::string frame_conflict_;                    ///< another publisher of it, when seen
  tf2_ros::TransformBroadcaster tf_broadcaster_;  ///< world → body
  TrackingMode mode_ = TrackingMode::Replay;      ///< ~mode
  double rate_ = 50.0;                            ///< ~rate [Hz]; 0 = at the nodes
  std::string trace_axis_name_ = "auto";          ///< ~trace_axis
  TrackingOptions tracking_;                      ///< ~feedback_frequency, ~feedback_damping
  double rate_factor_ = 1.0;                      ///< maneuver seconds per ROS second
  double start_delay_ = 0.5;                      ///< [s] ROS time before step 0
  std::string world_frame_;                       ///< fixed frame (empty header.frame_id)
  std::string body_frame_;                        ///< body frame (empty child_frame_id)
  double body_size_ = 1.0;                        ///< largest box edge [m]
  double axis_length_ = 0.9;                      ///< principal-axis arrow length [m]
  double path_radius_ = 1.2;                      ///< distance of the traced tip [m]
  double replan_period_ = 0.0;                    ///< ~replan_period [s]; 0 = T / 10
  bool plan_in_process_ = false;                  ///< ~plan_in_process (also for re-plans)
  bool exit_when_done_ = false;                   ///< shut down after `done`
  double planner_timeout_ = 30.0;                 ///< ~planner_timeout [s, wall]
  double takeover_tolerance_ = 0.25;              ///< ~takeover_tolerance [rad]
  PlantKind plant_ = PlantKind::Internal;         ///< ~plant
  double measurement_timeout_ = 0.5;              ///< ~measurement_timeout [s, ROS time]
  /// ~projection_tolerance [rad], ~rate_projection_tolerance: how far past a constraint a re-plan's
  /// start is moved onto it (farther: the re-plan is not sent)
  ProjectionTolerance projection_tolerance_;
  std::mutex odometry_mutex_;              ///< guards odometry_ (callback vs stream)
  nav_msgs::Odometry::ConstPtr odometry_;  ///< newest `odometry`, null before the first
  ros::Time odometry_received_;            ///< when it arrived (for an unstamped one)
  RigidBodyState last_measured_;           ///< the last usable measurement (for display)
  ros::Publisher wheel_command_pub_;       ///< `wheel_command` (~plant external, wheels)
  ros::Subscriber wheel_measurement_sub_;  ///< `wheel_measurement` (~plant external)
  sensor_msgs::JointState::ConstPtr wheel_measurement_;  ///< newest, guarded by odometry_mutex_
  ros::Time wheel_received_;                             ///< when it arrived
  /// ~replay_scene's effects, if set: they act during every replay instead of ~scene's own.
  std::optional<std::vector<EffectSpec>> replay_scene_effects_;

  std::mutex replay_mutex_;                  ///< guards replay_thread_ (start/stop from callbacks)
  std::thread replay_thread_;                ///< runs runReplay()
  std::atomic<bool> stop_{false};            ///< asks the replay thread to return
  std::atomic<bool> replacing_{false};       ///< the stop is for a new maneuver
  std::atomic<bool> done_published_{false};  ///< the replay thread's run has its `done`
  std::mutex body_mutex_;                    ///< guards the three below (stream vs callbacks)
  bool run_active_ = false;                  ///< a rigid-body run is streaming
  RigidBodyState next_body_;                 ///< the body at its next sample
  /// The frames and final attitude of the last finished rigid-body run (holdFinalAttitude);
  /// owned by the replay thread.
  struct HeldPose {
    std::string world_frame, body_frame;
    Matrix3 attitude;
  };
  std::optional<HeldPose> held_;
  ros::Time next_stamp_;  ///< that sample's stamp
};

}  // namespace attitude_planner
