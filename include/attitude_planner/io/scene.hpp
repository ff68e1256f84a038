// Scene files (YAML, docs/DESIGN.md "Scene file"): what to plan and which effects are present.
//
// Keys (units SI, REP 103):
//   inertia          3×3 nested list, or 3 principal moments [a, b, c]        [kg·m²]
//   duration         T > 0                                                     [s]
//   steps            N, kMinSteps ≤ N ≤ kMaxSteps (planning/problem.hpp, validateProblem)
//   initial, final   {attitude: A, angular_velocity: [x, y, z]}                [rad/s] body
//                    (drift_two_input: {attitude: A} only; angular_velocity is an error there,
//                    the kinematic system's body rate E3 + u1 E1 + u2 E2 is not a boundary value)
//                    A = {axis: [x, y, z], angle: a [rad]} or {quaternion: [w, x, y, z]}
//   effects          optional list of single-key maps (see EffectSpec); absent or []: none
//   scheme           optional: paper (default) | variational | second_order | fourth_order
//   system           optional: rigid_body (default) | drift_two_input (seed 001)
//   control_weights  [c1, c2] > 0, only with system: drift_two_input
//   initial_costate  optional [p1, p2, p3] (finite), only with system: drift_two_input: guess for
//                    the extremal's p(0) [c·rad/s] (default: the planner's own starts)
//                    (drift_two_input: must be absent or [])
//   direction        optional: shortest (default) | long_way (rigid_body; see RotationDirection)
//   extra_revolutions optional integer ≥ 0: whole extra turns (rigid_body; validateProblem)
//   allow_nonphysical_inertia  optional bool (default false): accept an SPD inertia whose
//                    principal moments violate J1 + J2 ≥ J3 (the seed's example inertia does)
#pragma once

#include <Eigen/Core>
#include <cstdint>
#include <optional>
#include <string>
#include <variant>
#include <vector>

#include "attitude_planner/drift_two_input/planner.hpp"
#include "attitude_planner/name_table.hpp"
#include "attitude_planner/planner.hpp"

namespace attitude_planner {

/// Gravity-gradient torque of a circular orbit: 3 μ/r³ (ĉ × J ĉ), ĉ the nadir in the body frame.
struct GravityGradientSpec {
  double mu = 0.0;            ///< gravitational parameter μ [m³/s²], > 0
  double orbit_radius = 0.0;  ///< orbit radius r [m], > 0
};

/// A constant disturbance torque [N·m].
struct DisturbanceTorqueSpec {
  TorqueFrame frame = TorqueFrame::Body;  ///< the frame `value` is expressed in
  Vector3 value = Vector3::Zero();        ///< torque [N·m]
};

/// Per-axis saturation of the control torque (body frame).
struct ActuatorLimitsSpec {
  Vector3 max_torque = Vector3::Zero();  ///< |τ_i| ≤ max_torque_i [N·m], each > 0
};

/// Zero-mean Gaussian noise added to the applied torque (body frame).
struct TorqueNoiseSpec {
  Vector3 std = Vector3::Zero();  ///< standard deviation per axis [N·m], each ≥ 0
  std::uint64_t seed = 0;         ///< PRNG seed (reproducible runs)
};

/// One entry of the scene's `effects:` list.
using EffectSpec =
    std::variant<GravityGradientSpec, DisturbanceTorqueSpec, ActuatorLimitsSpec, TorqueNoiseSpec>;

/// Which effect a spec is (the alternatives of EffectSpec are in the order of EffectKind).
EffectKind effectKindOf(const EffectSpec& effect);
/// The YAML key of an effect ("gravity_gradient", "disturbance_torque", ...).
std::string effectName(const EffectSpec& effect);

/// Which system a scene describes.
enum class SystemKind {
  RigidBody,      ///< the fully actuated rigid body (seed 000), planned by planManeuver
  DriftTwoInput,  ///< the drift + two-input kinematic system (seed 001), planDriftTwoInput
};

/// The names of the systems (scene key `system`, JSON `system`).
inline constexpr NamedValue<SystemKind> kSystemNames[] = {
    {SystemKind::RigidBody, "rigid_body"},
    {SystemKind::DriftTwoInput, "drift_two_input"},
};

/// "rigid_body" or "drift_two_input".
inline std::string systemName(SystemKind system) {
  return nameIn(kSystemNames, system);
}
/// The system named `text`; throws InvalidInput naming `field`, the value and the accepted names.
inline SystemKind parseSystem(const std::string& text, const std::string& field) {
  return parseIn(kSystemNames, text, field);
}

/// How far from 1 the norm of a given quaternion may be before it is an error rather than
/// round-off in a hand-typed value (0.7071 has norm 0.99998); it is normalized after the check.
constexpr double kQuaternionNormTolerance = 1e-3;

/// The rotation (body → world) of a Hamilton quaternion [w, x, y, z] given by a user, in a scene
/// or a message: it must be finite, nonzero and of norm within kQuaternionNormTolerance of 1.
/// Throws InvalidInput naming `field` and the quaternion (`shown`: as the user wrote it; empty:
/// its numbers).
Matrix3 attitudeFromQuaternion(const Eigen::Vector4d& wxyz, const std::string& field,
                               const std::string& shown = "");

/// Checks the values of a list of effects, however they arrived (scene file, service request):
/// μ, r > 0; frame body|world; finite torques; max_torque > 0; std ≥ 0; at most one of each effect
/// except disturbance_torque (several add up). Throws InvalidInput naming
/// `field`[i].<effect>.<key> and the value.
void validateEffects(const std::vector<EffectSpec>& effects, const std::string& field);

/// A parsed scene. Unknown keys and bad values throw InvalidInput naming the key and the value.
struct Scene {
  PlanningProblem problem;            ///< what to plan (SI units, see planner.hpp)
  std::string source;                 ///< file name (for messages)
  SystemKind system = SystemKind::RigidBody;
  Eigen::Vector2d control_weights = Eigen::Vector2d::Ones();  ///< c1, c2 (drift_two_input) [-]
  /// Guess for p(0) [c·rad/s] (drift_two_input only); empty: the planner's default starts.
  std::optional<Vector3> initial_costate;
  std::vector<EffectSpec> effects;  ///< in file order
  /// true: the inertia need not satisfy the triangle inequality (only SPD is required).
  bool allow_nonphysical_inertia = false;
};

/// Parses YAML text; `source` names it in error messages.
Scene parseScene(const std::string& yaml_text, const std::string& source = "<scene>");
/// Reads and parses a scene file.
Scene loadScene(const std::string& path);

/// Writes a scene as YAML that parseScene reads back to the same problem (attitudes as
/// quaternions, numbers with %.17g).
std::string formatScene(const Scene& scene);

/// The plannable effects of `specs` (gravity gradient, disturbance torques) as one model for
/// J = inertia; null if there are none. parseScene stores it in Scene::problem.effects.
std::shared_ptr<const EffectModel> plannableEffects(const std::vector<EffectSpec>& specs,
                                                    const Matrix3& inertia);
/// Puts `specs` into the planning model of `problem` (whose inertia must be set): the plannable
/// effects into problem->effects, actuator_limits into problem->max_torque. torque_noise is not
/// plannable and is left to the replay (actuationOf).
void applyEffects(const std::vector<EffectSpec>& specs, PlanningProblem* problem);
/// The tracker-side effects of `specs` (actuator_limits, torque_noise).
Actuation actuationOf(const std::vector<EffectSpec>& specs);

/// Throws InvalidInput if planManeuver cannot plan this scene faithfully (effects present, or a
/// system other than rigid_body): a scene's content is never silently ignored. A drift_two_input
/// scene is planned by planDriftTwoInput instead (driftTwoInputRequest).
void requirePlannable(const Scene& scene);

/// The planDriftTwoInput request of a `system: drift_two_input` scene: g0, g1, T, N, (c1, c2) and
/// the initial_costate guess (solver settings at their defaults). Throws InvalidInput naming the
/// scene if it is not a drift_two_input scene or lists effects (not modelled for this system).
DriftTwoInputRequest driftTwoInputRequest(const Scene& scene);

}  // namespace attitude_planner
