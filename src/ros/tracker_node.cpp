#include "attitude_planner/ros/tracker_node.hpp"

#include "attitude_planner/ros/parameters.hpp"

#include <Eigen/Eigenvalues>
#include <algorithm>
#include <cmath>

#include <geometry_msgs/TransformStamped.h>
#include <geometry_msgs/Vector3Stamped.h>
#include <geometry_msgs/WrenchStamped.h>

#include "attitude_planner/PlanAttitudeManeuver.h"
#include "attitude_planner/PlanDriftTwoInput.h"
#include "attitude_planner/PlanErrorCode.h"
#include "attitude_planner/dynamics/simulation.hpp"
#include "attitude_planner/io/scene.hpp"
#include "attitude_planner/planner.hpp"
#include "attitude_planner/ros/conversions.hpp"

namespace attitude_planner {

namespace rc = ros_conversions;

namespace {

std_msgs::ColorRGBA color(float r, float g, float b, float a) {
  std_msgs::ColorRGBA c;
  c.r = r;
  c.g = g;
  c.b = b;
  c.a = a;
  return c;
}

geometry_msgs::Point point(const Vector3& v) {
  geometry_msgs::Point p;
  p.x = v.x();
  p.y = v.y();
  p.z = v.z();
  return p;
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
  a.points.push_back(point(Vector3::Zero()));
  a.points.push_back(point(tip));
  a.scale.x = shaft_head_length.x();
  a.scale.y = shaft_head_length.y();
  a.scale.z = shaft_head_length.z();
  a.color = tint;
  return a;
}

visualization_msgs::MarkerArray bodyMarkers(const PrincipalBox& box, double axis_length,
                                            double path_radius, const std::string& body_frame,
                                            const ros::Time& stamp) {
  visualization_msgs::MarkerArray array;
  visualization_msgs::Marker m =
      newMarker(body_frame, stamp, "body", 0, visualization_msgs::Marker::CUBE);
  m.pose.orientation = rc::attitudeToMsg(box.axes);
  m.scale.x = box.dimensions.x();
  m.scale.y = box.dimensions.y();
  m.scale.z = box.dimensions.z();
  m.color = color(0.55f, 0.7f, 0.95f, 0.85f);
  array.markers.push_back(m);
  const std_msgs::ColorRGBA colors[3] = {
      color(0.9f, 0.1f, 0.1f, 1.0f), color(0.1f, 0.8f, 0.1f, 1.0f), color(0.1f, 0.3f, 1.0f, 1.0f)};
  for (int i = 0; i < 3; ++i) {
    array.markers.push_back(arrowMarker(body_frame, stamp, "principal_axes", i + 1,
                                        axis_length * box.axes.col(i),
                                        Vector3(0.04, 0.08, 0.15) * axis_length, colors[i]));
  }
  // The body x axis up to the traced tip, linking the body to `attitude_path` (same colour).
  array.markers.push_back(
      arrowMarker(body_frame, stamp, "body_x_axis", 4, Vector3(path_radius, 0.0, 0.0),
                  Vector3(0.015, 0.04, 0.06) * path_radius, color(1.0f, 0.6f, 0.0f, 1.0f)));
  return array;
}

visualization_msgs::MarkerArray constraintMarkers(
    const std::vector<PlanningConstraint>& constraints, double length,
    const std::string& world_frame, const std::string& body_frame, const ros::Time& stamp) {
  visualization_msgs::MarkerArray array;
  constexpr int kSegments = 48;  // triangles around the cone
  int id = 0;
  for (const PlanningConstraint& c : constraints) {
    if (!c.isCone()) continue;
    const bool out = c.kind == ConstraintKind::KeepOut;
    const std_msgs::ColorRGBA tint =
        out ? color(0.95f, 0.2f, 0.1f, 0.35f) : color(0.1f, 0.85f, 0.3f, 0.35f);
    // The cone: a fan of triangles from the apex (the body origin) to the circle of points at
    // slant distance `length` whose direction makes the half angle with s (any a in (0, π)).
    visualization_msgs::Marker cone = newMarker(world_frame, stamp, out ? "keep_out" : "keep_in",
                                                id, visualization_msgs::Marker::TRIANGLE_LIST);
    cone.scale.x = cone.scale.y = cone.scale.z = 1.0;
    cone.color = tint;
    const Vector3& s = c.world_direction;
    const Vector3 e1 = s.unitOrthogonal();
    const Vector3 e2 = s.cross(e1);
    const auto rim = [&](int i) {
      const double phi = 2.0 * M_PI * i / kSegments;
      return Vector3(length * (std::cos(c.half_angle) * s +
                               std::sin(c.half_angle) * (std::cos(phi) * e1 + std::sin(phi) * e2)));
    };
    for (int i = 0; i < kSegments; ++i) {
      cone.points.push_back(point(Vector3::Zero()));
      cone.points.push_back(point(rim(i)));
      cone.points.push_back(point(rim(i + 1)));
    }
    array.markers.push_back(cone);
    // The constrained body axis b, in the body frame, as long as the cone's slant.
    // (shaft twice the body x arrow's: drawn around it)
    std_msgs::ColorRGBA opaque = tint;
    opaque.a = 1.0f;
    array.markers.push_back(
        arrowMarker(body_frame, stamp, out ? "keep_out_body_axis" : "keep_in_body_axis", id,
                    length * c.body_axis, Vector3(0.03, 0.05, 0.08) * length, opaque));
    ++id;
  }
  return array;
}

bool planScene(const PlanningProblem& problem, const std::vector<EffectSpec>& effects,
               ros::ServiceClient* client, const std::string& world_frame,
               const std::string& body_frame, AttitudeManeuver* msg, double* solve_time,
               double* cost, std::string* error) {
  if (client && client->isValid()) {
    PlanAttitudeManeuver srv;
    srv.request.inertia = rc::inertiaToMsg(problem.inertia);
    srv.request.allow_nonphysical_inertia = problem.allow_nonphysical_inertia;
    srv.request.initial_attitude = rc::attitudeToMsg(problem.initial_attitude);
    srv.request.initial_angular_velocity = rc::vectorToMsg(problem.initial_velocity);
    srv.request.final_attitude = rc::attitudeToMsg(problem.final_attitude);
    srv.request.final_angular_velocity = rc::vectorToMsg(problem.final_velocity);
    srv.request.duration = problem.duration;
    srv.request.steps = problem.steps;
    srv.request.scheme = schemeName(problem.scheme);
    srv.request.direction = directionName(problem.direction);
    srv.request.extra_revolutions = problem.extra_revolutions;
    srv.request.objective = objectiveName(problem.objective);
    srv.request.time_margin = problem.time_margin;
    for (const EffectSpec& e : effects) {
      // Noise is random: the replay adds it, the plan cannot know it.
      if (!std::holds_alternative<TorqueNoiseSpec>(e))
        srv.request.effects.push_back(rc::effectToMsg(e));
    }
    for (const PlanningConstraint& c : problem.constraints)
      srv.request.constraints.push_back(rc::constraintToMsg(c));
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
  const PlanResult result = planManeuver(problem);
  if (!result.converged()) {
    *error = "planner: " + result.message;
    return false;
  }
  *msg = rc::maneuverToMsg(result.maneuver, problem, world_frame, body_frame, ros::Time::now());
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
  if (!plan.converged) {
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
  auto non_empty = [](const std::string& s) { return !s.empty(); };
  rate_factor_ = readParam<double>(pnh, "rate_factor", 1.0, positive, "> 0");
  start_delay_ = readParam<double>(
      pnh, "start_delay", 0.5, [](double v) { return std::isfinite(v) && v >= 0.0; }, ">= 0 s");
  world_frame_ = readParam<std::string>(pnh, "world_frame", "world", non_empty, "non-empty");
  body_frame_ = readParam<std::string>(pnh, "body_frame", "body", non_empty, "non-empty");
  body_size_ = readParam<double>(pnh, "body_size", 1.0, positive, "> 0 m");
  axis_length_ = readParam<double>(pnh, "axis_length", 0.9, positive, "> 0 m");
  path_radius_ = readParam<double>(pnh, "path_radius", 1.2, positive, "> 0 m");
  exit_when_done_ = readParam<bool>(pnh, "exit_when_done", false);
  const std::string scene = readFileParam(pnh, "scene");  // absolute, package:// or relative
  const std::string replay_scene = readFileParam(pnh, "replay_scene");
  const bool plan_in_process = readParam<bool>(pnh, "plan_in_process", false);
  const double planner_timeout = readParam<double>(pnh, "planner_timeout", 30.0, positive, "> 0 s");

  torque_pub_ = nh_.advertise<geometry_msgs::WrenchStamped>("torque", 10);
  velocity_pub_ = nh_.advertise<geometry_msgs::Vector3Stamped>("angular_velocity", 10);
  marker_pub_ = nh_.advertise<visualization_msgs::MarkerArray>("body_marker", 1, true);
  path_pub_ = nh_.advertise<visualization_msgs::Marker>("attitude_path", 1, true);
  done_pub_ = nh_.advertise<ReplayResult>("done", 1, true);
  constraint_pub_ = nh_.advertise<visualization_msgs::MarkerArray>("constraint_markers", 1, true);
  control_pub_ = nh_.advertise<geometry_msgs::Vector3Stamped>("control", 10);
  maneuver_sub_ = nh_.subscribe("maneuver", 1, &TrackerNode::onManeuver, this);
  drift_sub_ = nh_.subscribe("drift_maneuver", 1, &TrackerNode::onDriftManeuver, this);

  if (!replay_scene.empty()) {
    try {
      replay_scene_effects_ = loadScene(replay_scene).effects;
      ROS_INFO("replays act under the %zu effects of %s", replay_scene_effects_->size(),
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
    ROS_INFO("attitude_tracker_node: waiting for a maneuver on %s or %s",
             maneuver_sub_.getTopic().c_str(), drift_sub_.getTopic().c_str());
    return;
  }
  Replay replay;
  std::string error;
  try {
    const Scene parsed = loadScene(scene);
    if (parsed.system == SystemKind::DriftTwoInput) {
      const DriftTwoInputRequest request = driftTwoInputRequest(parsed);  // refuses effects
      ros::ServiceClient client;
      if (!plan_in_process) {
        client = nh_.serviceClient<PlanDriftTwoInput>("plan_drift_two_input");
        ROS_INFO("planning %s with %s", scene.c_str(), client.getService().c_str());
        if (!client.waitForExistence(ros::Duration(planner_timeout))) {
          error = "planner service " + client.getService() + " not available after " +
                  std::to_string(planner_timeout) + " s";
        }
      } else {
        ROS_INFO("planning %s in-process", scene.c_str());
      }
      replay.drift = true;
      if (error.empty() &&
          planDriftScene(request, plan_in_process ? nullptr : &client, world_frame_, body_frame_,
                         &replay.drift_msg, &replay.plan_solve_time, &replay.plan_cost, &error)) {
        ROS_INFO("planned %s: cost %.6g, solve time %.3f s", scene.c_str(), replay.plan_cost,
                 replay.plan_solve_time);
        startReplay(replay);
        return;
      }
      throw InvalidInput(error);
    }
    replay.effects = parsed.effects;
    replay.constraint_markers = constraintMarkers(parsed.problem.constraints, path_radius_,
                                                  world_frame_, body_frame_, ros::Time());
    if (!replay.constraint_markers.markers.empty())
      constraint_pub_.publish(replay.constraint_markers);
    ros::ServiceClient client;
    if (!plan_in_process) {
      client = nh_.serviceClient<PlanAttitudeManeuver>("plan_attitude_maneuver");
      ROS_INFO("planning %s with %s", scene.c_str(), client.getService().c_str());
      if (!client.waitForExistence(ros::Duration(planner_timeout))) {
        error = "planner service " + client.getService() + " not available after " +
                std::to_string(planner_timeout) + " s";
      }
    } else {
      ROS_INFO("planning %s in-process", scene.c_str());
    }
    if (error.empty() &&
        planScene(parsed.problem, parsed.effects, plan_in_process ? nullptr : &client, world_frame_,
                  body_frame_, &replay.msg, &replay.plan_solve_time, &replay.plan_cost, &error)) {
      ROS_INFO("planned %s: cost %.6g, solve time %.3f s", scene.c_str(), replay.plan_cost,
               replay.plan_solve_time);
      startReplay(replay);
      return;
    }
  } catch (const std::exception& e) {
    error = e.what();
  }
  ROS_ERROR("scene %s: %s", scene.c_str(), error.c_str());
  ReplayResult failed;
  failed.success = false;
  failed.message = "scene " + scene + ": " + error;
  publishDone(failed);
}

TrackerNode::~TrackerNode() {
  stopReplay();
}

void TrackerNode::onManeuver(const AttitudeManeuver::ConstPtr& msg) {
  Replay replay;
  replay.msg = *msg;
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
  stopReplay();
  std::lock_guard<std::mutex> lock(replay_mutex_);
  replay_thread_ = std::thread([this, replay]() { runReplay(replay); });
}

bool TrackerNode::sleepUntil(const ros::Time& t) {
  // Short wall sleeps so that a stop request or a paused /clock never blocks shutdown.
  while (!stop_ && ros::ok()) {
    const ros::Time now = ros::Time::now();
    if (!now.isZero() && now >= t) return true;
    const double remaining = now.isZero() ? 0.01 : (t - now).toSec() / 1.0;
    ros::WallDuration(std::min(0.01, std::max(1e-4, remaining))).sleep();
  }
  return false;
}

bool TrackerNode::waitForClock(ros::Time* start) {
  // use_sim_time: ROS time is zero until the first /clock message.
  constexpr double kClockSilenceWarning = 2.0;  // [s] wall time before saying why nothing moves
  const ros::WallTime waiting_since = ros::WallTime::now();
  while (ros::Time::now().isZero()) {
    if (stop_ || !ros::ok()) return false;
    if ((ros::WallTime::now() - waiting_since).toSec() > kClockSilenceWarning)
      ROS_WARN_ONCE("/use_sim_time is true and no /clock is published: waiting for /clock");
    ros::WallDuration(0.01).sleep();
  }
  *start = ros::Time::now() + ros::Duration(start_delay_);
  return true;
}

visualization_msgs::Marker TrackerNode::pathMarker() const {
  visualization_msgs::Marker path;
  path.header.frame_id = world_frame_;
  path.ns = "attitude_path";
  path.id = 0;
  path.type = visualization_msgs::Marker::LINE_STRIP;
  path.action = visualization_msgs::Marker::ADD;
  path.pose.orientation.w = 1.0;
  path.scale.x = 0.02 * path_radius_;  // line width [m]
  path.color = color(1.0f, 0.6f, 0.0f, 1.0f);
  return path;
}

void TrackerNode::publishPose(const Matrix3& R, const ros::Time& stamp, const PrincipalBox& box,
                              visualization_msgs::Marker* path,
                              visualization_msgs::MarkerArray* constraint_markers) {
  geometry_msgs::TransformStamped tf;
  tf.header.stamp = stamp;
  tf.header.frame_id = world_frame_;
  tf.child_frame_id = body_frame_;
  tf.transform.rotation = rc::attitudeToMsg(R);
  tf_broadcaster_.sendTransform(tf);
  marker_pub_.publish(bodyMarkers(box, axis_length_, path_radius_, body_frame_, stamp));
  path->header.stamp = stamp;
  path->points.push_back(point(path_radius_ * R.col(0)));
  if (path->points.size() >= 2) path_pub_.publish(*path);
  if (constraint_markers && !constraint_markers->markers.empty()) {
    for (visualization_msgs::Marker& m : constraint_markers->markers) m.header.stamp = stamp;
    constraint_pub_.publish(*constraint_markers);
  }
}

void TrackerNode::publishDone(ReplayResult result) {
  result.header.frame_id = world_frame_;
  if (result.header.stamp.isZero()) result.header.stamp = ros::Time::now();
  done_pub_.publish(result);
  if (exit_when_done_) {
    // Give latched subscribers (rosbag record, scripts) a moment to receive `done`.
    ros::WallDuration(1.0).sleep();
    ROS_INFO("exit_when_done: shutting down");
    ros::requestShutdown();
  }
}

void TrackerNode::runReplay(Replay replay) {
  if (replay.drift) {
    runDriftReplay(replay);
    return;
  }
  ReplayResult result;
  result.plan_solve_time = replay.plan_solve_time;
  result.plan_cost = replay.plan_cost;
  Maneuver plan, replayed;
  Matrix3 inertia;
  try {
    plan = rc::maneuverFromMsg(replay.msg);
    inertia = rc::inertiaFromMsg(replay.msg.inertia);
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
    if (!replay.msg.scheme.empty())
      problem.scheme = parseScheme(replay.msg.scheme, "maneuver.scheme");
    validateProblem(problem);
    // Exactly the effects of the replay's scene: forcing on the body, then what the actuators do.
    const std::shared_ptr<const EffectModel> effects = plannableEffects(replay.effects, inertia);
    Actuation actuation = actuationOf(replay.effects);
    SimulationInput input;
    input.initial_attitude = problem.initial_attitude;
    input.initial_velocity = problem.initial_velocity;
    input.torque = plan.torque;
    input.effects = effects.get();
    input.actuation = &actuation;
    replayed = replayPlan(problem.scheme, inertia, plan.time_step, input);
    for (const EffectSpec& e : replay.effects) result.replay_effects.push_back(effectName(e));
    result.steps = N;
    result.duration = problem.duration;
    result.cost = schemeCost(problem.scheme, replayed.torque);
    result.terminal_attitude_error = so3::angleBetween(plan.attitude[N], replayed.attitude[N]);
    result.terminal_velocity_error =
        (replayed.angular_velocity[N] - plan.angular_velocity[N]).norm();
    for (int k = 0; k <= N; ++k) {
      result.max_attitude_deviation = std::max(
          result.max_attitude_deviation, so3::angleBetween(plan.attitude[k], replayed.attitude[k]));
    }
    result.final_attitude = rc::attitudeToMsg(replayed.attitude[N]);
  } catch (const std::exception& e) {
    ROS_ERROR("maneuver rejected: %s", e.what());
    result.success = false;
    result.message = std::string("maneuver rejected: ") + e.what();
    publishDone(result);
    return;
  }

  const PrincipalBox box = principalBox(inertia, body_size_);
  ros::Time start;
  if (!waitForClock(&start)) return;
  visualization_msgs::Marker path = pathMarker();

  const int N = replayed.steps();
  ROS_INFO("replaying %d steps over %.3f s (rate factor %g)", N, N * replayed.time_step,
           rate_factor_);
  for (int k = 0; k <= N; ++k) {
    const ros::Time stamp = start + ros::Duration(replayed.time[k] / rate_factor_);
    if (!sleepUntil(stamp)) return;
    publishPose(replayed.attitude[k], stamp, box, &path, &replay.constraint_markers);

    geometry_msgs::WrenchStamped wrench;
    wrench.header.stamp = stamp;
    wrench.header.frame_id = body_frame_;
    wrench.wrench.torque = rc::vectorToMsg(replayed.torque[k]);
    torque_pub_.publish(wrench);

    geometry_msgs::Vector3Stamped velocity;
    velocity.header = wrench.header;
    velocity.vector = rc::vectorToMsg(replayed.angular_velocity[k]);
    velocity_pub_.publish(velocity);
  }
  result.success = true;
  result.message = "replayed " + std::to_string(N) + " steps";
  result.header.stamp = start + ros::Duration(replayed.time[N] / rate_factor_);
  ROS_INFO("replay done: terminal attitude error %.3g rad vs the plan's R_N",
           result.terminal_attitude_error);
  publishDone(result);
}

void TrackerNode::runDriftReplay(const Replay& replay) {
  ReplayResult result;
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

  const PrincipalBox box = principalBox(Matrix3::Identity(), body_size_);  // a cube
  ros::Time start;
  if (!waitForClock(&start)) return;
  visualization_msgs::Marker path = pathMarker();

  const int N = static_cast<int>(replayed.size()) - 1;
  const double t0 = plan.t.front();
  ROS_INFO("replaying drift maneuver: %d steps over %.3f s (rate factor %g)", N, result.duration,
           rate_factor_);
  for (int k = 0; k <= N; ++k) {
    const ros::Time stamp = start + ros::Duration((plan.t[k] - t0) / rate_factor_);
    if (!sleepUntil(stamp)) return;
    publishPose(replayed[k], stamp, box, &path);

    geometry_msgs::Vector3Stamped control;
    control.header.stamp = stamp;
    control.header.frame_id = body_frame_;
    control.vector = rc::vectorToMsg(Vector3(plan.u[k].x(), plan.u[k].y(), 0.0));
    control_pub_.publish(control);

    geometry_msgs::Vector3Stamped velocity;  // body rate ξ = (u1, u2, 1) [rad/s]
    velocity.header = control.header;
    velocity.vector = rc::vectorToMsg(Vector3(plan.u[k].x(), plan.u[k].y(), 1.0));
    velocity_pub_.publish(velocity);
  }
  result.success = true;
  result.message = "replayed drift maneuver, " + std::to_string(N) + " steps";
  result.header.stamp = start + ros::Duration((plan.t[N] - t0) / rate_factor_);
  ROS_INFO("drift replay done: terminal attitude error %.3g rad vs the plan's g(T)",
           result.terminal_attitude_error);
  publishDone(result);
}

}  // namespace attitude_planner
