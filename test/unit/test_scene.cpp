// Scene files: the shipped scenes parse to the seed's problems; every class of bad input is an
// InvalidInput whose message names the key path and the offending value; formatScene round-trips.
#include <gtest/gtest.h>

#include <cmath>
#include <set>
#include <string>

#include "attitude_planner/errors.hpp"
#include "attitude_planner/io/scene.hpp"
#include "scene_errors.hpp"

namespace ap = attitude_planner;

namespace {

const std::string kSceneDir = AP_SOURCE_DIR "/scenes/";

/// A valid scene; tests replace one line to make it invalid.
const std::string kValid =
    R"(inertia: [[13.25, -7.80, -11.40], [-7.80, 16.25, 4.71], [-11.40, 4.71, 18.37]]
allow_nonphysical_inertia: true
duration: 12.8
steps: 128
initial: {attitude: {axis: [1, 0, 0], angle: 0.0}, angular_velocity: [0, 0, 0]}
final:   {attitude: {axis: [1, 0, 0], angle: 1.0471975511965976}, angular_velocity: [0, 0, 0]}
effects: []
)";

/// `base` with the line starting with `key` replaced by `line` (or appended if absent).
std::string withLine(const std::string& key, const std::string& line, std::string text = kValid) {
  const std::size_t at = text.find(key);
  if (at == std::string::npos || (at != 0 && text[at - 1] != '\n')) return text + line + "\n";
  const std::size_t end = text.find('\n', at);
  return text.replace(at, end - at, line);
}

/// `text` without the allow_nonphysical_inertia opt-out (so the triangle inequality is enforced).
std::string strict(std::string text) {
  const std::string line = "allow_nonphysical_inertia: true\n";
  const std::size_t at = text.find(line);
  return at == std::string::npos ? text : text.replace(at, line.size(), "");
}

std::string errorOf(const std::string& text) {
  return attitude_planner_test::sceneErrorOf(text);
}

#define EXPECT_CONTAINS(haystack, needle) \
  EXPECT_NE(std::string(haystack).find(needle), std::string::npos) << "message: " << (haystack)

ap::Matrix3 seedInertia() {
  ap::Matrix3 J;
  J << 13.25, -7.80, -11.40, -7.80, 16.25, 4.71, -11.40, 4.71, 18.37;
  return J;
}

}  // namespace

TEST(SceneFiles, RestToRestIsSeedExampleOne) {
  const ap::Scene s = ap::loadScene(kSceneDir + "rest_to_rest.yaml");
  const ap::PlanningProblem& p = s.problem;
  EXPECT_EQ(p.inertia, seedInertia());
  EXPECT_EQ(p.duration, 12.8);
  EXPECT_EQ(p.steps, 128);
  EXPECT_EQ(p.scheme, ap::SchemeKind::Paper);
  EXPECT_LT((p.initial_attitude - ap::Matrix3::Identity()).norm(), 1e-15);
  EXPECT_EQ(p.initial_velocity, ap::Vector3::Zero());
  EXPECT_LT((ap::so3::log(p.final_attitude) - ap::Vector3(M_PI / 3, 0, 0)).norm(), 1e-15);
  EXPECT_EQ(p.final_velocity, ap::Vector3::Zero());
  EXPECT_TRUE(s.effects.empty());
  EXPECT_EQ(s.system, ap::SystemKind::RigidBody);
  EXPECT_NO_THROW(ap::requirePlannable(s));
}

TEST(SceneFiles, SlewUpIsSeedExampleTwo) {
  const ap::Scene s = ap::loadScene(kSceneDir + "slew_up.yaml");
  const ap::PlanningProblem& p = s.problem;
  EXPECT_EQ(p.inertia, seedInertia());
  EXPECT_EQ(p.duration, 12.8);
  EXPECT_EQ(p.steps, 128);
  EXPECT_LT((ap::so3::log(p.final_attitude) - ap::Vector3(M_PI / 6, 0, 0)).norm(), 1e-15);
  EXPECT_EQ(p.final_velocity, ap::Vector3(0.3, 0.2, 0.3));
  EXPECT_NO_THROW(ap::requirePlannable(s));
}

TEST(SceneFiles, ShippedInlineExampleParses) {
  const ap::Scene s = ap::parseScene(kValid);
  EXPECT_EQ(s.problem.steps, 128);
}

TEST(SceneOptionalKeys, DiagonalInertiaSchemeAndQuaternion) {
  std::string text = withLine("inertia", "inertia: [1.5, 2.5, 3.5]");
  text = withLine("final",
                  "final: {attitude: {quaternion: [-0.5, 0.5, 0.5, 0.5]}, "
                  "angular_velocity: [0.1, 0, 0]}",
                  text);
  text += "scheme: variational\n";
  const ap::Scene s = ap::parseScene(text);
  EXPECT_EQ(s.problem.inertia, ap::Vector3(1.5, 2.5, 3.5).asDiagonal().toDenseMatrix());
  EXPECT_EQ(s.problem.scheme, ap::SchemeKind::Variational);
  // −q is the same rotation as q: 120° about (1,1,1)/√3 either way (w < 0 is accepted).
  const ap::Matrix3 expected = ap::so3::fromAxisAngle(ap::Vector3(1, 1, 1), -2 * M_PI / 3);
  EXPECT_LT((s.problem.final_attitude - expected).norm(), 1e-15);
}

TEST(SceneOptionalKeys, NearUnitQuaternionIsNormalized) {
  const std::string text = withLine("final",
                                    "final: {attitude: {quaternion: [0.7071, 0.7071, 0, 0]}, "
                                    "angular_velocity: [0, 0, 0]}");
  const ap::Scene s = ap::parseScene(text);
  EXPECT_LT(
      (s.problem.final_attitude - ap::so3::fromAxisAngle(ap::Vector3::UnitX(), M_PI / 2)).norm(),
      1e-14);
}

TEST(SceneOptionalKeys, EffectsAreParsedIntoThePlanningModelAndActuation) {
  const std::string text =
      withLine("effects",
               "effects:\n"
               "  - gravity_gradient: {mu: 3.986004418e14, orbit_radius: 7.0e6}\n"
               "  - disturbance_torque: {frame: world, value: [1e-4, 0, -2e-4]}\n"
               "  - disturbance_torque: {frame: body, value: [0, 1e-5, 0]}\n"
               "  - actuator_limits: {max_torque: [0.5, 0.5, 0.25]}\n"
               "  - torque_noise: {std: [1e-3, 1e-3, 0], seed: 42}");
  const ap::Scene s = ap::parseScene(text, "fx.yaml");
  ASSERT_EQ(s.effects.size(), 5u);
  const auto& g = std::get<ap::GravityGradientSpec>(s.effects[0]);
  EXPECT_EQ(g.mu, 3.986004418e14);
  EXPECT_EQ(g.orbit_radius, 7.0e6);
  const auto& d = std::get<ap::DisturbanceTorqueSpec>(s.effects[1]);
  EXPECT_EQ(d.frame, ap::TorqueFrame::World);
  EXPECT_EQ(d.value, ap::Vector3(1e-4, 0, -2e-4));
  EXPECT_EQ(std::get<ap::DisturbanceTorqueSpec>(s.effects[2]).frame, ap::TorqueFrame::Body);
  EXPECT_EQ(std::get<ap::ActuatorLimitsSpec>(s.effects[3]).max_torque, ap::Vector3(0.5, 0.5, 0.25));
  const auto& n = std::get<ap::TorqueNoiseSpec>(s.effects[4]);
  EXPECT_EQ(n.std, ap::Vector3(1e-3, 1e-3, 0));
  EXPECT_EQ(n.seed, 42u);
  // gravity gradient and disturbances are planned; limits and noise act on the commanded torque
  ASSERT_TRUE(s.problem.effects);
  EXPECT_EQ(
      s.problem.effects->names(),
      (std::vector<std::string>{"gravity_gradient", "disturbance_torque", "disturbance_torque"}));
  EXPECT_FALSE(ap::actuationOf(s.effects).empty());
  // actuator limits bound the plan
  EXPECT_EQ(s.problem.max_torque, ap::Vector3(0.5, 0.5, 0.25));
  // ... together with the effect torques (the interior point plans both)
  EXPECT_NO_THROW(ap::validateProblem(s.problem));
  // no effects: no model at all (the bare integrator)
  EXPECT_FALSE(ap::parseScene(withLine("effects", "effects: []"), "none.yaml").problem.effects);
}

TEST(SceneOptionalKeys, DriftTwoInputSystemIsStoredAndRefusedByThePlanner) {
  const std::string text =
      "system: drift_two_input\ncontrol_weights: [1.0, 2.5]\nduration: 3.0\nsteps: 64\n"
      "initial: {attitude: {axis: [0, 0, 1], angle: 0}}\n"
      "final: {attitude: {quaternion: [1, 0, 0, 0]}}\neffects: []\n";
  const ap::Scene s = ap::parseScene(text);
  EXPECT_EQ(s.system, ap::SystemKind::DriftTwoInput);
  EXPECT_EQ(s.control_weights, Eigen::Vector2d(1.0, 2.5));
  try {
    ap::requirePlannable(s);
    ADD_FAILURE() << "drift_two_input must be refused";
  } catch (const ap::InvalidInput& e) {
    EXPECT_CONTAINS(e.what(), "drift_two_input");
  }
  EXPECT_CONTAINS(errorOf(text + "bogus: 1\n"), "bogus");
  EXPECT_CONTAINS(errorOf(withLine("effects", "effects: []\ncontrol_weights: [1, 1]")),
                  "control_weights: unknown key");
  EXPECT_CONTAINS(
      errorOf("system: drift_two_input\ncontrol_weights: [1.0, -2]\nduration: 3.0\nsteps: 64\n"
              "initial: {attitude: {axis: [0, 0, 1], angle: 0}}\n"
              "final: {attitude: {axis: [0, 0, 1], angle: 0}}\neffects: []\n"),
      "control_weights[1]: must be > 0, got '-2'");
  EXPECT_CONTAINS(errorOf(withLine("effects", "effects: []\nsystem: unicycle")),
                  "system: unknown value 'unicycle'");
}

TEST(SceneOptionalKeys, DriftTwoInputSceneGivesThePlannerRequest) {
  const std::string text =
      "system: drift_two_input\ncontrol_weights: [1.5, 2.5]\nduration: 3.0\nsteps: 64\n"
      "initial: {attitude: {axis: [0, 0, 1], angle: 0.5}}\n"
      "final: {attitude: {axis: [1, 1, 0], angle: 1.2}}\n"
      "initial_costate: [-1.5, -0.5, 2]\n";  // effects: optional for this system
  const ap::Scene s = ap::parseScene(text);
  ASSERT_TRUE(s.initial_costate.has_value());
  EXPECT_EQ(*s.initial_costate, ap::Vector3(-1.5, -0.5, 2));
  const ap::DriftTwoInputRequest r = ap::driftTwoInputRequest(s);
  EXPECT_EQ(r.weights.c1, 1.5);
  EXPECT_EQ(r.weights.c2, 2.5);
  EXPECT_EQ(r.duration, 3.0);
  EXPECT_EQ(r.steps, 64);
  EXPECT_EQ(r.initial_costate, s.initial_costate);
  EXPECT_LT(ap::so3::angleBetween(r.g0, ap::so3::fromAxisAngle(ap::Vector3::UnitZ(), 0.5)), 1e-15);
  EXPECT_LT(ap::so3::angleBetween(r.g1, ap::so3::fromAxisAngle(ap::Vector3(1, 1, 0), 1.2)), 1e-15);
  // formatScene keeps the guess and writes no angular velocities for this system.
  const std::string formatted = ap::formatScene(s);
  EXPECT_EQ(formatted.find("angular_velocity"), std::string::npos) << formatted;
  EXPECT_EQ(ap::parseScene(formatted).initial_costate, s.initial_costate);
  // A rigid-body scene is not a drift request.
  EXPECT_THROW(ap::driftTwoInputRequest(ap::parseScene(kValid)), ap::InvalidInput);

  const ap::Scene with_effects = ap::parseScene(
      text + "effects: [{disturbance_torque: {frame: body, value: [1, 0, 0]}}]\n", "fx.yaml");
  try {
    ap::driftTwoInputRequest(with_effects);
    ADD_FAILURE() << "effects must be refused for drift_two_input";
  } catch (const ap::InvalidInput& e) {
    EXPECT_CONTAINS(e.what(), "fx.yaml: effects: not modelled for system: drift_two_input");
  }
}

TEST(SceneErrors, DriftTwoInputRefusesBoundaryVelocitiesAndBadGuesses) {
  const std::string head =
      "system: drift_two_input\ncontrol_weights: [1, 2]\nduration: 3.0\nsteps: 64\n"
      "final: {attitude: {axis: [1, 1, 0], angle: 1.2}}\n";
  EXPECT_CONTAINS(
      errorOf(head +
              "initial: {attitude: {axis: [0, 0, 1], angle: 0}, angular_velocity: [0, 0, 1]}\n"),
      "bad.yaml:6: initial.angular_velocity: not allowed with system: drift_two_input");
  const std::string initial = "initial: {attitude: {axis: [0, 0, 1], angle: 0}}\n";
  EXPECT_CONTAINS(errorOf(head + initial + "initial_costate: [1, 2]\n"),
                  "initial_costate: expected 3 entries, got 2: [1, 2]");
  EXPECT_CONTAINS(errorOf(head + initial + "initial_costate: [1, x, 0]\n"),
                  "initial_costate[1]: expected a number, got 'x'");
  EXPECT_CONTAINS(errorOf(head + initial + "initial_costate: [1, .inf, 0]\n"),
                  "initial_costate[1]: not finite");
  // Only the drift system has a costate.
  EXPECT_CONTAINS(errorOf(withLine("effects", "effects: []\ninitial_costate: [0, 0, 0]")),
                  "initial_costate: unknown key");
}

TEST(SceneErrors, MalformedYamlNamesTheLine) {
  const std::string e = errorOf(withLine("steps", "steps: [1, 2"));
  EXPECT_CONTAINS(e, "bad.yaml:");
  EXPECT_CONTAINS(e, "malformed YAML");
  // The unclosed bracket is noticed at line 4 or later (the line after it opened).
  const int line = std::stoi(e.substr(e.find(':') + 1));
  EXPECT_GE(line, 3);
}

TEST(SceneErrors, UnknownKeyAnywhereIsNamedWithItsPath) {
  EXPECT_CONTAINS(errorOf(kValid + "durration: 3\n"), "bad.yaml:8: durration: unknown key");
  EXPECT_CONTAINS(errorOf(withLine("initial",
                                   "initial: {attitude: {axis: [1, 0, 0], angle: 0.0}, "
                                   "angular_velocity: [0, 0, 0], spin: 1}")),
                  "initial.spin: unknown key");
  EXPECT_CONTAINS(errorOf(withLine("final",
                                   "final: {attitude: {axis: [1, 0, 0], angel: 1.0}, "
                                   "angular_velocity: [0, 0, 0]}")),
                  "final.attitude.angel: unknown key");
  EXPECT_CONTAINS(errorOf(withLine("effects",
                                   "effects: [{gravity_gradient: {mu: 1, "
                                   "orbit_radius: 2, J2: 3}}]")),
                  "effects[0].gravity_gradient.J2: unknown key");
  EXPECT_CONTAINS(errorOf(withLine("effects", "effects: [{solar_pressure: {}}]")),
                  "effects[0].solar_pressure: unknown effect");
}

TEST(SceneErrors, DuplicateKeyIsAnError) {
  EXPECT_CONTAINS(errorOf(kValid + "steps: 64\n"), "steps: duplicate key");
}

TEST(SceneErrors, MissingFieldIsNamed) {
  EXPECT_CONTAINS(errorOf(withLine("duration", "")), "duration: missing");
  EXPECT_CONTAINS(errorOf(withLine("initial", "initial: {attitude: {axis: [1, 0, 0], angle: 0}}")),
                  "initial.angular_velocity: missing");
  EXPECT_CONTAINS(errorOf(withLine("final",
                                   "final: {attitude: {axis: [1, 0, 0]}, "
                                   "angular_velocity: [0, 0, 0]}")),
                  "final.attitude.angle: missing");
  EXPECT_CONTAINS(errorOf(withLine("effects", "effects: [{disturbance_torque: {frame: body}}]")),
                  "effects[0].disturbance_torque.value: missing");
}

TEST(SceneErrors, WrongTypeNamesKeyAndValue) {
  EXPECT_CONTAINS(errorOf(withLine("duration", "duration: fast")),
                  "duration: expected a number, got 'fast'");
  EXPECT_CONTAINS(errorOf(withLine("duration", "duration: \"12.8\"")),
                  "duration: expected a number, got '12.8'");
  EXPECT_CONTAINS(errorOf(withLine("steps", "steps: 12.5")),
                  "steps: expected an integer, got '12.5'");
  EXPECT_CONTAINS(errorOf(withLine("steps", "steps: 99999999999")), "steps: out of range");
  EXPECT_CONTAINS(errorOf(withLine("initial",
                                   "initial: {attitude: {axis: [1, 0], angle: 0}, "
                                   "angular_velocity: [0, 0, 0]}")),
                  "initial.attitude.axis: expected 3 entries, got 2: [1, 0]");
  EXPECT_CONTAINS(errorOf(withLine("initial",
                                   "initial: {attitude: {axis: [1, 0, 0], angle: 0}, "
                                   "angular_velocity: 5}")),
                  "initial.angular_velocity: expected a list of 3 numbers, got '5'");
  EXPECT_CONTAINS(errorOf(withLine("effects", "effects: {}")), "effects: expected a list");
  EXPECT_CONTAINS(errorOf(withLine("inertia", "inertia: [[1, 0, 0], 2, [0, 0, 3]]")),
                  "inertia[1]: expected a row of 3 numbers");
  EXPECT_CONTAINS(errorOf("- 1\n- 2\n"), "scene: expected a mapping");
  EXPECT_CONTAINS(
      errorOf(withLine("effects", "effects: [{torque_noise: {std: [1, 1, 1], seed: -3}}]")),
      "effects[0].torque_noise.seed: expected a non-negative integer, got '-3'");
  EXPECT_CONTAINS(errorOf(withLine("effects",
                                   "effects: [{disturbance_torque: {frame: orbit, value: [0, 0, "
                                   "0]}}]")),
                  "effects[0].disturbance_torque.frame: unknown value 'orbit'");
  EXPECT_CONTAINS(errorOf(withLine("effects", "effects: []\nscheme: rk4")),
                  "scheme: unknown value 'rk4'");
}

TEST(SceneErrors, NanAndInfAreRejected) {
  EXPECT_CONTAINS(errorOf(withLine("duration", "duration: .nan")), "duration: not finite: '.nan'");
  EXPECT_CONTAINS(errorOf(withLine("final",
                                   "final: {attitude: {axis: [1, 0, 0], angle: -.inf}, "
                                   "angular_velocity: [0, 0, 0]}")),
                  "final.attitude.angle: not finite: '-.inf'");
  EXPECT_CONTAINS(errorOf(withLine("initial",
                                   "initial: {attitude: {axis: [1, 0, 0], angle: 0}, "
                                   "angular_velocity: [0, nan, 0]}")),
                  "initial.angular_velocity[1]: not finite: 'nan'");
  EXPECT_CONTAINS(errorOf(withLine("inertia", "inertia: [1, 1e999, 1]")),
                  "inertia[1]: out of the range of a double: '1e999'");
  EXPECT_CONTAINS(errorOf(withLine("effects",
                                   "effects: [{actuator_limits: {max_torque: [1, "
                                   ".inf, 1]}}]")),
                  "effects[0].actuator_limits.max_torque[1]: not finite: '.inf'");
}

TEST(SceneErrors, NonPhysicalInertiaIsNamedWithItsValue) {
  EXPECT_CONTAINS(errorOf(withLine("inertia", "inertia: [[1, 0.5, 0], [0, 1, 0], [0, 0, 1]]")),
                  "inertia: not symmetric: [1, 0.5, 0; 0, 1, 0; 0, 0, 1]");
  EXPECT_CONTAINS(errorOf(withLine("inertia", "inertia: [1, -2, 3]")),
                  "inertia: not positive definite: [1, 0, 0; 0, -2, 0; 0, 0, 3]");
  // An SPD "inertia" no body has (J1 + J2 < J3) is refused unless the scene opts out.
  const std::string flat = strict(withLine("inertia", "inertia: [1, 1, 3]"));
  EXPECT_CONTAINS(errorOf(flat), "violate the triangle inequality");
  EXPECT_CONTAINS(errorOf(flat), "[1, 0, 0; 0, 1, 0; 0, 0, 3]");
  EXPECT_CONTAINS(errorOf(withLine("inertia", "inertia: [1e-13, 1, 1]")),
                  "inertia: condition number 1");
  EXPECT_CONTAINS(errorOf(withLine("inertia", "inertia: [1e-13, 1, 1]")), "> 1e12");
  // The line of the key is part of the message.
  EXPECT_CONTAINS(errorOf(withLine("inertia", "inertia: [1, -2, 3]")), "bad.yaml:1: inertia");
}

TEST(SceneErrors, SeedInertiaViolatesTriangleInequalityUnlessAllowed) {
  const std::string e = errorOf(strict(kValid));
  EXPECT_CONTAINS(e,
                  "bad.yaml:1: inertia: [13.25, -7.8, -11.4; -7.8, 16.25, 4.71; -11.4, 4.71, "
                  "18.37] has principal moments [3.14");
  EXPECT_CONTAINS(e, "violate the triangle inequality");
  EXPECT_CONTAINS(errorOf(withLine("allow_nonphysical_inertia", "allow_nonphysical_inertia: yes")),
                  "allow_nonphysical_inertia: expected true or false, got 'yes'");
  // The planner itself only needs SPD: the seed's problem passes validateProblem.
  EXPECT_NO_THROW(ap::validateProblem(ap::parseScene(kValid).problem));
}

TEST(SceneErrors, DurationAndStepsOutOfRange) {
  EXPECT_CONTAINS(errorOf(withLine("duration", "duration: 0")), "duration: must be");
  EXPECT_CONTAINS(errorOf(withLine("duration", "duration: -1.5")), "got -1.5");
  EXPECT_CONTAINS(errorOf(withLine("steps", "steps: 3")), "steps: must be >= 4, got 3");
  EXPECT_CONTAINS(errorOf(withLine("steps", "steps: 2000001")),
                  "steps: must be <= 2000000, got 2000001");
}

TEST(SceneErrors, BadQuaternionIsNamed) {
  const auto finalQ = [](const std::string& q) {
    return withLine("final",
                    "final: {attitude: {quaternion: " + q + "}, angular_velocity: [0, 0, 0]}");
  };
  EXPECT_CONTAINS(errorOf(finalQ("[0, 0, 0, 0]")),
                  "final.attitude.quaternion: zero quaternion [0, 0, 0, 0]");
  EXPECT_CONTAINS(errorOf(finalQ("[1, 1, 0, 0]")),
                  "final.attitude.quaternion: not a unit quaternion: [1, 1, 0, 0] has norm "
                  "1.4142135623730951");
  EXPECT_CONTAINS(errorOf(finalQ("[1, 0, 0]")), "final.attitude.quaternion: expected 4 entries");
  EXPECT_CONTAINS(errorOf(finalQ("[1, 0, 0, 0], axis: [1, 0, 0]")),
                  "final.attitude.axis: unknown key");
  EXPECT_CONTAINS(errorOf(withLine("final",
                                   "final: {attitude: {axis: [0, 0, 0], angle: 1}, "
                                   "angular_velocity: [0, 0, 0]}")),
                  "final.attitude.axis: zero vector [0, 0, 0]");
}

TEST(SceneRoundTrip, AxisAngleAndQuaternionFormsGiveTheSameProblem) {
  const ap::Scene axis_angle = ap::loadScene(kSceneDir + "slew_up.yaml");
  const std::string text = ap::formatScene(axis_angle);
  EXPECT_NE(text.find("quaternion"), std::string::npos);
  const ap::Scene back = ap::parseScene(text, "round_trip.yaml");
  const ap::PlanningProblem& a = axis_angle.problem;
  const ap::PlanningProblem& b = back.problem;
  EXPECT_EQ(a.inertia, b.inertia);
  EXPECT_EQ(a.duration, b.duration);
  EXPECT_EQ(a.steps, b.steps);
  EXPECT_EQ(a.scheme, b.scheme);
  EXPECT_EQ(a.initial_velocity, b.initial_velocity);
  EXPECT_EQ(a.final_velocity, b.final_velocity);
  EXPECT_LT((a.initial_attitude - b.initial_attitude).norm(), 1e-15);
  EXPECT_LT((a.final_attitude - b.final_attitude).norm(), 1e-15);
  // And once more: the quaternion form is a fixed point of format ∘ parse.
  EXPECT_EQ(ap::formatScene(back), text);
}

TEST(SceneRoundTrip, EffectsAndDriftSystemSurviveFormatting) {
  const std::string text =
      "system: drift_two_input\ncontrol_weights: [1.0, 2.5]\nduration: 3.0\nsteps: 64\n"
      "initial: {attitude: {axis: [0, 0, 1], angle: 0.25}}\n"
      "final: {attitude: {quaternion: [0.5, 0.5, -0.5, 0.5]}}\n"
      "effects: [{torque_noise: {std: [0.1, 0.2, 0.3], seed: 18446744073709551615}}, "
      "{disturbance_torque: {frame: world, value: [1, 2, 3]}}]\n";
  const ap::Scene s = ap::parseScene(text);
  const ap::Scene back = ap::parseScene(ap::formatScene(s));
  EXPECT_EQ(back.system, ap::SystemKind::DriftTwoInput);
  EXPECT_EQ(back.control_weights, s.control_weights);
  ASSERT_EQ(back.effects.size(), 2u);
  EXPECT_EQ(std::get<ap::TorqueNoiseSpec>(back.effects[0]).seed, 18446744073709551615ull);
  EXPECT_EQ(std::get<ap::DisturbanceTorqueSpec>(back.effects[1]).value, ap::Vector3(1, 2, 3));
  EXPECT_LT((back.problem.initial_attitude - s.problem.initial_attitude).norm(), 1e-15);
  EXPECT_LT((back.problem.final_attitude - s.problem.final_attitude).norm(), 1e-15);
}

TEST(SceneFiles, MissingFileIsNamed) {
  try {
    ap::loadScene("/nonexistent/scene.yaml");
    ADD_FAILURE();
  } catch (const ap::InvalidInput& e) {
    EXPECT_CONTAINS(e.what(), "/nonexistent/scene.yaml");
  }
}

TEST(SceneFiles, AbsentEffectsKeyMeansNone) {
  // A scene without `effects:` means no effects (not "effects: missing (required)").
  const ap::Scene absent = ap::parseScene(withLine("effects", ""), "no_effects.yaml");
  EXPECT_TRUE(absent.effects.empty());
  EXPECT_FALSE(absent.problem.effects);
  EXPECT_FALSE(absent.problem.hasTorqueBounds());
  const ap::Scene empty = ap::parseScene(kValid, "empty_effects.yaml");  // `effects: []` stays
  EXPECT_TRUE(empty.effects.empty());
  EXPECT_EQ(ap::formatScene(absent), ap::formatScene(empty));
}

TEST(NameTables, EveryNameRoundTripsAndIsUnique) {
  const auto check = [](const auto& table, auto name, auto parse) {
    std::set<std::string> names;
    for (const auto& row : table) {
      EXPECT_EQ(name(row.value), row.name);
      EXPECT_EQ(parse(row.name, "field"), row.value) << row.name;
      EXPECT_TRUE(names.insert(row.name).second) << "duplicate name " << row.name;
    }
  };
  check(ap::kSchemeNames, ap::schemeName, ap::parseScheme);
  check(ap::kSolverNames, ap::solverName, ap::parseSolver);
  check(ap::kRotationDirectionNames, ap::directionName, ap::parseDirection);
  check(ap::kSystemNames, ap::systemName, ap::parseSystem);
  check(ap::kTorqueFrameNames, ap::torqueFrameName, ap::parseTorqueFrame);
  check(ap::kAccuracyMeasureNames, ap::accuracyMeasureName, ap::parseAccuracyMeasure);
  check(ap::kEffectKindNames, ap::effectKindName, ap::parseEffectKind);
}

TEST(NameTables, UnknownNameIsRefusedNamingFieldValueAndEveryAcceptedName) {
  try {
    ap::parseSolver("magic", "--solver");
    ADD_FAILURE() << "no InvalidInput";
  } catch (const ap::InvalidInput& e) {
    EXPECT_STREQ(e.what(), "--solver: unknown value 'magic' (expected newton or nlopt)");
  }
  EXPECT_CONTAINS(errorOf(withLine("effects", "effects: []\ndirection: sideways")),
                  "direction: unknown value 'sideways' (expected shortest or long_way)");
  EXPECT_CONTAINS(errorOf(withLine("effects", "effects: [{solar_pressure: {}}]")),
                  "unknown effect (expected gravity_gradient, disturbance_torque, "
                  "actuator_limits or torque_noise)");
  ap::PlanningProblem p;
  try {
    ap::applySchemeName("rk4", "scheme", &p);
    ADD_FAILURE() << "no InvalidInput";
  } catch (const ap::InvalidInput& e) {
    EXPECT_STREQ(
        e.what(),
        "scheme: unknown value 'rk4' (expected paper, variational, second_order, fourth_order or "
        "auto)");
  }
  ap::applySchemeName("auto", "scheme", &p);
  EXPECT_TRUE(p.accuracy.choose_scheme);
  EXPECT_THROW(ap::validateProblem(p), ap::InvalidInput);  // auto needs an accuracy target
}

TEST(QuaternionRule, SceneAndMessagesShareOneToleranceAndMessage) {
  const Eigen::Vector4d near_unit(0.7071, 0.7071, 0, 0);  // norm 0.99998: typed, accepted
  EXPECT_LT(ap::so3::angleBetween(ap::attitudeFromQuaternion(near_unit, "q"),
                                  ap::so3::fromAxisAngle(ap::Vector3::UnitX(), M_PI / 2)),
            1e-12);
  try {
    ap::attitudeFromQuaternion(Eigen::Vector4d(2, 0, 0, 0), "initial_attitude");
    ADD_FAILURE() << "no InvalidInput";
  } catch (const ap::InvalidInput& e) {
    EXPECT_CONTAINS(e.what(), "initial_attitude: not a unit quaternion: [2, 0, 0, 0] has norm 2");
  }
  EXPECT_THROW(ap::attitudeFromQuaternion(Eigen::Vector4d::Zero(), "q"), ap::InvalidInput);
  EXPECT_THROW(ap::attitudeFromQuaternion(Eigen::Vector4d(NAN, 0, 0, 1), "q"), ap::InvalidInput);
}
