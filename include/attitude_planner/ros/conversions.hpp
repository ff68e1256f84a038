// Conversions between the ROS interfaces (msg/srv/action) and the ROS-free core types.
// Every check that is about the *encoding* (a quaternion that is not unit, a NaN in a message)
// lives here and throws InvalidInput naming the field; every check about the *problem* lives in
// the core (validateProblem).
#pragma once

#include <optional>
#include <string>
#include <vector>

#include <geometry_msgs/Quaternion.h>
#include <geometry_msgs/Vector3.h>
#include <nav_msgs/Odometry.h>
#include <ros/time.h>
#include <sensor_msgs/JointState.h>
#include <boost/array.hpp>

#include "attitude_planner/AttitudeManeuver.h"
#include "attitude_planner/Constraint.h"
#include "attitude_planner/DriftTwoInputManeuver.h"
#include "attitude_planner/DurationVerdictSummary.h"
#include "attitude_planner/Effect.h"
#include "attitude_planner/MinimumTimeSummary.h"
#include "attitude_planner/NamedFigure.h"
#include "attitude_planner/PlanAttempt.h"
#include "attitude_planner/PlanDriftTwoInput.h"
#include "attitude_planner/ReactionWheelArray.h"
#include "attitude_planner/ReactionWheelsSummary.h"
#include "attitude_planner/analysis/tracking.hpp"
#include "attitude_planner/analysis/wheel_peaks.hpp"
#include "attitude_planner/drift_two_input/planner.hpp"
#include "attitude_planner/dynamics/maneuver.hpp"
#include "attitude_planner/errors.hpp"
#include "attitude_planner/io/scene.hpp"
#include "attitude_planner/planner.hpp"

namespace attitude_planner {
namespace ros_conversions {

/// A measured rigid-body state (nav_msgs/Odometry, the tracker's ~plant external input):
/// pose.pose.orientation the attitude body → header.frame_id, twist.twist.angular the body rate
/// [rad/s] in child_frame_id.
using MeasuredState = RigidBodyState;

/// The attitude and body rate of an Odometry message (the position, the linear velocity and the
/// covariances are not used); throws InvalidInput naming the field for a quaternion that is not
/// unit or a non-finite rate. Frames are the caller's to check.
MeasuredState measuredStateFromMsg(const nav_msgs::Odometry& msg);

/// An Odometry message of the state (R, Ω): orientation R (body `child_frame` → `frame`), angular
/// twist Ω in the body frame, position and linear velocity zero (attitude_plant_node).
nav_msgs::Odometry odometryToMsg(const Matrix3& attitude, const Vector3& angular_velocity,
                                 const ros::Time& stamp, const std::string& frame,
                                 const std::string& child_frame);

/// Rotation matrix (body → world) of a message quaternion; throws InvalidInput naming `field` if
/// the quaternion has a non-finite entry, is zero or is not unit within kQuaternionNormTolerance
/// (the scene's rule: attitudeFromQuaternion, io/scene.hpp).
Matrix3 attitudeFromMsg(const geometry_msgs::Quaternion& q, const std::string& field);
/// Unit Hamilton quaternion (w ≥ 0) of a rotation matrix.
geometry_msgs::Quaternion attitudeToMsg(const Matrix3& R);
/// Eigen vector of a message vector (no check: the core checks finiteness with the field name).
Vector3 vectorFromMsg(const geometry_msgs::Vector3& v);
/// Eigen vector of a message vector that must be finite (a NaN in a message is an encoding error:
/// throws InvalidInput naming `field` and the value).
Vector3 finiteVectorFromMsg(const geometry_msgs::Vector3& v, const std::string& field);
/// Message vector of an Eigen vector.
geometry_msgs::Vector3 vectorToMsg(const Vector3& v);
/// Any message with fields x, y, z (geometry_msgs Vector3, Point) from v.
template <class Msg>
Msg xyzToMsg(const Vector3& v) {
  Msg m;
  m.x = v.x();
  m.y = v.y();
  m.z = v.z();
  return m;
}
/// J [kg·m²] from a row-major float64[9] (symmetry and definiteness are checked by the core).
Matrix3 inertiaFromMsg(const boost::array<double, 9>& j);
/// Row-major float64[9] of J [kg·m²].
boost::array<double, 9> inertiaToMsg(const Matrix3& J);

/// Message of a maneuver planned for `problem`; header.frame_id = world_frame, child_frame_id =
/// body_frame, header.stamp = stamp (the time t_0 refers to); `constraints` = problem.constraints,
/// `reaction_wheels` = problem.reaction_wheels; `wheel_states` (one row per maneuver row; null:
/// none) fills wheel_torque and wheel_momentum row-major.
AttitudeManeuver maneuverToMsg(const Maneuver& maneuver, const PlanningProblem& problem,
                               const std::string& world_frame, const std::string& body_frame,
                               const ros::Time& stamp, const WheelStates* wheel_states = nullptr);

/// The core array of a ReactionWheels message (`field` names it in errors, e.g.
/// "reaction_wheels"): empty spin_axes = none (then every other field must be empty / 0: throws
/// InvalidInput naming `field`.spin_axes otherwise); a non-finite axis is refused naming
/// `field`.spin_axes[i]; max_momentum_norm 0 = no envelope. The values (span, limits, initial
/// momenta) are the core's to check (validateReactionWheels, through validateProblem).
ReactionWheels reactionWheelsFromMsg(const ReactionWheelArray& msg, const std::string& field);
/// The message of a core array (no envelope: max_momentum_norm 0).
ReactionWheelArray reactionWheelsToMsg(const ReactionWheels& wheels);
/// The peaks of `wheels` against their limits as a message (the JSON summary's reaction_wheels);
/// `effort_minimized` the plan's PlanResult::minimized_effort (a flown path minimizes nothing:
/// none, the field left empty).
ReactionWheelsSummary wheelSummaryToMsg(
    const ReactionWheels& wheels, const WheelPeaks& peaks,
    std::optional<MinimizedEffort> effort_minimized = std::nullopt);
/// The effects a body with reaction wheels is flown under (attitude_plant_node's ~scene, the
/// tracker's run): gravity_gradient and disturbance_torque act on the body, the wheels only move
/// momentum between body and wheels; actuator_limits and torque_noise act on a body torque that
/// no wheel makes (the wheels' own max_torque bounds them). Throws InvalidInput naming `field`
/// and the first of those.
void requireWheelBodyEffects(const std::vector<EffectSpec>& effects, const std::string& field);
/// One value per wheel from a sensor_msgs/JointState's `names` and one of its value arrays
/// (`values`: effort for a wheel command, velocity for a wheel measurement), looked up by the
/// names wheel_1 .. wheel_n (any order; other joints ignored). Throws InvalidInput naming
/// `field` for a missing wheel, a value array shorter than the names, or a non-finite value.
Eigen::VectorXd wheelJointValues(const std::vector<std::string>& names,
                                 const std::vector<double>& values, int wheels,
                                 const std::string& field);
/// A JointState of n wheels (names wheel_1 .. wheel_n, frame `frame`, stamped `stamp`) carrying
/// `effort` and, when not empty, `velocity`.
sensor_msgs::JointState wheelJointState(const Eigen::VectorXd& effort,
                                        const Eigen::VectorXd& velocity, const std::string& frame,
                                        const ros::Time& stamp);
/// `rows` vectors of `wheels` entries from a row-major array (AttitudeManeuver.wheel_torque /
/// wheel_momentum); throws InvalidInput naming `field` for a wrong length or a non-finite entry.
std::vector<Eigen::VectorXd> wheelRowsFromMsg(const std::vector<double>& values, int rows,
                                              int wheels, const std::string& field);
/// Core maneuver of a message; throws InvalidInput if the arrays disagree in length, N < 1, or an
/// entry is not finite / not a unit quaternion.
Maneuver maneuverFromMsg(const AttitudeManeuver& msg);

/// The warm start of a request's `initial_guess` (`field` names it in errors): false, leaving
/// `guess` alone, when it has no attitude rows (none); else its rows (the columns other than
/// the attitudes may be left empty), checked by validateInitialGuess. Throws InvalidInput naming
/// the field, the row and the value (e.g. "initial_guess.attitude[3]: not a unit quaternion").
bool initialGuessFromMsg(const AttitudeManeuver& msg, const std::string& field, Maneuver* guess);

/// Message of a drift + two-input trajectory (seed 001): time, attitude g(t_k), control
/// (u1, u2, 0) [rad/s], costate p [c·rad/s]; time_step = t_1 − t_0 [s]; frames and stamp as
/// maneuverToMsg.
DriftTwoInputManeuver driftManeuverToMsg(const DriftTwoInputTrajectory& trajectory,
                                         const DriftTwoInputWeights& weights,
                                         const std::string& world_frame,
                                         const std::string& body_frame, const ros::Time& stamp);
/// Core trajectory (t, g, u, p; cost left 0: not transported) and weights of a message; throws
/// InvalidInput if the arrays disagree in length, N < 1, a weight is not > 0, an entry is not
/// finite or not a unit quaternion, or a control's z component is not 0.
DriftTwoInputTrajectory driftManeuverFromMsg(const DriftTwoInputManeuver& msg,
                                             DriftTwoInputWeights* weights);

/// Core spec of an Effect message (`field` names it in errors, e.g. "effects[2]"). Throws
/// InvalidInput naming the field and the value for an unknown type or a field the type does not
/// use that is not left at zero; the values themselves are checked by validateEffects.
EffectSpec effectFromMsg(const Effect& msg, const std::string& field);
/// Effect message of a core spec.
Effect effectToMsg(const EffectSpec& spec);
/// The effects of a planning request: converted, validated (validateEffects) and put into the
/// planning model of `problem` (applyEffects). torque_noise is refused: it is not plannable.
void applyRequestEffects(const std::vector<Effect>& effects, PlanningProblem* problem);

/// Core constraint of a Constraint message (`field` names it in errors, e.g. "constraints[1]").
/// Throws InvalidInput for an unknown type or a field of another type that is not left at zero;
/// the values themselves are checked by validateConstraints (validateProblem).
PlanningConstraint constraintFromMsg(const Constraint& msg, const std::string& field);
/// The Constraint message of a core constraint (the fields its kind does not use left at 0).
Constraint constraintToMsg(const PlanningConstraint& constraint);

/// One attempt of the structured trail (PlanResult::attempts) as a message, every enumeration by
/// the name the JSON summary gives it.
PlanAttempt attemptToMsg(const Attempt& attempt);
/// What backs a minimum-time answer's T* (PlanResult::minimum_time) as a message.
MinimumTimeSummary minimumTimeToMsg(const MinimumTimeCertificate& certificate);
/// The verdict on durations of a result (PlanResult::duration_verdict) as a message.
DurationVerdictSummary durationVerdictToMsg(const DurationVerdict& verdict);
/// A result's verdict's figures (PlanResult::verdict) as messages, by the names and in the order
/// of the JSON summary's `verdict.figures` (the kind is verdictKindName).
std::vector<NamedFigure> verdictFiguresToMsg(const Verdict& verdict);

/// The request field a core error names, in the request's own spelling: the core (and the scene)
/// say `initial.angular_velocity`, `constraints[0].max_torque_norm`,
/// `constraints[1].keep_out.body_axis`, `effects[0].actuator_limits.max_torque[2]`; the request
/// says `initial_angular_velocity`, `constraints[0].limit`, `constraints[1].body_axis`,
/// `effects[0].value.z`. Fields spelt alike (`steps`, `duration`, ...) are returned unchanged.
std::string requestFieldName(const std::string& core_field);
/// The message of an error in the request's vocabulary: "<request field>: <detail>" when the
/// error carries its field apart (FieldError::field), else its message unchanged.
std::string requestErrorMessage(const FieldError& error);

/// How much of the planned maneuver a response carries (request field `return_maneuver`).
enum class ManeuverOutput {
  Nodes,  ///< every node, or about `output_steps` of them (default; "" or "nodes")
  None,   ///< none: the summary figures only ("none")
};
/// The names of `return_maneuver` ("" also means "nodes").
inline constexpr NamedValue<ManeuverOutput> kManeuverOutputNames[] = {
    {ManeuverOutput::Nodes, "nodes"},
    {ManeuverOutput::None, "none"},
};
/// What a response carries of the maneuver: none, or at most `max_nodes` rows (0 = all).
struct OutputSelection {
  ManeuverOutput output = ManeuverOutput::Nodes;
  int max_nodes = 0;  ///< 0: all N + 1 nodes; M >= 2: about M nodes, both ends included
};
/// The output selection of a request (`return_maneuver`, `output_steps`); throws InvalidInput
/// naming the field and the value (an unknown name; output_steps < 0 or 1, or given with "none").
OutputSelection outputSelectionFromRequest(const std::string& return_maneuver, int output_steps);
/// The rows of `maneuver` kept by a decimation to at most `max_nodes` nodes (0 or >= N + 1: all):
/// k = 0, s, 2s, ..., N with the stride s = ceil(N / (max_nodes - 1)), so both ends are kept and
/// the last interval may be shorter. time[] keeps each row's t_k; time_step stays the plan's h.
Maneuver decimatedManeuver(const Maneuver& maneuver, int max_nodes);
/// The rows k decimatedManeuver keeps of a plan of `steps` steps (all for max_nodes 0).
std::vector<int> decimatedRows(int steps, int max_nodes);
/// The same rows of a plan's wheel states.
WheelStates decimatedWheelStates(const WheelStates& states, int max_nodes);

/// Planner defaults that fill the empty/zero fields of a request (the node's private params).
struct PlannerDefaults {
  SchemeKind scheme = SchemeKind::Paper;
  SolverKind solver = SolverKind::Structured;
  /// N of a request that leaves `steps` at 0 (both services): the seed's example resolution.
  int steps = 128;
  double tolerance = 1e-10;   ///< optimality tolerance (scaled residual)
  int max_iterations = 200;   ///< iteration limit
  double time_budget = 30.0;  ///< wall-time limit [s]; 0 = none (then max_solve_time)
  int max_steps = 100000;     ///< largest accepted N
  /// Cap on every request's time budget [s] (> 0): a request asking for more, or for none
  /// (time_budget 0 with ~time_budget 0), is solved with this budget, so no solve runs away.
  double max_solve_time = 300.0;
};

/// The N of a request: `steps`, or defaults.steps for 0; throws InvalidInput naming `steps` if it
/// exceeds the node's ~max_steps. The planners check the lower bounds (validateProblem, N >= 4;
/// planDriftTwoInput, N >= 1).
int stepsFromRequest(int steps, const PlannerDefaults& defaults);

/// Builds the core request of a plan_drift_two_input call (zero fields take the documented
/// defaults). Throws InvalidInput naming the field and the value; the core checks the rest.
DriftTwoInputRequest driftRequestFromMsg(const PlanDriftTwoInput::Request& req,
                                         const PlannerDefaults& defaults);

/// The accuracy target of a request: inactive for an empty measure (then accuracy_target must be
/// 0); otherwise the measure ("terminal_miss" | "cost_error"), the target (finite, > 0) and the
/// node's ~max_steps as the largest N. Throws InvalidInput naming the field and the value.
AccuracyTarget accuracyTargetFromRequest(const std::string& measure, double target,
                                         const PlannerDefaults& defaults);

/// The deadline [s] of a request's solve: its `time_budget`, or the node's ~time_budget when 0,
/// capped by ~max_solve_time; 0 = none. (An invalid budget, refused by problemFromRequest, gives
/// 0.)
double effectiveTimeBudget(double requested, const PlannerDefaults& defaults);

/// Builds the problem and solver options of a service request or action goal (both have the same
/// fields). Throws InvalidInput naming the field and the value.
template <class Request>
PlanningProblem problemFromRequest(const Request& req, const PlannerDefaults& defaults,
                                   SolverOptions* options);

/// The request's end condition: "" or "attitude" (final_attitude), or "pointing" with its two
/// vectors (finite; nonzero is the core's rule, validateProblem). Throws InvalidInput naming
/// end_condition and the value for another name.
EndCondition endConditionFromRequest(const std::string& name,
                                     const geometry_msgs::Vector3& body_axis,
                                     const geometry_msgs::Vector3& world_direction);

// ---- templates ----------------------------------------------------------------------------------

template <class Request>
PlanningProblem problemFromRequest(const Request& req, const PlannerDefaults& defaults,
                                   SolverOptions* options) {
  PlanningProblem p;
  p.inertia = inertiaFromMsg(req.inertia);
  p.allow_nonphysical_inertia = req.allow_nonphysical_inertia;
  p.duration = req.duration;
  // With an accuracy target the planner chooses N (at most ~max_steps): `steps` is not used.
  p.steps = req.accuracy_measure.empty() ? stepsFromRequest(req.steps, defaults) : req.steps;
  p.accuracy = accuracyTargetFromRequest(req.accuracy_measure, req.accuracy_target, defaults);
  p.initial_attitude = attitudeFromMsg(req.initial_attitude, "initial_attitude");
  p.initial_velocity =
      finiteVectorFromMsg(req.initial_angular_velocity, "initial_angular_velocity");
  p.final_attitude = attitudeFromMsg(req.final_attitude, "final_attitude");
  p.final_velocity = finiteVectorFromMsg(req.final_angular_velocity, "final_angular_velocity");
  p.scheme = defaults.scheme;
  if (!req.scheme.empty()) applySchemeName(req.scheme, "scheme", &p);
  if (!req.direction.empty()) p.direction = parseDirection(req.direction, "direction");
  p.extra_revolutions = req.extra_revolutions;  // < 0 refused by validateProblem
  if (!req.objective.empty()) p.objective = parseObjective(req.objective, "objective");
  p.time_margin = req.time_margin;  // rules in validateProblem
  options->solver = req.solver.empty() ? defaults.solver : parseSolver(req.solver, "solver");
  if (!std::isfinite(req.tolerance) || req.tolerance < 0.0) {
    throw InvalidInput("tolerance: must be a finite number >= 0 (0 = default), got " +
                       exactNumber(req.tolerance));
  }
  options->tolerance = req.tolerance > 0.0 ? req.tolerance : defaults.tolerance;
  if (req.max_iterations < 0) {
    throw InvalidInput("max_iterations: must be >= 0 (0 = default), got " +
                       std::to_string(req.max_iterations));
  }
  options->max_iterations = req.max_iterations > 0 ? req.max_iterations : defaults.max_iterations;
  if (!std::isfinite(req.time_budget) || req.time_budget < 0.0) {
    throw InvalidInput("time_budget: must be a finite number >= 0 s (0 = default), got " +
                       exactNumber(req.time_budget));
  }
  options->time_budget_s = effectiveTimeBudget(req.time_budget, defaults);
  applyRequestEffects(req.effects, &p);
  if (!std::isfinite(req.start_time) || req.start_time < 0.0) {
    throw InvalidInput("start_time: must be a finite number >= 0 s, got " +
                       exactNumber(req.start_time));
  }
  if (req.start_time > 0.0 && p.effects && !p.effects->empty()) {
    p.effects = std::make_shared<const EffectModel>(p.effects->timeShifted(req.start_time));
  }
  for (std::size_t i = 0; i < req.constraints.size(); ++i) {
    p.constraints.push_back(
        constraintFromMsg(req.constraints[i], "constraints[" + std::to_string(i) + "]"));
  }
  validateConstraints(p.constraints, "constraints");
  p.end_condition = endConditionFromRequest(req.end_condition, req.pointing_body_axis,
                                            req.pointing_world_direction);
  p.reaction_wheels = reactionWheelsFromMsg(req.reaction_wheels, "reaction_wheels");
  return p;
}

}  // namespace ros_conversions
}  // namespace attitude_planner
