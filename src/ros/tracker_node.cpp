#include "attitude_planner/ros/tracker_node.hpp"

#include <diagnostic_msgs/DiagnosticArray.h>

#include "attitude_planner/ros/markers.hpp"
#include "attitude_planner/ros/parameters.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <type_traits>

#include <geometry_msgs/PoseStamped.h>
#include <geometry_msgs/TransformStamped.h>
#include <geometry_msgs/Vector3Stamped.h>
#include <geometry_msgs/WrenchStamped.h>
#include <sensor_msgs/JointState.h>
#include <std_msgs/Float64.h>
#include <std_msgs/Float64MultiArray.h>

#include "attitude_planner/PlanAttitudeManeuver.h"
#include "attitude_planner/PlanDriftTwoInput.h"
#include "attitude_planner/PlanErrorCode.h"
#include "attitude_planner/analysis/wheel_plant.hpp"
#include "attitude_planner/dynamics/simulation.hpp"
#include "attitude_planner/io/scene.hpp"
#include "attitude_planner/planner.hpp"
#include "attitude_planner/planning/pointing.hpp"
#include "attitude_planner/ros/conversions.hpp"

namespace attitude_planner {

namespace rc = ros_conversions;

namespace {

/// Runs `work` on a detached thread; its future never blocks in its destructor (unlike
/// std::async's), so an answer nobody waits for any more (a new maneuver, a timeout) is simply
/// dropped. roscpp cannot cancel a service call: a hung one keeps its thread, not the caller.
template <class Work>
std::future<std::invoke_result_t<Work>> startDetached(Work work) {
  using Result = std::invoke_result_t<Work>;
  auto promise = std::make_shared<std::promise<Result>>();
  std::future<Result> future = promise->get_future();
  std::thread([promise, work = std::move(work)]() mutable {
    try {
      promise->set_value(work());
    } catch (...) {
      promise->set_exception(std::current_exception());  // rethrown by get()
    }
  }).detach();
  return future;
}

/// The plan's wheel torques u_k: the message's wheel_torque rows (named in errors), or the
/// plan's own (wheelStates) when it carries none.
std::vector<Eigen::VectorXd> wheelTorqueRows(const AttitudeManeuver& msg, const Maneuver& plan,
                                             const Matrix3& inertia, SchemeKind scheme,
                                             const ReactionWheels& wheels) {
  if (msg.wheel_torque.empty()) return wheelStates(scheme, inertia, wheels, plan).torque;
  return rc::wheelRowsFromMsg(msg.wheel_torque, plan.steps() + 1, wheels.count(),
                              "maneuver.wheel_torque");
}

/// Measured wheel momenta as a re-plan's initial_momentum: each within its ±H_i (a measurement
/// past a limit by round-off or noise would be refused by the planner).
std::vector<double> withinLimits(const ReactionWheels& wheels, const Eigen::VectorXd& momentum) {
  std::vector<double> out(momentum.size());
  for (int i = 0; i < momentum.size(); ++i) {
    out[i] = std::clamp(momentum(i), -wheels.momentumLimit(i), wheels.momentumLimit(i));
  }
  return out;
}

/// The end of sample j's hold: the next sample's time (the last sample's own: an empty hold).
double nextSampleTime(const std::vector<double>& times, std::size_t j) {
  return times[std::min(j + 1, times.size() - 1)];
}

}  // namespace

PrincipalBox principalBox(const Matrix3& inertia, double size) {
  const Eigen::SelfAdjointEigenSolver<Matrix3> eig(0.5 * (inertia + inertia.transpose()));
  PrincipalBox box;
  box.moments = eig.eigenvalues();
  box.axes = eig.eigenvectors();
  if (box.axes.determinant() < 0.0) box.axes.col(2) *= -1.0;  // right-handed
  const Vector3& J = box.moments;
  // Uniform box, edges a, b, c along the axes: J1 = m (b² + c²)/12 etc. ⇒ a² ∝ J2 + J3 − J1.
  Vector3 squared(J(1) + J(2) - J(0), J(0) + J(2) - J(1), J(0) + J(1) - J(2));
  squared = squared.cwiseMax(0.0);
  Vector3 edges = squared.cwiseSqrt();
  const double largest = edges.maxCoeff();
  edges = largest > 0.0 ? Vector3(edges * (size / largest)) : Vector3::Constant(size);
  box.dimensions = edges.cwiseMax(0.1 * size);
  return box;
}

/// A marker of `type` in `frame`, added, at the frame's origin with the identity orientation.
visualization_msgs::Marker newMarker(const std::string& frame, const ros::Time& stamp,
                                     const std::string& ns, int id, int type) {
  visualization_msgs::Marker m;
  m.header.frame_id = frame;
  m.header.stamp = stamp;
  m.ns = ns;
  m.id = id;
  m.type = type;
  m.action = visualization_msgs::Marker::ADD;
  m.pose.orientation.w = 1.0;
  return m;
}

/// An arrow from the frame's origin to `tip`: shaft and head diameters and head length [m].
visualization_msgs::Marker arrowMarker(const std::string& frame, const ros::Time& stamp,
                                       const std::string& ns, int id, const Vector3& tip,
                                       const Vector3& shaft_head_length,
                                       const std_msgs::ColorRGBA& tint) {
  visualization_msgs::Marker a = newMarker(frame, stamp, ns, id, visualization_msgs::Marker::ARROW);
  a.points.push_back(rc::xyzToMsg<geometry_msgs::Point>(Vector3::Zero()));
  a.points.push_back(rc::xyzToMsg<geometry_msgs::Point>(tip));
  a.scale.x = shaft_head_length.x();
  a.scale.y = shaft_head_length.y();
  a.scale.z = shaft_head_length.z();
  a.color = tint;
  return a;
}

visualization_msgs::MarkerArray bodyMarkers(const PrincipalBox& box, double axis_length,
                                            double path_radius, const std::string& body_frame,
                                            const ros::Time& stamp, const Vector3& trace_axis) {
  visualization_msgs::MarkerArray array;
  visualization_msgs::Marker m =
      newMarker(body_frame, stamp, "body", 0, visualization_msgs::Marker::CUBE);
  m.pose.orientation = rc::attitudeToMsg(box.axes);
  m.scale.x = box.dimensions.x();
  m.scale.y = box.dimensions.y();
  m.scale.z = box.dimensions.z();
  m.color = meaningColour("body", 0.85f);
  array.markers.push_back(m);
  const char* axes[3] = {"principal_axis_smallest", "principal_axis_middle",
                         "principal_axis_largest"};
  for (int i = 0; i < 3; ++i) {
    array.markers.push_back(
        arrowMarker(body_frame, stamp, axes[i], i + 1, axis_length * box.axes.col(i),
                    Vector3(0.04, 0.08, 0.15) * axis_length, meaningColour(axes[i])));
  }
  // The traced body axis up to the traced tip, linking the body to `attitude_path` (same colour).
  array.markers.push_back(
      arrowMarker(body_frame, stamp, "traced_axis", 4, path_radius * trace_axis.normalized(),
                  Vector3(0.015, 0.04, 0.06) * path_radius, meaningColour("traced_axis")));
  return array;
}

visualization_msgs::MarkerArray constraintMarkers(
    const std::vector<PlanningConstraint>& constraints, double length,
    const std::string& world_frame, const ros::Time& stamp) {
  visualization_msgs::MarkerArray array;
  constexpr int kSegments = 48;  // triangles around the cone
  int id = 0;
  for (const PlanningConstraint& c : constraints) {
    if (!c.isCone()) continue;
    const bool out = c.kind == ConstraintKind::KeepOut;
    // The cone: a fan of triangles from the apex (the body origin) to the circle of points at
    // slant distance `length` whose direction makes the half angle with s (any a in (0, π)).
    const std::string ns = out ? "keep_out" : "keep_in";
    visualization_msgs::Marker cone =
        newMarker(world_frame, stamp, ns, id, visualization_msgs::Marker::TRIANGLE_LIST);
    cone.scale.x = cone.scale.y = cone.scale.z = 1.0;
    cone.color = meaningColour(ns, 0.35f);  // translucent: the body shows through
    const Vector3 s = c.world_direction.normalized();
    const Vector3 e1 = s.unitOrthogonal();
    const Vector3 e2 = s.cross(e1);
    const auto rim = [&](int i) {
      const double phi = 2.0 * M_PI * i / kSegments;
      return Vector3(length * (std::cos(c.half_angle) * s +
                               std::sin(c.half_angle) * (std::cos(phi) * e1 + std::sin(phi) * e2)));
    };
    for (int i = 0; i < kSegments; ++i) {
      cone.points.push_back(rc::xyzToMsg<geometry_msgs::Point>(Vector3::Zero()));
      cone.points.push_back(rc::xyzToMsg<geometry_msgs::Point>(rim(i)));
      cone.points.push_back(rc::xyzToMsg<geometry_msgs::Point>(rim(i + 1)));
    }
    array.markers.push_back(cone);
    ++id;
  }
  return array;
}

Vector3 traceAxis(const std::string& name, const Matrix3& initial, const Matrix3& final) {
  if (name == "x") return Vector3::UnitX();
  if (name == "y") return Vector3::UnitY();
  if (name == "z") return Vector3::UnitZ();
  if (name != "auto") {
    throw InvalidInput("~trace_axis: unknown value '" + name + "' (expected x, y, z or auto)");
  }
  const Vector3 rotation = so3::log(Matrix3(initial.transpose() * final));  // body frame
  if (rotation.norm() == 0.0) return Vector3::UnitX();
  Eigen::Index least = 0;
  rotation.cwiseAbs().minCoeff(&least);  // the axis most perpendicular to the rotation axis
  return Vector3::Unit(least);
}

std::string defaultBodyFrame(const std::string& ns) {
  std::string stripped = ns;
  while (!stripped.empty() && stripped.front() == '/') stripped.erase(stripped.begin());
  while (!stripped.empty() && stripped.back() == '/') stripped.pop_back();
  return stripped.empty() ? "body" : stripped + "/body";
}

std::vector<int> decimatedIndices(int n, int max_points) {
  std::vector<int> indices;
  const int points = std::max(2, std::min(n + 1, max_points));
  for (int i = 0; i < points; ++i) {
    // Evenly spread, rounded: 0 and n exactly, strictly increasing since points <= n + 1.
    indices.push_back(static_cast<int>(std::lround(static_cast<double>(i) * n / (points - 1))));
  }
  return indices;
}

std::vector<double> sampleTimes(double duration, int steps, double rate, double rate_factor) {
  std::vector<double> times;
  if (rate == 0.0) {
    for (int k = 0; k <= steps; ++k) times.push_back(duration * k / steps);
    return times;
  }
  const double spacing = rate_factor / rate;  // maneuver seconds between samples
  for (long j = 0; j * spacing < duration; ++j) times.push_back(j * spacing);
  times.push_back(duration);
  return times;
}

PlanAttitudeManeuver::Request planRequestOf(const PlanningProblem& problem,
                                            const std::vector<EffectSpec>& effects) {
  PlanAttitudeManeuver::Request request;
  request.inertia = rc::inertiaToMsg(problem.inertia);
  request.allow_nonphysical_inertia = problem.allow_nonphysical_inertia;
  request.initial_attitude = rc::attitudeToMsg(problem.initial_attitude);
  request.initial_angular_velocity = rc::vectorToMsg(problem.initial_velocity);
  request.final_attitude = rc::attitudeToMsg(problem.final_attitude);
  request.final_angular_velocity = rc::vectorToMsg(problem.final_velocity);
  request.duration = problem.duration;
  request.steps = problem.steps;
  request.scheme = schemeName(problem.scheme);
  request.direction = directionName(problem.direction);
  request.extra_revolutions = problem.extra_revolutions;
  request.objective = objectiveName(problem.objective);
  request.time_margin = problem.time_margin;
  if (problem.end_condition.pointing()) {
    request.end_condition = "pointing";
    request.pointing_body_axis = rc::vectorToMsg(problem.end_condition.body_axis);
    request.pointing_world_direction = rc::vectorToMsg(problem.end_condition.world_direction);
  }
  for (const EffectSpec& e : effects) {
    // Noise is random: the replay adds it, the plan cannot know it.
    if (!std::holds_alternative<TorqueNoiseSpec>(e)) request.effects.push_back(rc::effectToMsg(e));
  }
  for (const PlanningConstraint& c : problem.constraints)
    request.constraints.push_back(rc::constraintToMsg(c));
  request.reaction_wheels = rc::reactionWheelsToMsg(problem.reaction_wheels);
  return request;
}

ReplanAnswer planRemainder(const PlanningProblem& rest, const std::vector<EffectSpec>& effects,
                           double start_time, const Maneuver& guess, ros::ServiceClient client) {
  ReplanAnswer answer;
  try {
    if (client.isValid()) {
      PlanAttitudeManeuver srv;
      srv.request = planRequestOf(rest, effects);
      srv.request.start_time = start_time;  // the service shifts the effects' clock itself
      srv.request.initial_guess = rc::maneuverToMsg(guess, rest, "", "", ros::Time());
      if (!client.call(srv)) {
        answer.error = "service " + client.getService() + " call failed";
      } else if (!srv.response.success) {
        answer.error = "planner: " + srv.response.message;
      } else {
        answer.plan = rc::maneuverFromMsg(srv.response.maneuver);
        answer.solve_time = srv.response.solve_time;
        answer.ok = true;
      }
      return answer;
    }
    SolverOptions options;
    options.warm_start = &guess;
    const PlanResult result = planManeuver(rest, options);  // rest's effects: already shifted
    answer.solve_time = result.solve_time_s;
    if (!result.converged()) {
      answer.error = "planner: " + result.message();
      return answer;
    }
    answer.plan = result.maneuver;
    answer.ok = true;
  } catch (const std::exception& e) {
    answer.ok = false;
    answer.error = e.what();
  }
  return answer;
}

void reportConstraintHealth(const ConstraintHealth& health, ReplayResult* result) {
  result->constraint_names = health.names();
  result->constraint_violations = health.worstViolations();
  std::string past;
  for (std::size_t i = 0; i < health.names().size(); ++i) {
    const double v = health.worstViolations()[i];
    if (v > 0.0) past += (past.empty() ? "" : ", ") + health.names()[i] + " by " + exactNumber(v);
  }
  // Said in words too: a run that went past a constraint is not what was planned.
  if (!past.empty()) result->message += "; past constraints along the flown path: " + past;
}

bool planScene(const PlanningProblem& problem, const std::vector<EffectSpec>& effects,
               ros::ServiceClient* client, const std::string& world_frame,
               const std::string& body_frame, AttitudeManeuver* msg, double* solve_time,
               double* cost, std::string* error) {
  if (client && client->isValid()) {
    PlanAttitudeManeuver srv;
    srv.request = planRequestOf(problem, effects);
    if (!client->call(srv)) {
      *error = "service " + client->getService() + " call failed";
      return false;
    }
    if (!srv.response.success) {
      *error = "planner: " + srv.response.message;
      return false;
    }
    *msg = srv.response.maneuver;
    // A scene is planned for this tracker: its frames, whatever the planner's defaults are.
    msg->header.frame_id = world_frame;
    msg->child_frame_id = body_frame;
    *solve_time = srv.response.solve_time;
    *cost = srv.response.cost;
    return true;
  }
  const PlanResult result = planManeuver(problem);
  if (!result.converged()) {
    *error = "planner: " + result.message();
    return false;
  }
  const bool wheels = problem.reaction_wheels.present();
  const WheelStates states =
      wheels ? wheelStates(problem.scheme, problem.inertia, problem.reaction_wheels,
                           result.maneuver, problem.worldDisturbance())
             : WheelStates();
  *msg = rc::maneuverToMsg(result.maneuver, problem, world_frame, body_frame, ros::Time::now(),
                           wheels ? &states : nullptr);
  *solve_time = result.solve_time_s;
  *cost = result.cost;
  return true;
}

bool planDriftScene(const DriftTwoInputRequest& request, ros::ServiceClient* client,
                    const std::string& world_frame, const std::string& body_frame,
                    DriftTwoInputManeuver* msg, double* solve_time, double* cost,
                    std::string* error) {
  if (client && client->isValid()) {
    PlanDriftTwoInput srv;
    srv.request.initial_attitude = rc::attitudeToMsg(request.g0);
    srv.request.final_attitude = rc::attitudeToMsg(request.g1);
    srv.request.duration = request.duration;
    srv.request.steps = request.steps;
    srv.request.control_weights = {request.weights.c1, request.weights.c2};
    srv.request.use_initial_costate = request.initial_costate.has_value();
    if (request.initial_costate) {
      srv.request.initial_costate = rc::vectorToMsg(*request.initial_costate);
    }
    if (!client->call(srv)) {
      *error = "service " + client->getService() + " call failed";
      return false;
    }
    if (!srv.response.success) {
      *error = "planner: " + srv.response.message;
      return false;
    }
    *msg = srv.response.maneuver;
    *solve_time = srv.response.solve_time;
    *cost = srv.response.cost;
    return true;
  }
  const ros::WallTime start = ros::WallTime::now();
  const DriftTwoInputPlan plan = planDriftTwoInput(request);
  if (!plan.converged()) {
    *error = "planner: " + plan.message;
    return false;
  }
  *msg = rc::driftManeuverToMsg(plan.trajectory, request.weights, world_frame, body_frame,
                                ros::Time::now());
  *solve_time = (ros::WallTime::now() - start).toSec();
  *cost = plan.cost;
  return true;
}

TrackerNode::TrackerNode(ros::NodeHandle& nh, ros::NodeHandle& pnh) : nh_(nh) {
  auto positive = [](double v) { return std::isfinite(v) && v > 0.0; };
  auto non_negative = [](double v) { return std::isfinite(v) && v >= 0.0; };
  auto non_empty = [](const std::string& s) { return !s.empty(); };
  rate_factor_ = readParam<double>(pnh, "rate_factor", 1.0, positive, "> 0");
  start_delay_ = readParam<double>(pnh, "start_delay", 0.5, non_negative, ">= 0 s");
  world_frame_ = readParam<std::string>(pnh, "world_frame", "world", non_empty, "non-empty");
  body_frame_ = readParam<std::string>(pnh, "body_frame", "");
  if (body_frame_.empty()) body_frame_ = defaultBodyFrame(nh_.getNamespace());
  body_size_ = readParam<double>(pnh, "body_size", 1.0, positive, "> 0 m");
  axis_length_ = readParam<double>(pnh, "axis_length", 0.9, positive, "> 0 m");
  path_radius_ = readParam<double>(pnh, "path_radius", 1.2, positive, "> 0 m");
  rate_ = readParam<double>(pnh, "rate", 50.0, non_negative, ">= 0 Hz, 0 = at the plan nodes");
  replan_period_ = readParam<double>(pnh, "replan_period", 0.0, non_negative, ">= 0 s, 0 = T / 10");
  tracking_.natural_frequency =
      readParam<double>(pnh, "feedback_frequency", 0.0, non_negative, ">= 0 rad/s, 0 = 40 / T");
  tracking_.damping = readParam<double>(pnh, "feedback_damping", 1.0, positive, "> 0");
  exit_when_done_ = readParam<bool>(pnh, "exit_when_done", false);
  std::string scene = readFileParam(pnh, "scene");  // absolute, package:// or relative
  std::string replay_scene = readFileParam(pnh, "replay_scene");
  // A run in another mode than the one asked for would be silently wrong: a bad name stops the
  // node (exit 78, naming the parameter and the accepted names).
  mode_ = readNamedParam(pnh, "mode", TrackingMode::Replay, kTrackingModeNames);
  const std::string mode = trackingModeName(mode_);
  trace_axis_name_ = readParam<std::string>(
      pnh, "trace_axis", "auto",
      [](const std::string& s) { return s == "x" || s == "y" || s == "z" || s == "auto"; },
      "one of x, y, z, auto");
  plan_in_process_ = readParam<bool>(pnh, "plan_in_process", false);
  const double planner_timeout = readParam<double>(pnh, "planner_timeout", 30.0, positive, "> 0 s");
  planner_timeout_ = planner_timeout;
  takeover_tolerance_ = readParam<double>(pnh, "takeover_tolerance", 0.25, positive, "> 0 rad");
  plant_ = readNamedParam(pnh, "plant", PlantKind::Internal, kPlantNames);
  measurement_timeout_ =
      readParam<double>(pnh, "measurement_timeout", 0.5, positive, "> 0 s (ROS time)");
  projection_tolerance_.cone_angle = readParam<double>(pnh, "projection_tolerance", 0.01,
                                                       non_negative, ">= 0 rad, 0 = never move");
  projection_tolerance_.rate_fraction = readParam<double>(
      pnh, "rate_projection_tolerance", 0.01, non_negative, ">= 0 (a fraction of the rate limit)");
  warnUnknownParameters(pnh);

  advertiseTopics();

  maneuver_sub_ = nh_.subscribe("maneuver", 1, &TrackerNode::onManeuver, this);
  tf_sub_ = nh_.subscribe("/tf", 100, &TrackerNode::onTf, this);
  drift_sub_ = nh_.subscribe("drift_maneuver", 1, &TrackerNode::onDriftManeuver, this);

  if (!replay_scene.empty()) {
    try {
      replay_scene_effects_ = loadScene(replay_scene).effects;
      ROS_INFO("runs act under the %zu effects of %s", replay_scene_effects_->size(),
               replay_scene.c_str());
    } catch (const std::exception& e) {
      // A replay under effects other than the requested ones would be silently wrong: refuse.
      ROS_ERROR("~replay_scene %s: %s", replay_scene.c_str(), e.what());
      ReplayResult failed;
      failed.success = false;
      failed.message = "~replay_scene " + replay_scene + ": " + e.what();
      publishDone(failed);
      return;
    }
  }
  if (scene.empty()) {
    ROS_INFO("attitude_tracker_node (%s): waiting for a maneuver on %s or %s", mode.c_str(),
             maneuver_sub_.getTopic().c_str(), drift_sub_.getTopic().c_str());
    return;
  }
  std::string error;
  if (planAndStartScene(scene, plan_in_process_, planner_timeout, &error)) return;
  ROS_ERROR("scene %s: %s", scene.c_str(), error.c_str());
  ReplayResult failed;
  failed.success = false;
  failed.message = "scene " + scene + ": " + error;
  publishDone(failed);
}

void TrackerNode::advertiseTopics() {
  torque_pub_ = nh_.advertise<geometry_msgs::WrenchStamped>("torque", 10);
  velocity_pub_ = nh_.advertise<geometry_msgs::Vector3Stamped>("angular_velocity", 10);
  reference_pub_ = nh_.advertise<geometry_msgs::PoseStamped>("reference_pose", 10);
  error_pub_ = nh_.advertise<std_msgs::Float64>("attitude_error", 10);
  rate_error_pub_ = nh_.advertise<std_msgs::Float64>("angular_velocity_error", 10);
  marker_pub_ = nh_.advertise<visualization_msgs::MarkerArray>("body_marker", 10, true);
  trail_pub_ = nh_.advertise<visualization_msgs::Marker>("attitude_trail", 10);
  text_pub_ = nh_.advertise<visualization_msgs::Marker>("status_text", 10);
  path_pub_ = nh_.advertise<visualization_msgs::Marker>("attitude_path", 1, true);
  ghost_pub_ = nh_.advertise<visualization_msgs::MarkerArray>("ghost_markers", 1, true);
  done_pub_ = nh_.advertise<ReplayResult>("done", 1, true);
  diagnostics_pub_ = nh_.advertise<diagnostic_msgs::DiagnosticArray>("/diagnostics", 10);
  diagnostics_timer_ =
      nh_.createWallTimer(ros::WallDuration(kDiagnosticsPeriod),
                          [this](const ros::WallTimerEvent&) { publishDiagnostics(); });
  constraint_pub_ = nh_.advertise<visualization_msgs::MarkerArray>("constraint_markers", 1, true);
  legend_pub_ = nh_.advertise<visualization_msgs::MarkerArray>("legend", 1, true);
  control_pub_ = nh_.advertise<geometry_msgs::Vector3Stamped>("control", 10);
  body_pose_pub_ = nh_.advertise<geometry_msgs::PoseStamped>("body_pose", 10);
  error_vector_pub_ = nh_.advertise<geometry_msgs::Vector3Stamped>("attitude_error_vector", 10);
  rate_error_vector_pub_ =
      nh_.advertise<geometry_msgs::Vector3Stamped>("angular_velocity_error_vector", 10);
  wheel_state_pub_ = nh_.advertise<sensor_msgs::JointState>("wheel_states", 10);
  wheel_momentum_pub_ = nh_.advertise<std_msgs::Float64MultiArray>("wheel_momentum", 10);
  wheel_marker_pub_ = nh_.advertise<visualization_msgs::MarkerArray>("wheel_momentum_markers", 10);
  if (plant_ == PlantKind::External) {
    command_pub_ = nh_.advertise<geometry_msgs::WrenchStamped>("torque_command", 10);
    // Only the newest state matters: a queue of one never feeds the law an old measurement.
    odometry_sub_ = nh_.subscribe("odometry", 1, &TrackerNode::onOdometry, this,
                                  ros::TransportHints().tcpNoDelay());
    // A maneuver with reaction wheels commands the wheels and measures their speeds.
    wheel_command_pub_ = nh_.advertise<sensor_msgs::JointState>("wheel_command", 10);
    wheel_measurement_sub_ = nh_.subscribe("wheel_measurement", 1, &TrackerNode::onWheelMeasurement,
                                           this, ros::TransportHints().tcpNoDelay());
  }
}

bool TrackerNode::planAndStartScene(const std::string& scene, bool plan_in_process,
                                    double planner_timeout, std::string* error) {
  try {
    const Scene parsed = loadScene(scene);
    const bool drift = parsed.system == SystemKind::DriftTwoInput;
    std::optional<DriftTwoInputRequest> drift_request;
    if (drift) drift_request = driftTwoInputRequest(parsed);  // refuses effects
    ros::ServiceClient client;
    if (!plan_in_process) {
      client = drift ? nh_.serviceClient<PlanDriftTwoInput>("plan_drift_two_input")
                     : nh_.serviceClient<PlanAttitudeManeuver>("plan_attitude_maneuver");
      ROS_INFO("planning %s with %s", scene.c_str(), client.getService().c_str());
      if (!client.waitForExistence(ros::Duration(planner_timeout))) {
        *error = "planner service " + client.getService() + " not available after " +
                 std::to_string(planner_timeout) + " s";
        return false;
      }
    } else {
      ROS_INFO("planning %s in-process", scene.c_str());
    }
    // On a detached thread with copies of everything, bounded by ~planner_timeout: a planner
    // that never answers leaves its call behind, not the node.
    struct Planned {
      bool ok = false;
      Replay replay;
      std::string error;
    };
    std::future<Planned> call =
        startDetached([drift, drift_request, parsed, plan_in_process, client, world = world_frame_,
                       body = body_frame_]() mutable {
          Planned out;
          out.replay.drift = drift;
          ros::ServiceClient* via = plan_in_process ? nullptr : &client;
          Replay& r = out.replay;
          out.ok = drift ? planDriftScene(*drift_request, via, world, body, &r.drift_msg,
                                          &r.plan_solve_time, &r.plan_cost, &out.error)
                         : planScene(parsed.problem, parsed.effects, via, world, body, &r.msg,
                                     &r.plan_solve_time, &r.plan_cost, &out.error);
          return out;
        });
    if (!plan_in_process && call.wait_for(std::chrono::duration<double>(planner_timeout)) !=
                                std::future_status::ready) {
      *error = "planner service " + client.getService() + " did not answer within " +
               exactNumber(planner_timeout) + " s (~planner_timeout)";
      return false;
    }
    Planned planned = call.get();
    if (!planned.ok) {
      *error = planned.error;
      return false;
    }
    Replay& replay = planned.replay;
    ROS_INFO("planned %s: cost %.6g, solve time %.3f s", scene.c_str(), replay.plan_cost,
             replay.plan_solve_time);
    replay.effects = parsed.effects;
    replay.scene_constraints = parsed.problem.constraints;
    replay.problem = parsed.problem;
    if (parsed.problem.end_condition.pointing() && !replay.msg.attitude.empty()) {
      replay.pointing = parsed.problem.end_condition;  // drawn, and its error reported
      // A pointing scene is flown, and re-planned, to the end attitude its plan chose.
      replay.problem->end_condition = EndCondition();
      replay.problem->final_attitude = rc::attitudeFromMsg(replay.msg.attitude.back(), "attitude");
    }
    startReplay(replay);
    return true;
  } catch (const std::exception& e) {
    *error = e.what();
    return false;
  }
}

TrackerNode::~TrackerNode() {
  stopReplay();
}

void TrackerNode::onManeuver(const AttitudeManeuver::ConstPtr& msg) {
  Replay replay;
  replay.msg = *msg;
  std::optional<RigidBodyState> body;
  ros::Time next;
  {
    std::lock_guard<std::mutex> lock(body_mutex_);
    if (run_active_) body = next_body_;
    next = next_stamp_;
  }
  if (body && !msg->attitude.empty()) {
    Matrix3 start;
    try {
      start = rc::attitudeFromMsg(msg->attitude[0], "maneuver.attitude[0]");
    } catch (const std::exception&) {
      startReplay(replay);  // refused by preparePlayback, naming the field
      return;
    }
    const double gap = so3::angleBetween(start, body->attitude);
    if (gap > takeover_tolerance_) {
      // Flying it would first pull the body across the gap: refused, the run in progress goes on.
      ReplayResult refused;
      refused.success = false;
      refused.mode = trackingModeName(mode_);
      refused.message = "maneuver refused: its start attitude[0] is " + exactNumber(gap) +
                        " rad from the body (~takeover_tolerance " +
                        exactNumber(takeover_tolerance_) + " rad); the run in progress goes on";
      refused.header.stamp = ros::Time::now();
      refused.header.frame_id = world_frame_;
      ROS_WARN("%s", refused.message.c_str());
      done_pub_.publish(refused);
      return;
    }
    replay.takeover = body;  // flown from where the body is: no jump to the new plan's R_0
    replay.continue_at = next;
  }
  startReplay(replay);
}

void TrackerNode::onDriftManeuver(const DriftTwoInputManeuver::ConstPtr& msg) {
  Replay replay;
  replay.drift = true;
  replay.drift_msg = *msg;
  startReplay(replay);
}

void TrackerNode::stopReplay() {
  std::lock_guard<std::mutex> lock(replay_mutex_);
  stop_ = true;
  if (replay_thread_.joinable()) replay_thread_.join();
  stop_ = false;
}

void TrackerNode::startReplay(Replay replay) {
  if (replay_scene_effects_) replay.effects = *replay_scene_effects_;
  replacing_ = true;
  stopReplay();  // returns within a sample: nothing in the stream waits for a planner
  replacing_ = false;
  std::lock_guard<std::mutex> lock(replay_mutex_);
  replay_thread_ = std::thread([this, replay]() {
    done_published_ = false;
    held_.reset();
    runReplay(replay);
    noteNextSample(false);
    if (!done_published_ && replacing_) {
      ReplayResult replaced;
      replaced.success = false;
      replaced.mode = trackingModeName(mode_);
      replaced.message = "replaced by a new maneuver before the end of the run";
      replaced.header.stamp = ros::Time::now();
      replaced.header.frame_id = world_frame_;
      done_pub_.publish(replaced);  // not publishDone: ~exit_when_done waits for the last run
    }
    holdFinalAttitude();
  });
}

void TrackerNode::noteNextSample(bool running, const RigidBodyState& body, const ros::Time& stamp) {
  std::lock_guard<std::mutex> lock(body_mutex_);
  run_active_ = running;
  if (!running) return;
  next_body_ = body;
  next_stamp_ = stamp;
}

bool TrackerNode::sleepUntil(const ros::Time& t) {
  // Short wall sleeps so that a stop request or a paused /clock never blocks shutdown.
  while (!stop_ && ros::ok()) {
    const ros::Time now = ros::Time::now();
    if (!now.isZero() && now >= t) return true;
    const double remaining = now.isZero() ? 0.01 : (t - now).toSec();
    ros::WallDuration(std::min(0.01, std::max(1e-4, remaining))).sleep();
  }
  return false;
}

bool TrackerNode::waitForClock(const ros::Time& stamp, ros::Time* start) {
  // use_sim_time: ROS time is zero until the first /clock message.
  constexpr double kClockSilenceWarning = 2.0;  // [s] wall time before saying why nothing moves
  const ros::WallTime waiting_since = ros::WallTime::now();
  while (ros::Time::now().isZero()) {
    if (stop_ || !ros::ok()) return false;
    if ((ros::WallTime::now() - waiting_since).toSec() > kClockSilenceWarning)
      ROS_WARN_ONCE("/use_sim_time is true and no /clock is published: waiting for /clock");
    ros::WallDuration(0.01).sleep();
  }
  const ros::Time now = ros::Time::now();
  // A maneuver stamped in the future starts then (t_0 = header.stamp); else after ~start_delay.
  *start = stamp > now ? stamp : now + ros::Duration(start_delay_);
  return true;
}

visualization_msgs::Marker TrackerNode::pathMarker(const std::string& frame, const std::string& ns,
                                                   const std::vector<Vector3>& tips,
                                                   float alpha) const {
  visualization_msgs::Marker path =
      newMarker(frame, ros::Time(), ns, 0, visualization_msgs::Marker::LINE_STRIP);
  path.scale.x = 0.02 * path_radius_;  // line width [m]
  path.color = meaningColour(ns, alpha);
  for (const Vector3& tip : tips) path.points.push_back(rc::xyzToMsg<geometry_msgs::Point>(tip));
  return path;
}

void TrackerNode::publishPose(const Matrix3& R, const ros::Time& stamp,
                              const std::string& world_frame, const std::string& body_frame,
                              const PrincipalBox& box, const Vector3& trace_axis,
                              std::deque<Vector3>* trail,
                              const visualization_msgs::MarkerArray& world_axes) {
  geometry_msgs::TransformStamped tf;
  tf.header.stamp = stamp;
  tf.header.frame_id = world_frame;
  tf.child_frame_id = body_frame;
  tf.transform.rotation = rc::attitudeToMsg(R);
  tf_broadcaster_.sendTransform(tf);
  visualization_msgs::MarkerArray markers =
      bodyMarkers(box, axis_length_, path_radius_, body_frame, stamp, trace_axis);
  markers.markers.insert(markers.markers.end(), world_axes.markers.begin(),
                         world_axes.markers.end());
  marker_pub_.publish(markers);
  trail->push_back(path_radius_ * (R * trace_axis));
  while (trail->size() > static_cast<std::size_t>(kTrailPoints)) trail->pop_front();
  if (trail->size() >= 2) {
    visualization_msgs::Marker m = pathMarker(
        world_frame, "attitude_trail", std::vector<Vector3>(trail->begin(), trail->end()), 1.0f);
    m.header.stamp = stamp;
    m.scale.x = 0.03 * path_radius_;
    trail_pub_.publish(m);
  }
}

void TrackerNode::publishDone(ReplayResult result) {
  done_published_ = true;
  {
    std::lock_guard<std::mutex> lock(health_mutex_);
    health_.running = false;
    ++health_.runs_finished;
  }
  if (result.header.frame_id.empty()) result.header.frame_id = world_frame_;
  if (result.header.stamp.isZero()) result.header.stamp = ros::Time::now();
  done_pub_.publish(result);
  if (exit_when_done_) {
    // Give latched subscribers (rosbag record, scripts) a moment to receive `done`.
    ros::WallDuration(1.0).sleep();
    ROS_INFO("exit_when_done: shutting down");
    ros::requestShutdown();
  }
}

void TrackerNode::runBody(const Replay& replay, const Maneuver& plan, const Matrix3& inertia,
                          SchemeKind scheme, Playback* pb) const {
  ReplayResult& result = pb->result;
  const int N = plan.steps();
  // A maneuver that replaced a running one starts where that body is; else at the plan's start.
  const RigidBodyState start =
      replay.takeover.value_or(RigidBodyState{plan.attitude[0], plan.angular_velocity[0]});
  if (mode_ == TrackingMode::Replan) {
    pb->replan_period_steps = replanPeriodSteps(replan_period_, N, plan.time_step);
    // The closed loop on the first plan until a re-plan is adopted (serviceReplans).
    pb->horizon = std::make_shared<RecedingHorizonRun>(
        plan, scheme, inertia, pb->effects, actuationOf(replay.effects), tracking_, start);
    finishReplanResult(pb);
    return;
  }
  if (mode_ == TrackingMode::Feedback && pb->wheels.present()) {
    trackWheels(N, inertia, scheme, start, pb);
  } else if (mode_ == TrackingMode::Feedback) {
    Actuation actuation = actuationOf(replay.effects);
    const TrackingRun run = simulateTracking(*pb->reference, start.attitude, start.angular_velocity,
                                             pb->effects.get(), &actuation, tracking_);
    result.effort = run.effort;
    result.cost = run.effort / plan.time_step;  // the same units as the replay's Σ ½|τ_k|²
    result.max_attitude_deviation = run.max_attitude_error;
    result.message = "tracked " + std::to_string(N) + " steps with feedback (omega_n " +
                     exactNumber(run.natural_frequency) + " rad/s, " +
                     std::to_string(run.substeps) + " control samples per step)";
    pb->actual = std::make_unique<ManeuverInterpolation>(run.actual, scheme, inertia, nullptr,
                                                         TorqueHold::StepStart);
  } else if (pb->wheels.present()) {
    flyWheels(replay.msg, plan, inertia, scheme, start, pb);
  } else {
    // Exactly the effects of the run's scene: forcing on the body, then what the actuators do.
    Actuation actuation = actuationOf(replay.effects);
    SimulationInput input;
    input.initial_attitude = start.attitude;
    input.initial_velocity = start.angular_velocity;
    input.torque = plan.torque;
    input.effects = pb->effects.get();
    input.actuation = &actuation;
    const Maneuver replayed = replayPlan(scheme, inertia, plan.time_step, input);
    result.cost = schemeCost(scheme, replayed.torque);
    result.effort = openLoopEffort(scheme, replayed);
    for (int k = 0; k <= N; ++k) {
      result.max_attitude_deviation = std::max(
          result.max_attitude_deviation, so3::angleBetween(plan.attitude[k], replayed.attitude[k]));
    }
    result.message = "replayed " + std::to_string(N) + " steps";
    pb->actual =
        std::make_unique<ManeuverInterpolation>(replayed, scheme, inertia, pb->effects.get());
  }
  const ManeuverSample end = pb->actual->at(pb->actual->duration());
  result.terminal_attitude_error = so3::angleBetween(plan.attitude[N], end.attitude);
  result.terminal_velocity_error = (end.angular_velocity - plan.angular_velocity[N]).norm();
  result.final_attitude = rc::attitudeToMsg(end.attitude);
}

TrackerNode::Playback TrackerNode::preparePlayback(const Replay& replay) const {
  Playback pb;
  const AttitudeManeuver& msg = replay.msg;
  const Maneuver plan = rc::maneuverFromMsg(msg);
  requireUniformTimeGrid(plan);
  const Matrix3 inertia = rc::inertiaFromMsg(msg.inertia);
  const int N = plan.steps();
  // The core validates the body (symmetric positive definite J) with the problem checks.
  PlanningProblem problem;
  problem.inertia = inertia;
  problem.allow_nonphysical_inertia = true;  // replaying only needs J SPD
  problem.duration = N * plan.time_step;
  problem.steps = N;
  problem.initial_attitude = plan.attitude.front();
  problem.initial_velocity = plan.angular_velocity.front();
  problem.final_attitude = plan.attitude.back();
  problem.final_velocity = plan.angular_velocity[N];
  if (!msg.scheme.empty()) problem.scheme = parseScheme(msg.scheme, "maneuver.scheme");
  for (std::size_t i = 0; i < msg.constraints.size(); ++i) {
    pb.constraints.push_back(rc::constraintFromMsg(
        msg.constraints[i], "maneuver.constraints[" + std::to_string(i) + "]"));
  }
  validateConstraints(pb.constraints, "maneuver.constraints");
  validateProblem(problem);
  pb.wheels = rc::reactionWheelsFromMsg(msg.reaction_wheels, "maneuver.reaction_wheels");
  if (pb.wheels.present()) requireWheelFlight(pb.wheels, replay.effects);
  if (pb.constraints.empty()) pb.constraints = replay.scene_constraints;
  // What a re-plan solves: the scene's problem, or the message's own; either way under the
  // effects of the run (the body's environment), so a re-plan also corrects a model mismatch.
  pb.problem = replay.problem ? *replay.problem : problem;
  if (!replay.problem) pb.problem.constraints = pb.constraints;
  pb.problem.steps = N;  // the plan's grid (an accuracy target may have chosen it)
  pb.problem.duration = problem.duration;
  pb.problem.scheme = problem.scheme;
  pb.problem.max_torque = Vector3::Constant(std::numeric_limits<double>::infinity());
  applyEffects(replay.effects, &pb.problem);
  pb.effects_specs = replay.effects;
  pb.pointing = replay.pointing;
  pb.health = std::make_shared<ConstraintHealth>(pb.problem.max_torque, pb.problem.constraints);

  pb.world_frame = msg.header.frame_id.empty() ? world_frame_ : msg.header.frame_id;
  pb.body_frame = msg.child_frame_id.empty() ? body_frame_ : msg.child_frame_id;
  pb.box = principalBox(inertia, body_size_);
  pb.trace_axis = traceAxis(trace_axis_name_, plan.attitude.front(), plan.attitude.back());
  pb.effects = plannableEffects(replay.effects, inertia);
  pb.reference =
      std::make_unique<ManeuverInterpolation>(plan, problem.scheme, inertia, pb.effects.get());
  // Wheels on a plant read at every sample: the user's (external), or the tracker's own when
  // re-plans or effects act on it (the flights of runBody have neither).
  const bool wheel_loop =
      pb.wheels.present() &&
      (plant_ == PlantKind::External || mode_ == TrackingMode::Replan || !replay.effects.empty());
  if (!wheel_loop && plant_ == PlantKind::Internal) {
    runBody(replay, plan, inertia, problem.scheme, &pb);
  } else if (wheel_loop) {
    // The plan's wheel torques (replay's command) and the peaks along the loop.
    pb.plan_wheel_torque = wheelTorqueRows(msg, plan, inertia, problem.scheme, pb.wheels);
    pb.measured_wheel_peaks = WheelPeaks(pb.wheels.count());
    pb.problem.reaction_wheels = pb.wheels;  // a re-plan's array (its momenta: the plant's)
    if (plant_ == PlantKind::Internal) {
      const RigidBodyState start =
          replay.takeover.value_or(RigidBodyState{plan.attitude[0], plan.angular_velocity[0]});
      pb.wheel_plant = std::make_shared<WheelPlant>(inertia, pb.wheels, start,
                                                    0.25 * plan.time_step, pb.effects);
    }
  }
  if ((plant_ == PlantKind::External || pb.wheel_plant) && mode_ == TrackingMode::Replan) {
    // External: the plans in force and their laws; its own simulated body is not flown.
    pb.replan_period_steps = replanPeriodSteps(replan_period_, N, plan.time_step);
    pb.horizon = std::make_shared<RecedingHorizonRun>(plan, problem.scheme, inertia, pb.effects,
                                                      Actuation(), tracking_);
  }
  pb.times = sampleTimes(problem.duration, N, rate_, rate_factor_);
  ReplayResult& result = pb.result;
  result.mode = trackingModeName(mode_);
  for (const EffectSpec& e : replay.effects) result.replay_effects.push_back(effectName(e));
  result.steps = N;
  result.duration = problem.duration;
  result.plan_solve_time = replay.plan_solve_time;
  result.plan_cost = replay.plan_cost;
  return pb;
}

void TrackerNode::publishManeuverMarkers(const Playback& pb) {
  const ManeuverInterpolation& plan = *pb.reference;
  const Maneuver& nodes = plan.nodes();
  // The planned path of the traced tip, once: at most kMaxPathPoints nodes.
  std::vector<Vector3> tips;
  for (int k : decimatedIndices(plan.steps(), kMaxPathPoints))
    tips.push_back(path_radius_ * (nodes.attitude[k] * pb.trace_axis));
  path_pub_.publish(pathMarker(pb.world_frame, "attitude_path", tips, 0.6f));
  // Start and target ghosts: the box at R_0 (grey) and R_N (white), translucent, in the world.
  visualization_msgs::MarkerArray ghosts;
  // The previous maneuver's ghosts and cones go first (DELETEALL), also when this one has none.
  visualization_msgs::Marker clear;
  clear.action = visualization_msgs::Marker::DELETEALL;
  ghosts.markers.push_back(clear);
  const std::pair<const char*, int> ends[2] = {{"start_ghost", 0}, {"target_ghost", plan.steps()}};
  for (const auto& [ns, k] : ends) {
    visualization_msgs::Marker box =
        newMarker(pb.world_frame, ros::Time(), ns, 0, visualization_msgs::Marker::CUBE);
    box.pose.orientation = rc::attitudeToMsg(Matrix3(nodes.attitude[k] * pb.box.axes));
    box.scale.x = pb.box.dimensions.x();
    box.scale.y = pb.box.dimensions.y();
    box.scale.z = pb.box.dimensions.z();
    box.color = meaningColour(ns, 0.3f);
    ghosts.markers.push_back(box);
    ghosts.markers.push_back(arrowMarker(pb.world_frame, ros::Time(), std::string(ns) + "_axis", 1,
                                         path_radius_ * (nodes.attitude[k] * pb.trace_axis),
                                         Vector3(0.015, 0.04, 0.06) * path_radius_,
                                         meaningColour(std::string(ns) + "_axis", 0.4f)));
  }
  ghost_pub_.publish(ghosts);
  // The cones and the world directions they and a pointing target refer to (the Sun arrow).
  visualization_msgs::MarkerArray cones;
  cones.markers.push_back(clear);
  for (const visualization_msgs::MarkerArray& part :
       {constraintMarkers(pb.constraints, path_radius_, pb.world_frame, ros::Time()),
        worldDirectionMarkers(pb.constraints, pb.pointing, path_radius_, pb.world_frame)}) {
    cones.markers.insert(cones.markers.end(), part.markers.begin(), part.markers.end());
  }
  constraint_pub_.publish(cones);
  legend_pub_.publish(legendMarkers(pb.world_frame, path_radius_));
}

void TrackerNode::publishSample(const Playback& pb, double t, const ros::Time& stamp,
                                std::deque<Vector3>* trail) {
  // replan: the body under the plans adopted so far, the reference the plan in force.
  const ManeuverSample body = pb.horizon ? pb.horizon->bodyAt(t) : pb.actual->at(t);
  const ManeuverSample plan = pb.horizon ? pb.horizon->referenceAt(t) : pb.reference->at(t);
  pb.health->observe(body.attitude, body.angular_velocity, body.torque);
  publishState(pb, body, plan, t, stamp, trail);
  if (pb.wheel_flight) publishWheels(pb, t, body.angular_velocity, stamp);
}

void TrackerNode::requireWheelFlight(const ReactionWheels& wheels,
                                     const std::vector<EffectSpec>& effects) const {
  const std::string field = "maneuver.reaction_wheels";
  validateReactionWheels(wheels, field);
  if (plant_ == PlantKind::External && !wheels.hasSpinInertia()) {
    throw InvalidInput(field + ".spin_inertia",
                       "~plant external measures the wheels' spin rates (wheel_measurement "
                       "velocity) and needs each wheel's spin inertia to turn them into momenta, "
                       "got none");
  }
  rc::requireWheelBodyEffects(effects, field + ", effects during the run");
}

void TrackerNode::flyWheels(const AttitudeManeuver& msg, const Maneuver& plan,
                            const Matrix3& inertia, SchemeKind scheme, const RigidBodyState& start,
                            Playback* pb) const {
  const int N = plan.steps();
  auto flight = std::make_shared<WheelFlight>(
      flyWithWheels(inertia, scheme, pb->wheels, plan,
                    wheelTorqueRows(msg, plan, inertia, scheme, pb->wheels), start));
  ReplayResult& result = pb->result;
  result.cost = schemeCost(scheme, flight->body.torque);
  result.effort = openLoopEffort(scheme, flight->body);
  for (int k = 0; k <= N; ++k) {
    result.max_attitude_deviation =
        std::max(result.max_attitude_deviation,
                 so3::angleBetween(plan.attitude[k], flight->body.attitude[k]));
  }
  result.message = "flew " + std::to_string(N) + " steps with " +
                   std::to_string(pb->wheels.count()) +
                   " reaction wheels (body + wheels from the wheel torques, " +
                   (schemeIsDiscretization(scheme) ? "on the plan's scheme " + schemeName(scheme)
                                                   : std::string("continuous, RK4")) +
                   ")";
  reportWheelPeaks(*flight, pb);
  pb->actual = std::make_unique<ManeuverInterpolation>(flight->body, scheme, inertia, nullptr);
  pb->wheel_flight = std::move(flight);
}

void TrackerNode::trackWheels(int steps, const Matrix3& inertia, SchemeKind scheme,
                              const RigidBodyState& start, Playback* pb) const {
  auto run = std::make_shared<WheelTracking>(
      trackWithWheels(*pb->reference, inertia, pb->wheels, start, tracking_));
  ReplayResult& result = pb->result;
  result.effort = run->effort;
  result.cost = run->effort / pb->reference->nodes().time_step;  // as the feedback mode's
  for (int j = 0; j <= run->samples; ++j) {
    const double t = j * run->flight.body.time_step;
    result.max_attitude_deviation =
        std::max(result.max_attitude_deviation,
                 so3::angleBetween(pb->reference->at(t).attitude, run->flight.body.attitude[j]));
  }
  result.message = "tracked " + std::to_string(steps) + " steps with feedback through " +
                   std::to_string(pb->wheels.count()) + " reaction wheels (omega_n " +
                   exactNumber(run->natural_frequency) + " rad/s, " +
                   std::to_string(run->substeps) + " control samples per step, minimum-norm " +
                   "distribution; " + std::to_string(run->saturated_samples) + " of " +
                   std::to_string(run->samples) + " samples cut at a wheel limit)";
  reportWheelPeaks(run->flight, pb);
  pb->actual = std::make_unique<ManeuverInterpolation>(run->flight.body, scheme, inertia, nullptr,
                                                       TorqueHold::StepStart);
  pb->wheel_flight = std::shared_ptr<const WheelFlight>(run, &run->flight);
}

void TrackerNode::reportWheelPeaks(const WheelFlight& flight, Playback* pb) const {
  ReplayResult& result = pb->result;
  result.reaction_wheels = rc::wheelSummaryToMsg(pb->wheels, flight.peaks);
  std::string which;
  const double excess = flight.peaks.worstExcess(pb->wheels, &which);
  if (excess > 0.0)
    result.message += "; past a wheel limit: " + which + " by " + exactNumber(excess);
}

void TrackerNode::publishWheels(const Playback& pb, double t, const Vector3& body_rate,
                                const ros::Time& stamp) {
  publishWheelValues(pb, pb.wheel_flight->torqueAt(t), pb.wheel_flight->momentumAt(t), body_rate,
                     stamp);
}

void TrackerNode::publishWheelValues(const Playback& pb, const Eigen::VectorXd& torque,
                                     const Eigen::VectorXd& momentum, const Vector3& body_rate,
                                     const ros::Time& stamp) {
  // Spin rates relative to the body need the wheels' spin inertia; without it velocity stays
  // empty (a JointState field may be empty).
  const Eigen::VectorXd spin = pb.wheels.hasSpinInertia()
                                   ? wheelSpinRates(pb.wheels, momentum, body_rate)
                                   : Eigen::VectorXd();
  std_msgs::Float64MultiArray momenta;
  momenta.layout.dim.resize(1);
  momenta.layout.dim[0].label = "wheel";
  momenta.layout.dim[0].size = pb.wheels.count();
  momenta.layout.dim[0].stride = pb.wheels.count();
  for (int i = 0; i < pb.wheels.count(); ++i) momenta.data.push_back(momentum(i));
  // effort u_i [N m]; velocity w_i [rad/s] relative to the body
  wheel_state_pub_.publish(rc::wheelJointState(torque, spin, pb.body_frame, stamp));
  wheel_momentum_pub_.publish(momenta);
  wheel_marker_pub_.publish(
      wheelMomentumMarkers(pb.wheels, momentum, path_radius_, pb.world_frame, stamp));
}

void TrackerNode::publishStampedErrors(const Playback& pb, const Matrix3& body,
                                       const Matrix3& reference, const TrackingErrors& e,
                                       const ros::Time& stamp) {
  // For rqt_plot and bag analysis: the body's attitude and the error vectors, stamped.
  geometry_msgs::PoseStamped pose;
  pose.header.stamp = stamp;
  pose.header.frame_id = pb.world_frame;
  pose.pose.orientation = rc::attitudeToMsg(body);
  body_pose_pub_.publish(pose);
  geometry_msgs::Vector3Stamped error;
  error.header.stamp = stamp;
  error.header.frame_id = pb.body_frame;
  error.vector = rc::vectorToMsg(so3::log(Matrix3(reference.transpose() * body)));
  error_vector_pub_.publish(error);
  error.vector = rc::vectorToMsg(e.rate);
  rate_error_vector_pub_.publish(error);
}

void TrackerNode::publishState(const Playback& pb, const ManeuverSample& body,
                               const ManeuverSample& plan, double t, const ros::Time& stamp,
                               std::deque<Vector3>* trail) {
  // The constrained body axes and the boresight in the world frame, from the attitude itself:
  // drawn whatever the order in which tf and markers reach rviz (a frame-locked marker in the body
  // frame, latched before the body frame existed, was never drawn).
  publishPose(body.attitude, stamp, pb.world_frame, pb.body_frame, pb.box, pb.trace_axis, trail,
              bodyAxisMarkers(pb.constraints, pb.pointing, body.attitude, path_radius_,
                              pb.world_frame, stamp));

  geometry_msgs::WrenchStamped wrench;
  wrench.header.stamp = stamp;
  wrench.header.frame_id = pb.body_frame;
  wrench.wrench.torque = rc::vectorToMsg(body.torque);
  torque_pub_.publish(wrench);
  geometry_msgs::Vector3Stamped velocity;
  velocity.header = wrench.header;
  velocity.vector = rc::vectorToMsg(body.angular_velocity);
  velocity_pub_.publish(velocity);

  geometry_msgs::PoseStamped reference;
  reference.header.stamp = stamp;
  reference.header.frame_id = pb.world_frame;
  reference.pose.orientation = rc::attitudeToMsg(plan.attitude);
  reference_pub_.publish(reference);
  AttitudeReference ref;
  ref.attitude = plan.attitude;
  ref.angular_velocity = plan.angular_velocity;
  const TrackingErrors e = trackingErrors(body.attitude, body.angular_velocity, ref);
  std_msgs::Float64 value;
  value.data = e.angle;
  error_pub_.publish(value);
  value.data = e.rate.norm();
  rate_error_pub_.publish(value);
  publishStampedErrors(pb, body.attitude, plan.attitude, e, stamp);
  {
    std::lock_guard<std::mutex> lock(health_mutex_);
    health_.running = true;
    health_.time = t;
    health_.duration = pb.result.duration;
    health_.attitude_error = e.angle;
    health_.rate_error = e.rate.norm();
    health_.replans = pb.result.replans;
    health_.replan_failures = pb.result.replan_failures;
  }

  const Matrix3& target = pb.reference->nodes().attitude.back();
  char text[160];
  std::snprintf(text, sizeof text, "%s  t %.1f / %.1f s\nto go %.3f rad  |tau| %.3g N m",
                pb.result.mode.c_str(), t, pb.result.duration,
                so3::angleBetween(body.attitude, target), body.torque.norm());
  visualization_msgs::Marker label = newMarker(pb.world_frame, stamp, "status_text", 0,
                                               visualization_msgs::Marker::TEXT_VIEW_FACING);
  label.pose.position.z = 1.1 * body_size_ + 0.3 * path_radius_;
  label.scale.z = 0.12 * path_radius_;  // text height [m]
  label.color = meaningColour("status_text");
  label.text = text;
  if (pb.pointing) {
    char line[80];
    std::snprintf(line, sizeof line, "\npointing error %.3g rad",
                  pointingError(body.attitude, *pb.pointing));
    label.text += line;
  }
  if (!pb.replan_status.empty()) label.text += "\n" + pb.replan_status;
  text_pub_.publish(label);
}

void TrackerNode::runReplay(Replay replay) {
  if (replay.drift) {
    runDriftReplay(replay);
    return;
  }
  Playback pb;
  try {
    pb = preparePlayback(replay);
  } catch (const std::exception& e) {
    ROS_ERROR("maneuver rejected: %s", e.what());
    ReplayResult result;
    result.success = false;
    result.mode = trackingModeName(mode_);
    result.message = std::string("maneuver rejected: ") + e.what();
    publishDone(result);
    return;
  }
  ros::Time start;
  if (!waitForClock(replay.msg.header.stamp, &start)) return;
  claimFrames(pb.world_frame, pb.body_frame);
  if (replay.takeover && replay.msg.header.stamp <= ros::Time::now()) {
    start = std::max(replay.continue_at, ros::Time::now());  // the stream goes on at its rate
  }
  publishManeuverMarkers(pb);
  ROS_INFO("%s: %d steps over %.3f s, %zu samples (rate %g Hz, rate factor %g), frames %s -> %s",
           pb.result.mode.c_str(), pb.result.steps, pb.result.duration, pb.times.size(), rate_,
           rate_factor_, pb.world_frame.c_str(), pb.body_frame.c_str());
  std::deque<Vector3> trail;
  ReplanState replans;
  replans.period_steps = pb.replan_period_steps;
  replans.next_node = replans.period_steps;
  if (plant_ == PlantKind::External || pb.wheel_plant) {
    if (!runExternal(start, &pb, &replans)) return;
  } else {
    for (std::size_t j = 0; j < pb.times.size(); ++j) {
      const double t = pb.times[j];
      const ros::Time stamp = start + ros::Duration(t / rate_factor_);
      if (!sleepUntil(stamp)) return;
      if (pb.horizon) serviceReplans(t, &pb, &replans);
      publishSample(pb, t, stamp, &trail);
      if (j + 1 < pb.times.size()) {  // what a new maneuver would start from
        const double next = pb.times[j + 1];
        const ManeuverSample body = pb.horizon ? pb.horizon->bodyAt(next) : pb.actual->at(next);
        noteNextSample(true, RigidBodyState{body.attitude, body.angular_velocity},
                       start + ros::Duration(next / rate_factor_));
      }
    }
    if (pb.horizon) finishReplanResult(&pb);  // a re-plan still in flight is not adopted
    pb.result.success = true;
  }
  ReplayResult result = pb.result;
  reportConstraintHealth(*pb.health, &result);
  const WheelPeaks* wheel_peaks = pb.wheel_flight           ? &pb.wheel_flight->peaks
                                  : pb.measured_wheel_peaks ? &*pb.measured_wheel_peaks
                                                            : nullptr;
  if (wheel_peaks) {  // the wheels' limits as one more constraint of the flown path
    result.constraint_names.push_back("reaction_wheels");
    result.constraint_violations.push_back(std::max(0.0, wheel_peaks->worstExcess(pb.wheels)));
  }
  if (pb.pointing) {
    result.pointing_error =
        pointingError(rc::attitudeFromMsg(result.final_attitude, "final_attitude"), *pb.pointing);
  }
  const std::string conflict = claimFrames(pb.world_frame, pb.body_frame);
  if (!conflict.empty()) {  // the run was shown on a transform another node also moved
    result.success = false;
    result.message += "; " + conflict;
  }
  result.header.frame_id = pb.world_frame;
  result.header.stamp = start + ros::Duration(pb.times.back() / rate_factor_);
  ROS_INFO("%s done: terminal attitude error %.3g rad, rate error %.3g rad/s vs the plan's end",
           result.mode.c_str(), result.terminal_attitude_error, result.terminal_velocity_error);
  publishDone(result);
  // The simulated body stays where it ended; an external body goes on moving (holdFinalAttitude
  // follows its measurements).
  held_ = HeldPose{pb.world_frame, pb.body_frame,
                   rc::attitudeFromMsg(result.final_attitude, "final_attitude")};
}

void TrackerNode::holdFinalAttitude() {
  if (!held_) return;
  // After a run the body stays where it ended: rviz and tf listeners keep the frame (before, tf
  // stopped with the last sample and the body's frame expired from every buffer).
  constexpr double kHoldPeriod = 0.1;  // [s, wall]
  geometry_msgs::TransformStamped tf;
  tf.header.frame_id = held_->world_frame;
  tf.child_frame_id = held_->body_frame;
  tf.transform.rotation = rc::attitudeToMsg(held_->attitude);
  while (!stop_ && ros::ok()) {
    const ros::Time now = ros::Time::now();
    if (!now.isZero() && now > tf.header.stamp) {  // sim time may pause: never a repeated stamp
      tf.header.stamp = now;
      if (plant_ == PlantKind::External) {  // the body where it is measured now, not where it was
        if (const std::optional<Matrix3> R = measuredAttitude(*held_))
          tf.transform.rotation = rc::attitudeToMsg(*R);
      }
      tf_broadcaster_.sendTransform(tf);
    }
    ros::WallDuration(kHoldPeriod).sleep();
  }
}

void TrackerNode::serviceReplans(double t, Playback* pb, ReplanState* state,
                                 const std::function<RigidBodyState(int)>& state_at_node,
                                 const std::function<Eigen::VectorXd(int)>& momentum_at_node) {
  RecedingHorizonRun& run = *pb->horizon;
  const int N = run.steps();
  const double h = run.timeStep();
  ReplayResult& result = pb->result;
  constexpr double kNodeSlack = 1e-9;  // a sample time k h in floating point is node k
  if (state->pending) {
    const double waited = (ros::WallTime::now() - state->sent).toSec();
    const bool ready = state->answer.wait_for(std::chrono::seconds(0)) == std::future_status::ready;
    if (!ready && waited <= planner_timeout_) {
      ++result.samples_during_replans;  // this sample goes out while the planner works
      return;
    }
    state->pending = false;
    ReplanAnswer answer;
    if (ready) {
      answer = state->answer.get();
    } else {  // abandoned: the detached call may go on, its answer is dropped
      state->answer = std::future<ReplanAnswer>();
      answer.error =
          "no answer within ~planner_timeout " + exactNumber(planner_timeout_) + " s (abandoned)";
    }
    const int from = state->pending_from;
    const int at = std::max(from, static_cast<int>(std::ceil(t / h - kNodeSlack)));
    char line[200];
    if (answer.ok && at < N) {
      try {
        run.adopt(answer.plan, from, at);
      } catch (const std::exception& e) {  // e.g. a plan of another grid: not flown
        answer.ok = false;
        answer.error = e.what();
      }
    }
    if (!answer.ok) {
      ++result.replan_failures;
      if (result.replan_error.empty()) result.replan_error = answer.error;
      ROS_WARN("re-plan from t = %.6g s failed, flying the plan in force: %s", from * h,
               answer.error.c_str());
      std::snprintf(line, sizeof line, "replan from t %.1f s failed (%d failed)", from * h,
                    result.replan_failures);
    } else if (at >= N) {
      std::snprintf(line, sizeof line, "replan from t %.1f s arrived after the end", from * h);
    } else {
      result.replans = run.adoptions();
      std::snprintf(line, sizeof line, "replan %d: from t %.1f s, flown from t %.1f s (%.3f s)",
                    result.replans, from * h, at * h, answer.solve_time);
    }
    pb->replan_status = line;
  }
  const int node = static_cast<int>(std::floor(t / h + kNodeSlack));
  if (node < state->next_node || node > lastReplanNode(N, h, run.naturalFrequency())) return;
  // The state the body has at this node under the plan in force, and that plan's rest.
  RigidBodyState body;
  if (state_at_node) {
    body = state_at_node(node);  // external plant: the measured state moved to the node
  } else {
    const ManeuverSample simulated = run.bodyAtNode(node);
    body = RigidBodyState{simulated.attitude, simulated.angular_velocity};
  }
  // As the scheme's boundary data (its Ω_0 may be the first step's rate), then onto the
  // constraints: the two moves a start needs so that the planner can fly on from it.
  body = schemeStartOf(pb->problem.scheme, pb->reference->inertia(), pb->effects.get(), body,
                       run.commandAt(body, node * h), node * h, h);
  if (!projectReplanStart(node * h, &body, pb)) {
    state->next_node = node + state->period_steps;  // the next node may be back within bounds
    return;
  }
  PlanningProblem rest;
  try {
    rest = remainderProblem(pb->problem, node, body.attitude, body.angular_velocity);
    if (momentum_at_node)
      rest.reaction_wheels.initial_momentum =
          withinLimits(rest.reaction_wheels, momentum_at_node(node));
  } catch (const std::exception& e) {
    ROS_WARN("re-plan from t = %.6g s not sent: %s", node * h, e.what());
    state->next_node = N + 1;
    return;
  }
  ros::ServiceClient client;
  if (!plan_in_process_) client = nh_.serviceClient<PlanAttitudeManeuver>("plan_attitude_maneuver");
  state->answer = startDetached(
      [rest, effects = pb->effects_specs, start_time = node * h, guess = run.planRemainderAt(node),
       client]() { return planRemainder(rest, effects, start_time, guess, client); });
  state->sent = ros::WallTime::now();
  state->pending = true;
  state->pending_from = node;
  state->next_node = node + state->period_steps;
}

bool TrackerNode::projectReplanStart(double t, RigidBodyState* body, Playback* pb) const {
  ReplayResult& result = pb->result;
  const double h = pb->reference->nodes().time_step;
  const ProjectedStart start =
      projectOntoConstraints(*body, pb->problem.constraints, projection_tolerance_,
                             firstStepFixedByStart(pb->problem.scheme) ? h : 0.0);
  if (!start.feasible) {
    // The planner would refuse this start (boundary data past a constraint): not sent, counted.
    const std::string error = "re-plan from t = " + exactNumber(t) +
                              " s not sent: " + start.refusal + " (~projection_tolerance)";
    ++result.replan_failures;
    if (result.replan_error.empty()) result.replan_error = error;
    ROS_WARN("%s", error.c_str());
    return false;
  }
  if (start.moved > 0.0 || start.slowed > 0.0) {
    ++result.projected_replans;
    ROS_INFO(
        "re-plan from t = %.6g s starts on the constraints: the body's attitude turned by "
        "%.3g rad, its rate reduced by %.3g rad/s",
        t, start.moved, start.slowed);
  }
  *body = start.state;
  return true;
}

void TrackerNode::onTf(const ros::MessageEvent<tf2_msgs::TFMessage const>& event) {
  const std::string& sender = event.getPublisherName();
  if (sender == ros::this_node::getName()) return;
  std::lock_guard<std::mutex> lock(frames_mutex_);
  if (claimed_body_.empty()) return;
  for (const geometry_msgs::TransformStamped& t : event.getMessage()->transforms) {
    if (t.child_frame_id != claimed_body_) continue;
    if (frame_conflict_.empty()) {
      frame_conflict_ = "node " + sender + " also publishes the transform " + t.header.frame_id +
                        " -> " + claimed_body_ + " (give each tracker its own ~body_frame; " +
                        "the default is NS/body in namespace /NS)";
      ROS_ERROR("%s", frame_conflict_.c_str());
    }
  }
}

std::string TrackerNode::claimFrames(const std::string& world_frame,
                                     const std::string& body_frame) {
  std::lock_guard<std::mutex> lock(frames_mutex_);
  claimed_world_ = world_frame;
  claimed_body_ = body_frame;
  std::string conflict;
  conflict.swap(frame_conflict_);
  return conflict;
}

void TrackerNode::publishDiagnostics() {
  TrackerHealth health;
  {
    std::lock_guard<std::mutex> lock(health_mutex_);
    health = health_;
  }
  health.mode = trackingModeName(mode_);
  health.plant = plant_ == PlantKind::External ? "external" : "internal";
  {
    std::lock_guard<std::mutex> lock(frames_mutex_);
    health.frame_conflict = frame_conflict_;
  }
  diagnostic_msgs::DiagnosticArray array;
  array.header.stamp = ros::Time::now();
  array.status.push_back(trackerStatus(ros::this_node::getName() + ": tracker", health));
  diagnostics_pub_.publish(array);
}

void TrackerNode::onOdometry(const nav_msgs::Odometry::ConstPtr& msg) {
  std::lock_guard<std::mutex> lock(odometry_mutex_);
  odometry_ = msg;
  odometry_received_ = ros::Time::now();
}

void TrackerNode::onWheelMeasurement(const sensor_msgs::JointState::ConstPtr& msg) {
  std::lock_guard<std::mutex> lock(odometry_mutex_);
  wheel_measurement_ = msg;
  wheel_received_ = ros::Time::now();
}

std::optional<Matrix3> TrackerNode::measuredAttitude(const HeldPose& frames) {
  nav_msgs::Odometry::ConstPtr msg;
  {
    std::lock_guard<std::mutex> lock(odometry_mutex_);
    msg = odometry_;
  }
  if (!msg) return std::nullopt;
  const std::string& frame = msg->header.frame_id;
  const std::string& child = msg->child_frame_id;
  if ((!frame.empty() && frame != frames.world_frame) ||
      (!child.empty() && child != frames.body_frame)) {
    return std::nullopt;
  }
  try {
    return rc::measuredStateFromMsg(*msg).attitude;
  } catch (const std::exception&) {
    return std::nullopt;  // a bad quaternion: the last good attitude stays
  }
}

MeasurementAtSample TrackerNode::measurementAt(const Playback& pb, const ros::Time& start,
                                               const ros::Time& stamp, const Vector3& held_command,
                                               bool predict) {
  nav_msgs::Odometry::ConstPtr msg;
  ros::Time received;
  {
    std::lock_guard<std::mutex> lock(odometry_mutex_);
    msg = odometry_;
    received = odometry_received_;
  }
  MeasurementAtSample m;
  m.state = last_measured_;
  if (!msg) {
    m.problem = "no measurement on " + odometry_sub_.getTopic() + " yet";
    return m;
  }
  // Empty frames are taken as the maneuver's; others must be its frames (no tf lookup: the
  // measured attitude is body -> world as the maneuver's is).
  const std::string& frame = msg->header.frame_id;
  const std::string& child = msg->child_frame_id;
  if ((!frame.empty() && frame != pb.world_frame) || (!child.empty() && child != pb.body_frame)) {
    m.problem = "odometry frames " + frame + " -> " + child + " are not the maneuver's " +
                pb.world_frame + " -> " + pb.body_frame;
    return m;
  }
  const ros::Time measured_at = msg->header.stamp.isZero() ? received : msg->header.stamp;
  const double age = (stamp - measured_at).toSec();  // [s, ROS time]
  {
    std::lock_guard<std::mutex> lock(health_mutex_);
    health_.measurement_age = age;
  }
  if (age > measurement_timeout_) {
    char text[160];
    std::snprintf(text, sizeof text, "newest odometry is %.3f s old (~measurement_timeout %g s)",
                  age, measurement_timeout_);
    m.problem = text;
    return m;
  }
  try {
    m.state = rc::measuredStateFromMsg(*msg);
  } catch (const std::exception& e) {
    m.problem = e.what();
    return m;
  }
  // To the sample's time under the command held meanwhile and the known effects: the age is
  // transport and sampling lag (left in, the rate's lag biases the law's damping term).
  m.time = (measured_at - start).toSec() * rate_factor_;
  m.age = age * rate_factor_;
  m.fresh = true;
  if (!predict) return m;
  m.state =
      predictState(pb.reference->inertia(), pb.effects.get(), m.state, held_command, m.time, m.age);
  last_measured_ = m.state;
  return m;
}

bool TrackerNode::runExternal(const ros::Time& start, Playback* pb, ReplanState* replans) {
  if (pb->wheels.present()) return runExternalWheels(start, pb, replans);
  const Maneuver& plan = pb->reference->nodes();
  const int N = plan.steps();
  const TrackingLaw law(*pb->reference, pb->effects.get(), tracking_);
  const Matrix3 plan_inertia = pb->reference->inertia();
  last_measured_.attitude = plan.attitude[0];  // drawn until a measurement arrives
  last_measured_.angular_velocity = plan.angular_velocity[0];
  ReplayResult& result = pb->result;
  int stale = 0;
  std::string first_problem;
  std::deque<Vector3> trail;
  geometry_msgs::WrenchStamped command;
  command.header.frame_id = pb->body_frame;
  Vector3 held_command = Vector3::Zero();  // what the body receives until the next command
  for (std::size_t j = 0; j < pb->times.size(); ++j) {
    const double t = pb->times[j];
    const ros::Time stamp = start + ros::Duration(t / rate_factor_);
    if (!sleepUntil(stamp)) return false;
    const MeasurementAtSample measured = measurementAt(*pb, start, stamp, held_command);
    {
      std::lock_guard<std::mutex> lock(health_mutex_);
      health_.measurement_problem = measured.problem;
    }
    ManeuverSample body;
    body.time = t;
    body.attitude = measured.state.attitude;
    body.angular_velocity = measured.state.angular_velocity;
    if (measured.fresh && pb->horizon) {  // replan: re-planned from the measured state
      const double h = plan.time_step;
      serviceReplans(t, pb, replans, [&](int k) {
        return predictState(plan_inertia, pb->effects.get(), measured.state, held_command, t,
                            k * h - t);
      });
      body.torque = pb->horizon->commandAt(measured.state, t);
    } else if (measured.fresh) {
      // replay: the plan's torque open loop, its mean over the hold to the next sample
      body.torque = mode_ == TrackingMode::Feedback
                        ? law.command(body.attitude, body.angular_velocity, t)
                        : pb->reference->meanTorque(t, nextSampleTime(pb->times, j));
    } else {
      ++stale;  // a zero command: nothing is known about the body to act on
      if (first_problem.empty()) first_problem = measured.problem;
      ROS_WARN_THROTTLE(1.0, "external plant: zero command at t = %.6g s: %s", t,
                        measured.problem.c_str());
    }
    command.header.stamp = stamp;
    command.wrench.torque = rc::vectorToMsg(body.torque);
    command_pub_.publish(command);
    held_command = body.torque;
    const ManeuverSample reference =
        pb->horizon ? pb->horizon->referenceAt(t) : pb->reference->at(t);
    if (measured.fresh) {
      result.max_attitude_deviation = std::max(
          result.max_attitude_deviation, so3::angleBetween(reference.attitude, body.attitude));
      pb->health->observe(body.attitude, body.angular_velocity, body.torque);
    }
    if (j + 1 < pb->times.size()) {  // held until the next sample
      result.effort += 0.5 * body.torque.squaredNorm() * (pb->times[j + 1] - t);
    }
    publishState(*pb, body, reference, t, stamp, &trail);
    if (j + 1 < pb->times.size()) {
      noteNextSample(true, measured.state, start + ros::Duration(pb->times[j + 1] / rate_factor_));
    }
  }
  command.header.stamp = ros::Time::now();
  command.wrench.torque = rc::vectorToMsg(Vector3::Zero());  // the run is over: nothing held
  command_pub_.publish(command);
  finishFromMeasuredEnd(*pb, stale, &result);
  result.message = (mode_ == TrackingMode::Feedback ? "tracked " : "commanded ") +
                   std::to_string(N) + " steps on the measured state of " +
                   odometry_sub_.getTopic() + " (external plant, omega_n " +
                   exactNumber(law.naturalFrequency()) + " rad/s)";
  if (stale > 0) {
    result.message +=
        ": " + std::to_string(stale) + " of " + std::to_string(pb->times.size()) +
        " samples had no fresh measurement and got a zero command (first: " + first_problem + ")";
  }
  return true;
}

MeasurementAtSample TrackerNode::wheelMeasurementAt(const Playback& pb, const ros::Time& start,
                                                    const ros::Time& stamp,
                                                    const Eigen::VectorXd& held,
                                                    Eigen::VectorXd* momentum) {
  const RigidBodyState last = last_measured_;
  MeasurementAtSample m = measurementAt(pb, start, stamp, Vector3::Zero(), false);
  if (!m.fresh) return m;
  sensor_msgs::JointState::ConstPtr wheels;
  ros::Time received;
  {
    std::lock_guard<std::mutex> lock(odometry_mutex_);
    wheels = wheel_measurement_;
    received = wheel_received_;
  }
  const auto unusable = [&](const std::string& why) {
    m.fresh = false;
    m.problem = why;
    m.state = last;
    last_measured_ = last;
    return m;
  };
  if (!wheels) return unusable("no measurement on " + wheel_measurement_sub_.getTopic() + " yet");
  const ros::Time taken = wheels->header.stamp.isZero() ? received : wheels->header.stamp;
  const double age = (stamp - taken).toSec();
  {
    std::lock_guard<std::mutex> lock(health_mutex_);
    health_.wheel_measurement_age = age;
  }
  if (age > measurement_timeout_) {
    return unusable("newest wheel_measurement is " + exactNumber(age) +
                    " s old (~measurement_timeout " + exactNumber(measurement_timeout_) + " s)");
  }
  try {
    // The tachometers read spin rates relative to the body: momenta with the measured body rate
    // (the plant stamps both alike, so they are taken as one instant).
    const Eigen::VectorXd rates = rc::wheelJointValues(
        wheels->name, wheels->velocity, pb.wheels.count(), "wheel_measurement.velocity");
    *momentum = wheelMomentaFromSpinRates(pb.wheels, rates, m.state.angular_velocity);
  } catch (const std::exception& e) {
    return unusable(e.what());
  }
  // To the sample's time under the wheel torques held meanwhile (transport and sampling lag).
  const WheelBodyState moved =
      predictWheelState(pb.reference->inertia(), wheelArray(pb.wheels), {m.state, *momentum}, held,
                        m.age, pb.effects.get(), m.time);
  m.state = moved.body;
  *momentum = moved.momentum;
  last_measured_ = m.state;
  return m;
}

void TrackerNode::finishFromMeasuredEnd(const Playback& pb, int stale, ReplayResult* result) const {
  const Maneuver& plan = pb.reference->nodes();
  const int N = plan.steps();
  result->terminal_attitude_error = so3::angleBetween(plan.attitude[N], last_measured_.attitude);
  result->terminal_velocity_error =
      (last_measured_.angular_velocity - plan.angular_velocity[N]).norm();
  result->final_attitude = rc::attitudeToMsg(last_measured_.attitude);
  result->cost = result->effort / plan.time_step;
  if (pb.horizon) result->replans = pb.horizon->adoptions();
  result->success = stale == 0;
}

void TrackerNode::finishExternalWheelsResult(Playback* pb, int stale, int cut_samples,
                                             const std::string& first_problem) const {
  const Maneuver& plan = pb->reference->nodes();
  const int N = plan.steps(), n = pb->wheels.count();
  ReplayResult& result = pb->result;
  const WheelPeaks& peaks = *pb->measured_wheel_peaks;
  finishFromMeasuredEnd(*pb, stale, &result);
  const std::string flown =
      pb->wheel_plant ? std::string("on the tracker's own body + wheels (internal plant; ")
                      : "on the measured state of " + odometry_sub_.getTopic() + " and " +
                            wheel_measurement_sub_.getTopic() + " (external plant; ";
  result.message = (mode_ != TrackingMode::Replay ? "tracked " : "commanded ") + std::to_string(N) +
                   " steps through " + std::to_string(n) + " reaction wheels " + flown +
                   std::to_string(cut_samples) + " of " + std::to_string(pb->times.size()) +
                   " samples cut at a wheel limit)";
  if (stale > 0) {
    result.message +=
        ": " + std::to_string(stale) + " of " + std::to_string(pb->times.size()) +
        " samples had no fresh measurement and got a zero command (first: " + first_problem + ")";
  }
  result.reaction_wheels = rc::wheelSummaryToMsg(pb->wheels, peaks);
  std::string which;
  const double excess = peaks.worstExcess(pb->wheels, &which);
  if (excess > 0.0)
    result.message += "; past a wheel limit: " + which + " by " + exactNumber(excess);
}

bool TrackerNode::runExternalWheels(const ros::Time& start, Playback* pb, ReplanState* replans) {
  const Maneuver& plan = pb->reference->nodes();
  const int n = pb->wheels.count();
  const TrackingLaw law(*pb->reference, nullptr, tracking_);
  const WheelArray array = wheelArray(pb->wheels);
  last_measured_ = {plan.attitude[0], plan.angular_velocity[0]};  // drawn until measured
  ReplayResult& result = pb->result;
  WheelPeaks& peaks = *pb->measured_wheel_peaks;
  int stale = 0, cut_samples = 0;
  std::string first_problem;
  std::deque<Vector3> trail;
  Eigen::VectorXd held = Eigen::VectorXd::Zero(n), momentum = Eigen::VectorXd::Zero(n);
  for (std::size_t j = 0; j < pb->times.size(); ++j) {
    const double t = pb->times[j];
    const ros::Time stamp = start + ros::Duration(t / rate_factor_);
    if (!sleepUntil(stamp)) return false;
    const MeasurementAtSample measured =
        pb->wheel_plant ? simulatedWheelState(pb->wheel_plant.get(), t, &momentum)
                        : wheelMeasurementAt(*pb, start, stamp, held, &momentum);
    {
      std::lock_guard<std::mutex> lock(health_mutex_);
      health_.measurement_problem = measured.problem;
    }
    const RigidBodyState& state = measured.state;
    Eigen::VectorXd u = Eigen::VectorXd::Zero(n);  // stale: nothing known to act on
    if (measured.fresh && pb->horizon) {           // replan: from the measured body and wheels
      const double h = plan.time_step;
      const auto at_node = [&](int k) {
        return predictWheelState(pb->reference->inertia(), array, {state, momentum}, held,
                                 k * h - t, pb->effects.get(), t);
      };
      serviceReplans(
          t, pb, replans, [&](int k) { return at_node(k).body; },
          [&](int k) { return at_node(k).momentum; });
    }
    if (measured.fresh) {
      bool cut = false;
      const auto lawTorque = [&] {
        return pb->horizon ? pb->horizon->commandAt(state, t)
                           : law.command(state.attitude, state.angular_velocity, t);
      };
      u = mode_ != TrackingMode::Replay
              ? wheelTorquesFor(pb->wheels, array, lawTorque(), state.angular_velocity, momentum,
                                &cut)
              // replay: the plan's u, its mean over the hold to the next sample (u(t) itself,
              // held, would lag the plan by half a sample)
              : meanOverHold<Eigen::VectorXd>(
                    [&](double s) {
                      return heldLinearly(pb->plan_wheel_torque, plan.time_step, s);
                    },
                    t, nextSampleTime(pb->times, j), plan.time_step);
      cut_samples += cut ? 1 : 0;
      peaks.observeMomentum(array.axes, momentum);
      peaks.observeTorque(u);
    } else {
      ++stale;
      if (first_problem.empty()) first_problem = measured.problem;
      ROS_WARN_THROTTLE(1.0, "external plant: zero wheel command at t = %.6g s: %s", t,
                        measured.problem.c_str());
    }
    if (pb->wheel_plant) {
      pb->wheel_plant->command(u);  // the torque the body feels: the delivered one
    } else {
      wheel_command_pub_.publish(rc::wheelJointState(u, Eigen::VectorXd(), pb->body_frame, stamp));
    }
    held = u;
    ManeuverSample body;
    body.time = t;
    body.attitude = state.attitude;
    body.angular_velocity = state.angular_velocity;
    body.torque = arrayReaction(array, pb->wheel_plant ? pb->wheel_plant->deliveredTorque() : u,
                                state.angular_velocity, momentum);
    const ManeuverSample reference = pb->reference->at(t);
    if (measured.fresh) {
      result.max_attitude_deviation = std::max(
          result.max_attitude_deviation, so3::angleBetween(reference.attitude, body.attitude));
      pb->health->observe(body.attitude, body.angular_velocity, body.torque);
    }
    if (j + 1 < pb->times.size()) {
      result.effort += 0.5 * body.torque.squaredNorm() * (pb->times[j + 1] - t);
      noteNextSample(true, state, start + ros::Duration(pb->times[j + 1] / rate_factor_));
    }
    publishState(*pb, body, reference, t, stamp, &trail);
    publishWheelValues(*pb, u, momentum, body.angular_velocity, stamp);
  }
  if (!pb->wheel_plant) {
    wheel_command_pub_.publish(  // the run is over: nothing held
        rc::wheelJointState(Eigen::VectorXd::Zero(n), Eigen::VectorXd(), pb->body_frame,
                            ros::Time::now()));
  }
  finishExternalWheelsResult(pb, stale, cut_samples, first_problem);
  return true;
}

MeasurementAtSample TrackerNode::simulatedWheelState(WheelPlant* plant, double t,
                                                     Eigen::VectorXd* momentum) {
  plant->advanceTo(t);
  MeasurementAtSample m;
  m.state = {plant->attitude(), plant->angularVelocity()};
  m.time = t;
  m.age = 0.0;
  m.fresh = true;
  *momentum = plant->momentum();
  last_measured_ = m.state;
  return m;
}

void TrackerNode::finishReplanResult(Playback* pb) const {
  const RecedingHorizonRun& run = *pb->horizon;
  const Maneuver& plan = pb->reference->nodes();
  const int N = plan.steps();
  ReplayResult& result = pb->result;
  const ManeuverSample end = run.bodyAt(N * plan.time_step);
  // Against the first plan's end: every re-plan keeps its target, so the modes compare.
  result.terminal_attitude_error = so3::angleBetween(plan.attitude[N], end.attitude);
  result.terminal_velocity_error = (end.angular_velocity - plan.angular_velocity[N]).norm();
  result.final_attitude = rc::attitudeToMsg(end.attitude);
  result.effort = run.effort();
  result.cost = result.effort / plan.time_step;  // the same units as the replay's Σ ½|τ_k|²
  result.max_attitude_deviation = run.maxAttitudeError();
  result.replans = run.adoptions();
  result.message = "tracked " + std::to_string(N) + " steps with feedback (omega_n " +
                   exactNumber(run.naturalFrequency()) + " rad/s) and re-planning every " +
                   exactNumber(pb->replan_period_steps * plan.time_step) +
                   " s: " + std::to_string(result.replans) + " re-plans adopted, " +
                   std::to_string(result.replan_failures) + " failed";
}

void TrackerNode::runDriftReplay(const Replay& replay) {
  ReplayResult result;
  result.mode = trackingModeName(TrackingMode::Replay);  // kinematic: nothing to feed back
  result.plan_solve_time = replay.plan_solve_time;
  result.plan_cost = replay.plan_cost;
  DriftTwoInputTrajectory plan;
  std::vector<Matrix3> replayed;
  try {
    if (!replay.effects.empty()) {
      throw InvalidInput(
          "~replay_scene: effects are not modelled for a drift + two-input "
          "maneuver (a kinematic system has no torques), got " +
          std::to_string(replay.effects.size()) + " effect(s)");
    }
    DriftTwoInputWeights weights;
    plan = rc::driftManeuverFromMsg(replay.drift_msg, &weights);
    // Open loop: only g(0) and the controls are used; the plan's later attitudes are the check.
    replayed = replayDriftTwoInputControls(plan.g.front(), plan.t, plan.u);
    const int N = static_cast<int>(plan.t.size()) - 1;
    result.steps = N;
    result.duration = plan.t.back() - plan.t.front();
    for (int k = 0; k < N; ++k) {  // ½∫(c1 u1² + c2 u2²) dt, trapezoid on the samples
      auto running = [&](int i) {
        return 0.5 * (weights.c1 * plan.u[i].x() * plan.u[i].x() +
                      weights.c2 * plan.u[i].y() * plan.u[i].y());
      };
      result.cost += 0.5 * (plan.t[k + 1] - plan.t[k]) * (running(k) + running(k + 1));
    }
    result.effort = result.cost;
    result.terminal_attitude_error = so3::angleBetween(plan.g[N], replayed[N]);
    result.terminal_velocity_error = 0.0;  // no velocity boundary condition (kinematic system)
    for (int k = 0; k <= N; ++k) {
      result.max_attitude_deviation =
          std::max(result.max_attitude_deviation, so3::angleBetween(plan.g[k], replayed[k]));
    }
    result.final_attitude = rc::attitudeToMsg(replayed[N]);
  } catch (const std::exception& e) {
    ROS_ERROR("drift maneuver rejected: %s", e.what());
    result.success = false;
    result.message = std::string("drift maneuver rejected: ") + e.what();
    publishDone(result);
    return;
  }

  const std::string world =
      replay.drift_msg.header.frame_id.empty() ? world_frame_ : replay.drift_msg.header.frame_id;
  const std::string body =
      replay.drift_msg.child_frame_id.empty() ? body_frame_ : replay.drift_msg.child_frame_id;
  const PrincipalBox box = principalBox(Matrix3::Identity(), body_size_);  // a cube
  const Vector3 trace_axis = traceAxis(trace_axis_name_, plan.g.front(), plan.g.back());
  ros::Time start;
  if (!waitForClock(replay.drift_msg.header.stamp, &start)) return;
  const int N = static_cast<int>(replayed.size()) - 1;
  std::vector<Vector3> tips;
  for (int k : decimatedIndices(N, kMaxPathPoints))
    tips.push_back(path_radius_ * (plan.g[k] * trace_axis));
  path_pub_.publish(pathMarker(world, "attitude_path", tips, 0.6f));

  const double t0 = plan.t.front();
  // At ~rate like a rigid-body plan: between its nodes the replay's own motion (the same cubic
  // control and Magnus steps from the node before), exactly the replay's rows at the nodes.
  const std::vector<double> times = sampleTimes(result.duration, N, rate_, rate_factor_);
  ROS_INFO(
      "replaying drift maneuver: %d steps over %.3f s, %zu samples (rate %g Hz, rate factor %g)", N,
      result.duration, times.size(), rate_, rate_factor_);
  std::deque<Vector3> trail;
  for (double t : times) {
    const ros::Time stamp = start + ros::Duration(t / rate_factor_);
    if (!sleepUntil(stamp)) return;
    const DriftTwoInputReplaySample sample =
        replayedDriftTwoInputAt(replayed, plan.t, plan.u, t0 + t);
    publishPose(sample.g, stamp, world, body, box, trace_axis, &trail);

    geometry_msgs::Vector3Stamped control;
    control.header.stamp = stamp;
    control.header.frame_id = body;
    control.vector = rc::vectorToMsg(Vector3(sample.u.x(), sample.u.y(), 0.0));
    control_pub_.publish(control);

    geometry_msgs::Vector3Stamped velocity;  // body rate ξ = (u1, u2, 1) [rad/s]
    velocity.header = control.header;
    velocity.vector = rc::vectorToMsg(Vector3(sample.u.x(), sample.u.y(), 1.0));
    velocity_pub_.publish(velocity);
  }
  result.success = true;
  result.message = "replayed drift maneuver, " + std::to_string(N) + " steps";
  result.header.frame_id = world;
  result.header.stamp = start + ros::Duration(times.back() / rate_factor_);
  ROS_INFO("drift replay done: terminal attitude error %.3g rad vs the plan's g(T)",
           result.terminal_attitude_error);
  publishDone(result);
}

}  // namespace attitude_planner
