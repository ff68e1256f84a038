#include "attitude_planner/ros/conversions.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>
#include <sstream>

#include "attitude_planner/planning/warm_start.hpp"

namespace attitude_planner {
namespace ros_conversions {

EffectSpec effectFromMsg(const Effect& msg, const std::string& field) {
  // A field the type does not read must stay at zero: a value there is a mistake, not a default.
  auto unused = [&](bool is_zero, const std::string& key, const std::string& value) {
    if (!is_zero) {
      throw InvalidInput(field + "." + key + ": not used by type '" + msg.type +
                         "' (leave it at zero/empty), got " + value);
    }
  };
  const Vector3 value = vectorFromMsg(msg.value);
  const EffectKind kind = parseEffectKind(msg.type, field + ".type");
  const bool uses_orbit = kind == EffectKind::GravityGradient;
  const bool uses_frame = kind == EffectKind::DisturbanceTorque;
  const bool uses_value = kind != EffectKind::GravityGradient;
  const bool uses_seed = kind == EffectKind::TorqueNoise;
  if (!uses_orbit) unused(msg.mu == 0.0, "mu", exactNumber(msg.mu));
  if (!uses_orbit) unused(msg.orbit_radius == 0.0, "orbit_radius", exactNumber(msg.orbit_radius));
  if (!uses_frame) unused(msg.frame.empty(), "frame", "'" + msg.frame + "'");
  if (!uses_value) {
    unused(value.isZero(0.0), "value",
           "[" + exactNumber(value.x()) + ", " + exactNumber(value.y()) + ", " +
               exactNumber(value.z()) + "]");
  }
  if (!uses_seed) unused(msg.seed == 0, "seed", std::to_string(msg.seed));
  if (uses_orbit) return GravityGradientSpec{msg.mu, msg.orbit_radius};
  if (uses_frame) {
    return DisturbanceTorqueSpec{parseTorqueFrame(msg.frame, field + ".frame"), value};
  }
  if (kind == EffectKind::ActuatorLimits) return ActuatorLimitsSpec{value};
  return TorqueNoiseSpec{value, msg.seed};
}

Effect effectToMsg(const EffectSpec& spec) {
  Effect msg;
  msg.type = effectName(spec);
  if (const auto* g = std::get_if<GravityGradientSpec>(&spec)) {
    msg.mu = g->mu;
    msg.orbit_radius = g->orbit_radius;
  } else if (const auto* d = std::get_if<DisturbanceTorqueSpec>(&spec)) {
    msg.frame = torqueFrameName(d->frame);
    msg.value = vectorToMsg(d->value);
  } else if (const auto* a = std::get_if<ActuatorLimitsSpec>(&spec)) {
    msg.value = vectorToMsg(a->max_torque);
  } else if (const auto* n = std::get_if<TorqueNoiseSpec>(&spec)) {
    msg.value = vectorToMsg(n->std);
    msg.seed = n->seed;
  }
  return msg;
}

PlanningConstraint constraintFromMsg(const Constraint& msg, const std::string& field) {
  const auto vector = [](const geometry_msgs::Vector3& v) { return Vector3(v.x, v.y, v.z); };
  const Vector3 b = vector(msg.body_axis), s = vector(msg.world_direction);
  const bool cone = msg.type == Constraint::KEEP_OUT || msg.type == Constraint::KEEP_IN;
  if (!cone && msg.type != Constraint::MAX_TORQUE_NORM &&
      msg.type != Constraint::MAX_ANGULAR_RATE) {
    throw InvalidInput(field + ".type: unknown value '" + msg.type +
                       "' (expected max_torque_norm, max_angular_rate, keep_out or keep_in)");
  }
  if (cone && msg.limit != 0.0) {
    throw InvalidInput(field + ".limit: not used by " + msg.type + ", must be 0, got " +
                       exactNumber(msg.limit));
  }
  if (!cone && (!b.isZero(0.0) || !s.isZero(0.0) || msg.half_angle != 0.0 || msg.margin != 0.0)) {
    throw InvalidInput(field +
                       ": body_axis, world_direction, half_angle and margin are not used by " +
                       msg.type + ", must be 0");
  }
  if (msg.type == Constraint::MAX_TORQUE_NORM) return PlanningConstraint::maxTorqueNorm(msg.limit);
  if (msg.type == Constraint::MAX_ANGULAR_RATE)
    return PlanningConstraint::maxAngularRate(msg.limit);
  if (msg.type == Constraint::KEEP_OUT)
    return PlanningConstraint::keepOut(b, s, msg.half_angle, msg.margin);
  return PlanningConstraint::keepIn(b, s, msg.half_angle, msg.margin);
}

Constraint constraintToMsg(const PlanningConstraint& c) {
  Constraint msg;
  msg.type = constraintKindName(c.kind);
  if (c.isCone()) {
    msg.body_axis = vectorToMsg(c.body_axis);
    msg.world_direction = vectorToMsg(c.world_direction);
    msg.half_angle = c.half_angle;
    msg.margin = c.margin;
  } else {
    msg.limit = c.limit;
  }
  return msg;
}

PlanAttempt attemptToMsg(const Attempt& a) {
  PlanAttempt msg;
  msg.stage = attemptStageName(a.stage);
  msg.start = attemptStartName(a.start);
  msg.formulation = formulationName(a.formulation);
  msg.long_way = a.homotopy.long_way;
  msg.extra_revolutions = a.homotopy.extra_revolutions;
  msg.steps = a.steps;
  msg.termination = terminationName(a.termination);
  msg.iterations = a.iterations;
  msg.cost = a.cost;
  msg.kept = a.kept;
  const StartDetail& d = a.start_detail;
  msg.start_detail.duration = d.duration;
  msg.start_detail.eigenaxis = vectorToMsg(d.eigenaxis);
  msg.start_detail.excursion_axis = vectorToMsg(d.excursion_axis);
  msg.start_detail.excursion = d.excursion;
  msg.start_detail.cleared_of_cones = d.cleared_of_cones;
  msg.start_detail.coarse_steps = d.coarse_steps;
  msg.start_detail.origin = attemptStartName(originOf(a));
  msg.start_detail.excursion_peak = d.excursion_peak;
  msg.start_detail.twist = d.twist;
  msg.start_detail.elastic_from_violations = d.elastic_from_violations;
  return msg;
}

MinimumTimeSummary minimumTimeToMsg(const MinimumTimeCertificate& c) {
  MinimumTimeSummary msg;
  msg.kkt_point = c.kkt_point;
  msg.stationarity = c.stationarity;
  msg.time_stationarity = c.time_stationarity;
  msg.complementarity = c.complementarity;
  msg.solves = c.solves;
  msg.second_order_sufficient = c.second_order_sufficient;
  return msg;
}

DurationVerdictSummary durationVerdictToMsg(const DurationVerdict& v) {
  DurationVerdictSummary msg;
  msg.lower_bound = v.lower_bound;
  msg.lower_bound_basis = v.lower_bound_basis;
  msg.proven_infeasible = v.proven_infeasible;
  msg.least_duration_found = v.least_duration_found;
  msg.longest_duration_found = v.longest_duration_found;
  msg.rate_limit = v.rate_limit;
  msg.torque_limit = v.torque_limit;
  msg.plan_within_bounds = v.plan_within_bounds;
  return msg;
}

std::vector<NamedFigure> verdictFiguresToMsg(const Verdict& verdict) {
  std::vector<NamedFigure> figures;
  for (const VerdictFigure& f : verdictFigures(verdict)) {
    NamedFigure msg;
    msg.name = f.name;
    msg.value = f.value;
    figures.push_back(msg);
  }
  return figures;
}

void applyRequestEffects(const std::vector<Effect>& effects, PlanningProblem* problem) {
  std::vector<EffectSpec> specs;
  for (std::size_t i = 0; i < effects.size(); ++i) {
    const std::string field = "effects[" + std::to_string(i) + "]";
    specs.push_back(effectFromMsg(effects[i], field));
    if (std::holds_alternative<TorqueNoiseSpec>(specs.back())) {
      throw InvalidInput(field +
                         ".type: 'torque_noise' is not plannable (random; it acts in the "
                         "tracker's replay only): leave it out of planning requests");
    }
  }
  validateEffects(specs, "effects");
  applyEffects(specs, problem);
}

MeasuredState measuredStateFromMsg(const nav_msgs::Odometry& msg) {
  MeasuredState state;
  state.attitude = attitudeFromMsg(msg.pose.pose.orientation, "odometry.pose.pose.orientation");
  state.angular_velocity =
      finiteVectorFromMsg(msg.twist.twist.angular, "odometry.twist.twist.angular");
  return state;
}

nav_msgs::Odometry odometryToMsg(const Matrix3& attitude, const Vector3& angular_velocity,
                                 const ros::Time& stamp, const std::string& frame,
                                 const std::string& child_frame) {
  nav_msgs::Odometry msg;
  msg.header.stamp = stamp;
  msg.header.frame_id = frame;
  msg.child_frame_id = child_frame;
  msg.pose.pose.orientation = attitudeToMsg(attitude);
  msg.twist.twist.angular = vectorToMsg(angular_velocity);
  return msg;
}

Matrix3 attitudeFromMsg(const geometry_msgs::Quaternion& q, const std::string& field) {
  return attitudeFromQuaternion(Eigen::Vector4d(q.w, q.x, q.y, q.z), field);
}

geometry_msgs::Quaternion attitudeToMsg(const Matrix3& R) {
  const Eigen::Quaterniond q = so3::toQuaternion(R);
  geometry_msgs::Quaternion m;
  m.w = q.w();
  m.x = q.x();
  m.y = q.y();
  m.z = q.z();
  return m;
}

Vector3 vectorFromMsg(const geometry_msgs::Vector3& v) {
  return Vector3(v.x, v.y, v.z);
}

Vector3 finiteVectorFromMsg(const geometry_msgs::Vector3& v, const std::string& field) {
  const Vector3 out = vectorFromMsg(v);
  if (!out.allFinite()) {
    throw InvalidInput(field + ": not finite: [" + exactNumber(out.x()) + ", " +
                       exactNumber(out.y()) + ", " + exactNumber(out.z()) + "]");
  }
  return out;
}

geometry_msgs::Vector3 vectorToMsg(const Vector3& v) {
  return xyzToMsg<geometry_msgs::Vector3>(v);
}

EndCondition endConditionFromRequest(const std::string& name,
                                     const geometry_msgs::Vector3& body_axis,
                                     const geometry_msgs::Vector3& world_direction) {
  EndCondition end;
  if (name.empty() || name == "attitude") return end;
  if (name != "pointing") {
    throw InvalidInput("end_condition: expected \"\", \"attitude\" or \"pointing\", got \"" + name +
                       "\"");
  }
  end.kind = EndConditionKind::Pointing;
  end.body_axis = finiteVectorFromMsg(body_axis, "pointing_body_axis");
  end.world_direction = finiteVectorFromMsg(world_direction, "pointing_world_direction");
  return end;
}

Matrix3 inertiaFromMsg(const boost::array<double, 9>& j) {
  Matrix3 J;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) J(r, c) = j[3 * r + c];
  }
  return J;
}

boost::array<double, 9> inertiaToMsg(const Matrix3& J) {
  boost::array<double, 9> j;
  for (int r = 0; r < 3; ++r) {
    for (int c = 0; c < 3; ++c) j[3 * r + c] = J(r, c);
  }
  return j;
}

AttitudeManeuver maneuverToMsg(const Maneuver& maneuver, const PlanningProblem& problem,
                               const std::string& world_frame, const std::string& body_frame,
                               const ros::Time& stamp, const WheelStates* wheel_states) {
  AttitudeManeuver m;
  m.header.stamp = stamp;
  m.header.frame_id = world_frame;
  m.child_frame_id = body_frame;
  m.inertia = inertiaToMsg(problem.inertia);
  m.scheme = schemeName(problem.scheme);
  m.time_step = maneuver.time_step;
  m.time = maneuver.time;
  // Reserved: an N = 1e5 plan is handed over after a cancel, where every millisecond counts.
  m.attitude.reserve(maneuver.attitude.size());
  m.angular_velocity.reserve(maneuver.angular_velocity.size());
  m.torque.reserve(maneuver.torque.size());
  for (const Matrix3& R : maneuver.attitude) m.attitude.push_back(attitudeToMsg(R));
  for (const Vector3& w : maneuver.angular_velocity) m.angular_velocity.push_back(vectorToMsg(w));
  for (const Vector3& t : maneuver.torque) m.torque.push_back(vectorToMsg(t));
  for (const PlanningConstraint& c : problem.constraints)
    m.constraints.push_back(constraintToMsg(c));
  m.reaction_wheels = reactionWheelsToMsg(problem.reaction_wheels);
  if (wheel_states) {
    for (const Eigen::VectorXd& u : wheel_states->torque)
      m.wheel_torque.insert(m.wheel_torque.end(), u.data(), u.data() + u.size());
    for (const Eigen::VectorXd& h : wheel_states->momentum)
      m.wheel_momentum.insert(m.wheel_momentum.end(), h.data(), h.data() + h.size());
  }
  return m;
}

ReactionWheels reactionWheelsFromMsg(const ReactionWheelArray& msg, const std::string& field) {
  ReactionWheels out;
  if (msg.spin_axes.empty()) {
    if (!msg.max_torque.empty() || !msg.max_momentum.empty() || !msg.initial_momentum.empty() ||
        !msg.spin_inertia.empty() || msg.max_momentum_norm != 0.0) {
      throw InvalidInput(field +
                         ".spin_axes: empty (no wheels) while the array's other fields "
                         "are set: give the spin axes, or leave every field empty / 0");
    }
    return out;
  }
  for (std::size_t i = 0; i < msg.spin_axes.size(); ++i) {
    out.spin_axes.push_back(
        finiteVectorFromMsg(msg.spin_axes[i], field + ".spin_axes[" + std::to_string(i) + "]"));
  }
  out.max_torque = msg.max_torque;
  out.max_momentum = msg.max_momentum;
  out.initial_momentum = msg.initial_momentum;
  out.spin_inertia = msg.spin_inertia;  // checked by the core (validateReactionWheels)
  // 0 means no envelope; any other value (negative, NaN) is the core's to refuse by name.
  if (msg.max_momentum_norm != 0.0) out.max_momentum_norm = msg.max_momentum_norm;
  return out;
}

ReactionWheelArray reactionWheelsToMsg(const ReactionWheels& wheels) {
  ReactionWheelArray m;
  for (const Vector3& a : wheels.spin_axes) m.spin_axes.push_back(vectorToMsg(a));
  m.max_torque = wheels.max_torque;
  m.max_momentum = wheels.max_momentum;
  m.initial_momentum = wheels.initial_momentum;
  m.spin_inertia = wheels.spin_inertia;
  m.max_momentum_norm = std::isfinite(wheels.max_momentum_norm) ? wheels.max_momentum_norm : 0.0;
  return m;
}

ReactionWheelsSummary wheelSummaryToMsg(const ReactionWheels& wheels, const WheelPeaks& peaks,
                                        std::optional<MinimizedEffort> effort_minimized) {
  ReactionWheelsSummary m;
  if (effort_minimized) m.effort_minimized = minimizedEffortName(*effort_minimized);
  for (int i = 0; i < wheels.count(); ++i) {
    WheelPeak w;
    w.name = wheelName(i);
    w.peak_momentum = peaks.peak_momentum(i);
    w.max_momentum = wheels.momentumLimit(i);
    w.momentum_margin = w.max_momentum - w.peak_momentum;
    w.peak_torque = peaks.peak_torque(i);
    w.max_torque = wheels.torqueLimit(i);
    w.torque_margin = w.max_torque - w.peak_torque;
    m.wheels.push_back(w);
  }
  m.peak_momentum_norm = peaks.peak_momentum_norm;
  m.has_momentum_norm_limit = std::isfinite(wheels.max_momentum_norm);
  if (m.has_momentum_norm_limit) {
    m.max_momentum_norm = wheels.max_momentum_norm;
    m.momentum_norm_margin = wheels.max_momentum_norm - peaks.peak_momentum_norm;
  }
  return m;
}

void requireWheelBodyEffects(const std::vector<EffectSpec>& effects, const std::string& field) {
  for (const EffectSpec& e : effects) {
    const EffectKind kind = effectKindOf(e);
    if (kind == EffectKind::ActuatorLimits || kind == EffectKind::TorqueNoise) {
      throw InvalidInput(field + ": " + effectName(e) +
                         " acts on a body torque, which no reaction wheel makes (the wheels' "
                         "max_torque bounds them); with wheels only gravity_gradient and "
                         "disturbance_torque act");
    }
  }
}

Eigen::VectorXd wheelJointValues(const std::vector<std::string>& names,
                                 const std::vector<double>& values, int wheels,
                                 const std::string& field) {
  Eigen::VectorXd out(wheels);
  for (int i = 0; i < wheels; ++i) {
    const std::string wheel = wheelName(i);
    const auto at = std::find(names.begin(), names.end(), wheel);
    if (at == names.end()) throw InvalidInput(field + ": no joint named " + wheel);
    const std::size_t j = static_cast<std::size_t>(at - names.begin());
    if (j >= values.size()) {
      throw InvalidInput(field + ": " + std::to_string(values.size()) + " values for " +
                         std::to_string(names.size()) + " names (" + wheel + " has none)");
    }
    if (!std::isfinite(values[j])) {
      throw InvalidInput(field + "[" + std::to_string(j) + "] (" + wheel +
                         "): must be finite, got " + exactNumber(values[j]));
    }
    out(i) = values[j];
  }
  return out;
}

sensor_msgs::JointState wheelJointState(const Eigen::VectorXd& effort,
                                        const Eigen::VectorXd& velocity, const std::string& frame,
                                        const ros::Time& stamp) {
  sensor_msgs::JointState joints;
  joints.header.stamp = stamp;
  joints.header.frame_id = frame;
  for (int i = 0; i < effort.size(); ++i) {
    joints.name.push_back(wheelName(i));
    joints.effort.push_back(effort(i));
    if (velocity.size() > 0) joints.velocity.push_back(velocity(i));
  }
  return joints;
}

std::vector<Eigen::VectorXd> wheelRowsFromMsg(const std::vector<double>& values, int rows,
                                              int wheels, const std::string& field) {
  if (static_cast<long>(values.size()) != static_cast<long>(rows) * wheels) {
    throw InvalidInput(field + ": needs (N + 1) * n = " + std::to_string(rows) + " * " +
                       std::to_string(wheels) + " values, got " + std::to_string(values.size()));
  }
  std::vector<Eigen::VectorXd> out(rows, Eigen::VectorXd(wheels));
  for (int k = 0; k < rows; ++k) {
    for (int i = 0; i < wheels; ++i) {
      const double v = values[static_cast<std::size_t>(k) * wheels + i];
      if (!std::isfinite(v)) {
        throw InvalidInput(field + "[" + std::to_string(k * wheels + i) +
                           "]: must be finite, got " + exactNumber(v));
      }
      out[k](i) = v;
    }
  }
  return out;
}

Maneuver maneuverFromMsg(const AttitudeManeuver& msg) {
  const size_t rows = msg.attitude.size();
  if (rows < 2) {
    throw InvalidInput("maneuver.attitude: needs N + 1 >= 2 rows, got " + std::to_string(rows));
  }
  if (msg.time.size() != rows || msg.angular_velocity.size() != rows || msg.torque.size() != rows) {
    throw InvalidInput("maneuver: arrays disagree in length (time " +
                       std::to_string(msg.time.size()) + ", attitude " + std::to_string(rows) +
                       ", angular_velocity " + std::to_string(msg.angular_velocity.size()) +
                       ", torque " + std::to_string(msg.torque.size()) + ")");
  }
  if (!std::isfinite(msg.time_step) || !(msg.time_step > 0.0)) {
    throw InvalidInput("maneuver.time_step: must be a finite number > 0 s, got " +
                       std::to_string(msg.time_step));
  }
  Maneuver m;
  m.time_step = msg.time_step;
  m.time = msg.time;
  for (size_t k = 0; k < rows; ++k) {
    const std::string row = "[" + std::to_string(k) + "]";
    m.attitude.push_back(attitudeFromMsg(msg.attitude[k], "maneuver.attitude" + row));
    const Vector3 w = vectorFromMsg(msg.angular_velocity[k]);
    const Vector3 t = vectorFromMsg(msg.torque[k]);
    if (!w.allFinite()) throw InvalidInput("maneuver.angular_velocity" + row + ": not finite");
    if (!t.allFinite()) throw InvalidInput("maneuver.torque" + row + ": not finite");
    if (!std::isfinite(msg.time[k])) throw InvalidInput("maneuver.time" + row + ": not finite");
    m.angular_velocity.push_back(w);
    m.torque.push_back(t);
  }
  return m;
}

bool initialGuessFromMsg(const AttitudeManeuver& msg, const std::string& field, Maneuver* guess) {
  if (msg.attitude.empty()) return false;
  Maneuver m;
  m.time_step = msg.time_step;
  m.time = msg.time;
  for (size_t k = 0; k < msg.attitude.size(); ++k) {
    m.attitude.push_back(
        attitudeFromMsg(msg.attitude[k], field + ".attitude[" + std::to_string(k) + "]"));
  }
  for (const geometry_msgs::Vector3& w : msg.angular_velocity) {
    m.angular_velocity.push_back(vectorFromMsg(w));
  }
  for (const geometry_msgs::Vector3& t : msg.torque) m.torque.push_back(vectorFromMsg(t));
  validateInitialGuess(m, field);
  *guess = std::move(m);
  return true;
}

DriftTwoInputManeuver driftManeuverToMsg(const DriftTwoInputTrajectory& tr,
                                         const DriftTwoInputWeights& weights,
                                         const std::string& world_frame,
                                         const std::string& body_frame, const ros::Time& stamp) {
  DriftTwoInputManeuver m;
  m.header.stamp = stamp;
  m.header.frame_id = world_frame;
  m.child_frame_id = body_frame;
  m.control_weights = {weights.c1, weights.c2};
  m.time_step = tr.t.size() >= 2 ? tr.t[1] - tr.t[0] : 0.0;
  m.time = tr.t;
  for (const Matrix3& g : tr.g) m.attitude.push_back(attitudeToMsg(g));
  for (const Eigen::Vector2d& u : tr.u) m.control.push_back(vectorToMsg(Vector3(u.x(), u.y(), 0)));
  for (const Vector3& p : tr.p) m.costate.push_back(vectorToMsg(p));
  return m;
}

DriftTwoInputTrajectory driftManeuverFromMsg(const DriftTwoInputManeuver& msg,
                                             DriftTwoInputWeights* weights) {
  const size_t rows = msg.attitude.size();
  if (rows < 2) {
    throw InvalidInput("drift_maneuver.attitude: needs N + 1 >= 2 rows, got " +
                       std::to_string(rows));
  }
  if (msg.time.size() != rows || msg.control.size() != rows || msg.costate.size() != rows) {
    throw InvalidInput("drift_maneuver: arrays disagree in length (time " +
                       std::to_string(msg.time.size()) + ", attitude " + std::to_string(rows) +
                       ", control " + std::to_string(msg.control.size()) + ", costate " +
                       std::to_string(msg.costate.size()) + ")");
  }
  weights->c1 = msg.control_weights[0];
  weights->c2 = msg.control_weights[1];
  try {
    validateDriftTwoInputWeights(*weights);
  } catch (const InvalidInput& e) {
    throw InvalidInput(std::string("drift_maneuver.control_weights: ") + e.what());
  }
  DriftTwoInputTrajectory tr;
  for (size_t k = 0; k < rows; ++k) {
    const std::string row = "[" + std::to_string(k) + "]";
    if (!std::isfinite(msg.time[k]))
      throw InvalidInput("drift_maneuver.time" + row + ": not finite");
    const Vector3 u = vectorFromMsg(msg.control[k]);
    const Vector3 p = vectorFromMsg(msg.costate[k]);
    if (!u.allFinite()) throw InvalidInput("drift_maneuver.control" + row + ": not finite");
    if (u.z() != 0.0) {
      throw InvalidInput("drift_maneuver.control" + row +
                         ".z: must be 0 (the drift about body z is fixed), got " +
                         std::to_string(u.z()));
    }
    if (!p.allFinite()) throw InvalidInput("drift_maneuver.costate" + row + ": not finite");
    tr.t.push_back(msg.time[k]);
    tr.g.push_back(attitudeFromMsg(msg.attitude[k], "drift_maneuver.attitude" + row));
    tr.u.emplace_back(u.x(), u.y());
    tr.p.push_back(p);
  }
  return tr;
}

DriftTwoInputRequest driftRequestFromMsg(const PlanDriftTwoInput::Request& req,
                                         const PlannerDefaults& defaults) {
  DriftTwoInputRequest r;
  r.g0 = attitudeFromMsg(req.initial_attitude, "initial_attitude");
  r.g1 = attitudeFromMsg(req.final_attitude, "final_attitude");
  requireDuration(req.duration, "duration");  // the rule planDriftTwoInput applies too
  r.duration = req.duration;
  r.steps = stepsFromRequest(req.steps, defaults);
  for (int i = 0; i < 2; ++i) {
    const double c = req.control_weights[i];
    if (!std::isfinite(c) || !(c > 0.0)) {
      throw InvalidInput("control_weights[" + std::to_string(i) +
                         "]: must be a finite number > 0, got " + std::to_string(c));
    }
  }
  r.weights.c1 = req.control_weights[0];
  r.weights.c2 = req.control_weights[1];
  if (req.use_initial_costate) {
    const Vector3 p0 = vectorFromMsg(req.initial_costate);
    if (!p0.allFinite()) throw InvalidInput("initial_costate: not finite");
    r.initial_costate = p0;
  }
  if (!std::isfinite(req.tolerance) || req.tolerance < 0.0) {
    throw InvalidInput("tolerance: must be a finite number >= 0 rad (0 = default), got " +
                       std::to_string(req.tolerance));
  }
  if (req.tolerance > 0.0) r.tolerance = req.tolerance;
  if (req.max_iterations < 0) {
    throw InvalidInput("max_iterations: must be >= 0 (0 = default), got " +
                       std::to_string(req.max_iterations));
  }
  if (req.max_iterations > 0) r.max_iterations = req.max_iterations;
  if (req.shooting_intervals < 0) {
    throw InvalidInput("shooting_intervals: must be >= 0 (0 = 1, single shooting), got " +
                       std::to_string(req.shooting_intervals));
  }
  r.shooting_intervals = std::max(1, static_cast<int>(req.shooting_intervals));
  // No time_budget field in the request (adding one would change the service's MD5): the node's
  // ~time_budget applies, capped by ~max_solve_time, as for plan_attitude_maneuver.
  r.time_budget_s = defaults.time_budget;
  if (defaults.max_solve_time > 0.0 &&
      (r.time_budget_s <= 0.0 || r.time_budget_s > defaults.max_solve_time)) {
    r.time_budget_s = defaults.max_solve_time;
  }
  return r;
}

namespace {

/// Core (scene) field names spelt otherwise in the request.
const std::map<std::string, std::string> kRenamedFields = {
    {"initial.attitude", "initial_attitude"},
    {"initial.angular_velocity", "initial_angular_velocity"},
    {"final.attitude", "final_attitude"},
    {"final.pointing.body_axis", "pointing_body_axis"},
    {"final.pointing.world_direction", "pointing_world_direction"},
    {"final.pointing", "end_condition"},
    {"final.angular_velocity", "final_angular_velocity"},
};

/// The scene's (and the core's) path of the wheel array and the length of its `actuators.` part.
const std::string kSceneWheelsField = "actuators.reaction_wheels";
constexpr std::size_t kSceneWheelsPrefix = sizeof("actuators.") - 1;

bool startsWith(const std::string& s, const std::string& prefix) {
  return s.compare(0, prefix.size(), prefix) == 0;
}

/// `constraints[i].<kind>[.<key>]` → `constraints[i].limit` (torque and rate limits),
/// `constraints[i].<key>` (cones), `constraints[i]` (a cone as a whole).
std::string constraintRequestField(const std::string& item, const std::string& kind,
                                   const std::string& key) {
  const bool limit = kind == Constraint::MAX_TORQUE_NORM || kind == Constraint::MAX_ANGULAR_RATE;
  if (!key.empty()) return item + "." + key;
  return limit ? item + ".limit" : item;
}

/// `effects[i].<kind>.<key>[k]` → `effects[i].value.<x|y|z>` (max_torque, std and value are the
/// message's `value`), `effects[i].<key>` (mu, orbit_radius, frame), `effects[i]` (the effect).
std::string effectRequestField(const std::string& item, const std::string& key) {
  if (key.empty()) return item;
  const std::size_t bracket = key.find('[');
  const std::string name = key.substr(0, bracket);
  const bool vector = name == "max_torque" || name == "std" || name == "value";
  std::string out = item + "." + (vector ? std::string("value") : name);
  if (vector && bracket != std::string::npos && bracket + 1 < key.size()) {
    const char axis = key[bracket + 1];
    if (axis >= '0' && axis <= '2') out += std::string(".") + "xyz"[axis - '0'];
  }
  return out;
}

}  // namespace

std::string requestFieldName(const std::string& core_field) {
  const auto renamed = kRenamedFields.find(core_field);
  if (renamed != kRenamedFields.end()) return renamed->second;
  // The scene nests the array under `actuators`; the request has it at the top level.
  if (startsWith(core_field, kSceneWheelsField)) return core_field.substr(kSceneWheelsPrefix);
  // Paths of list items: `<list>[i].<kind>[.<key>]` (the scene nests a constraint's or effect's
  // values under its kind; the message has flat fields and a `type`).
  const std::size_t first = core_field.find('.');
  if (first == std::string::npos) return core_field;
  const std::string item = core_field.substr(0, first);
  const std::size_t second = core_field.find('.', first + 1);
  const std::string kind = core_field.substr(first + 1, second - first - 1);
  const std::string key = second == std::string::npos ? "" : core_field.substr(second + 1);
  if (startsWith(item, "constraints[")) return constraintRequestField(item, kind, key);
  if (startsWith(item, "effects[")) return effectRequestField(item, key);
  return core_field;
}

std::string requestErrorMessage(const FieldError& error) {
  if (error.field().empty()) return error.what();
  return requestFieldName(error.field()) + ": " + error.detail();
}

OutputSelection outputSelectionFromRequest(const std::string& return_maneuver, int output_steps) {
  OutputSelection out;
  if (!return_maneuver.empty()) {
    out.output = parseIn(kManeuverOutputNames, return_maneuver, "return_maneuver");
  }
  if (output_steps < 0 || output_steps == 1) {
    throw InvalidInput(
        "output_steps: must be 0 (every node) or >= 2 (about that many nodes, "
        "both ends included), got " +
        std::to_string(output_steps));
  }
  if (out.output == ManeuverOutput::None && output_steps != 0) {
    throw InvalidInput("output_steps: " + std::to_string(output_steps) +
                       " given with return_maneuver 'none' (no maneuver is returned): leave it 0");
  }
  out.max_nodes = output_steps;
  return out;
}

std::vector<int> decimatedRows(int steps, int max_nodes) {
  std::vector<int> rows;
  const int stride = max_nodes <= 0 || max_nodes >= steps + 1
                         ? 1
                         : (steps + max_nodes - 2) / (max_nodes - 1);  // ceil(N / (max_nodes − 1))
  for (int k = 0; k < steps; k += stride) rows.push_back(k);
  rows.push_back(steps);
  return rows;
}

Maneuver decimatedManeuver(const Maneuver& m, int max_nodes) {
  const int N = m.steps();
  if (max_nodes <= 0 || max_nodes >= N + 1) return m;
  Maneuver out;
  out.time_step = m.time_step;
  for (int k : decimatedRows(N, max_nodes)) {
    out.time.push_back(m.time[k]);
    out.attitude.push_back(m.attitude[k]);
    out.angular_velocity.push_back(m.angular_velocity[k]);
    out.torque.push_back(m.torque[k]);
  }
  return out;
}

WheelStates decimatedWheelStates(const WheelStates& states, int max_nodes) {
  const int N = static_cast<int>(states.momentum.size()) - 1;
  if (max_nodes <= 0 || max_nodes >= N + 1) return states;
  WheelStates out;
  for (int k : decimatedRows(N, max_nodes)) {
    out.momentum.push_back(states.momentum[k]);
    out.torque.push_back(states.torque[k]);
  }
  return out;
}

int stepsFromRequest(int steps, const PlannerDefaults& defaults) {
  if (steps == 0) return defaults.steps;
  if (steps > defaults.max_steps) {
    throw InvalidInput("steps: " + std::to_string(steps) +
                       " exceeds the node's ~max_steps = " + std::to_string(defaults.max_steps));
  }
  return steps;
}

AccuracyTarget accuracyTargetFromRequest(const std::string& measure, double target,
                                         const PlannerDefaults& defaults) {
  const std::string value = exactNumber(target);
  AccuracyTarget t;
  if (measure.empty()) {
    if (target != 0.0) {
      throw InvalidInput(std::string("accuracy_target: ") + value +
                         " given without accuracy_measure (terminal_miss or cost_error)");
    }
    return t;
  }
  t.measure = parseAccuracyMeasure(measure, "accuracy_measure");
  if (!std::isfinite(target) || !(target > 0.0)) {
    throw InvalidInput("accuracy_target: must be a finite number > 0 (" + measure + "), got " +
                       value);
  }
  t.value = target;
  t.max_steps = defaults.max_steps;
  return t;
}

double effectiveTimeBudget(double requested, const PlannerDefaults& defaults) {
  if (!std::isfinite(requested) || requested < 0.0) return 0.0;
  double budget = requested > 0.0 ? requested : defaults.time_budget;
  if (defaults.max_solve_time > 0.0 && (budget <= 0.0 || budget > defaults.max_solve_time)) {
    budget = defaults.max_solve_time;  // the node's ~max_solve_time bounds all
  }
  return budget;
}

}  // namespace ros_conversions
}  // namespace attitude_planner
