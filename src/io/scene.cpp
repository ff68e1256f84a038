// Scene parser: YAML → Scene, strict. Every error names the source, the line, the key path
// (`final.attitude.quaternion`, `effects[1].torque_noise.std[2]`) and the offending value,
// because a scene is typed by hand and a silently ignored key is a wrong maneuver.
#include "attitude_planner/io/scene.hpp"

#include <yaml-cpp/yaml.h>

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <limits>
#include <optional>
#include <set>
#include <sstream>
#include <type_traits>

#include "attitude_planner/errors.hpp"

namespace attitude_planner {

namespace {

/// A node's text for a message, one line.
std::string show(const YAML::Node& node) {
  if (!node.IsDefined() || node.IsNull()) return "null";
  if (node.IsScalar()) return "'" + node.Scalar() + "'";
  YAML::Emitter out;
  out.SetMapFormat(YAML::Flow);
  out.SetSeqFormat(YAML::Flow);
  out << node;
  return out.c_str();
}

/// The value checks of one effect (shared by scene files and service requests).
void validateEffect(const EffectSpec& effect, const std::string& path) {
  auto require = [&](bool ok, const std::string& key, double value, const char* rule) {
    if (!ok)
      throw InvalidInput(path + "." + key, std::string(rule) + ", got " + exactNumber(value));
  };
  auto requireVector = [&](const Vector3& v, const std::string& key, bool positive) {
    for (int k = 0; k < 3; ++k) {
      const std::string element = key + "[" + std::to_string(k) + "]";
      require(std::isfinite(v(k)), element, v(k), "must be finite");
      if (positive) require(v(k) > 0.0, element, v(k), "must be > 0 N m");
      if (!positive) require(v(k) >= 0.0, element, v(k), "must be >= 0 N m");
    }
  };
  if (const auto* g = std::get_if<GravityGradientSpec>(&effect)) {
    require(std::isfinite(g->mu) && g->mu > 0.0, "mu", g->mu, "must be finite and > 0 m^3/s^2");
    require(std::isfinite(g->orbit_radius) && g->orbit_radius > 0.0, "orbit_radius",
            g->orbit_radius, "must be finite and > 0 m");
  } else if (const auto* d = std::get_if<DisturbanceTorqueSpec>(&effect)) {
    for (int k = 0; k < 3; ++k) {
      require(std::isfinite(d->value(k)), "value[" + std::to_string(k) + "]", d->value(k),
              "must be finite");
    }
  } else if (const auto* a = std::get_if<ActuatorLimitsSpec>(&effect)) {
    requireVector(a->max_torque, "max_torque", true);
  } else if (const auto* n = std::get_if<TorqueNoiseSpec>(&effect)) {
    requireVector(n->std, "std", false);
  }
}

class SceneParser {
 public:
  explicit SceneParser(std::string source) : source_(std::move(source)) {}

  Scene parse(const std::string& text) {
    YAML::Node loaded;
    try {
      loaded = YAML::Load(text);
    } catch (const YAML::ParserException& e) {
      throw InvalidInput(source_ + ":" + std::to_string(e.mark.line + 1) + ":" +
                         std::to_string(e.mark.column + 1) + ": malformed YAML: " + e.msg);
    }
    // const: operator[] on a non-const node would insert the keys it looks up
    const YAML::Node root = loaded;
    if (!root.IsDefined() || root.IsNull()) throw InvalidInput(source_ + ": empty scene");
    requireMap(root, "scene");
    Scene scene;
    scene.source = source_;

    // The system decides which keys are required: the kinematic drift system of seed 001 has no
    // inertia and no boundary velocities.
    if (root["system"]) scene.system = named(root["system"], "system", kSystemNames);
    const bool rigid = scene.system == SystemKind::RigidBody;
    // `effects` is optional: a scene without the key simulates none, like `effects: []`.
    if (rigid) {
      // With objective minimum_time the duration is optional (an upper bound and first guess).
      if (root["objective"]) {
        scene.problem.objective = named(root["objective"], "objective", kObjectiveNames);
      }
      const bool timed = scene.problem.objective == Objective::MinimumTime;
      checkKeys(root, "",
                {"inertia", "duration", "steps", "initial", "final", "effects", "scheme", "system",
                 "allow_nonphysical_inertia", "direction", "extra_revolutions", "constraints",
                 "objective", "time_margin", "actuators"},
                timed
                    ? std::vector<std::string>{"inertia", "steps", "initial", "final"}
                    : std::vector<std::string>{"inertia", "duration", "steps", "initial", "final"});
    } else {
      checkKeys(root, "",
                {"inertia", "duration", "steps", "initial", "final", "effects", "scheme", "system",
                 "control_weights", "initial_costate", "allow_nonphysical_inertia"},
                {"duration", "steps", "initial", "final", "control_weights"});
    }

    PlanningProblem& p = scene.problem;
    if (root["inertia"]) p.inertia = inertia(root["inertia"], "inertia");
    p.duration = root["duration"] || p.objective != Objective::MinimumTime
                     ? number(root["duration"], "duration")
                     : 0.0;  // minimum_time without a duration: no upper bound given
    if (root["time_margin"]) p.time_margin = number(root["time_margin"], "time_margin");
    p.steps = integer(root["steps"], "steps");
    readState(root["initial"], "initial", rigid, &p.initial_attitude, &p.initial_velocity);
    readState(root["final"], "final", rigid, &p.final_attitude, &p.final_velocity,
              rigid ? &p.end_condition : nullptr);
    if (root["scheme"]) p.scheme = named(root["scheme"], "scheme", kSchemeNames);
    if (root["direction"]) {
      p.direction = named(root["direction"], "direction", kRotationDirectionNames);
    }
    if (root["extra_revolutions"]) {
      p.extra_revolutions = integer(root["extra_revolutions"], "extra_revolutions");
    }
    if (root["control_weights"]) {
      const YAML::Node w = root["control_weights"];
      requireSequence(w, "control_weights", 2);
      for (int i = 0; i < 2; ++i) {
        const std::string path = "control_weights[" + std::to_string(i) + "]";
        scene.control_weights(i) = number(w[i], path);
        if (!(scene.control_weights(i) > 0.0)) fail(w[i], path, "must be > 0, got " + show(w[i]));
      }
    }
    if (root["initial_costate"]) {
      scene.initial_costate = vector3(root["initial_costate"], "initial_costate");
    }
    if (root["effects"]) scene.effects = effects(root["effects"], "effects");
    if (root["constraints"]) p.constraints = constraints(root["constraints"], "constraints");
    if (root["actuators"]) p.reaction_wheels = actuators(root["actuators"], "actuators");
    if (root["allow_nonphysical_inertia"]) {
      scene.allow_nonphysical_inertia =
          boolean(root["allow_nonphysical_inertia"], "allow_nonphysical_inertia");
    }
    p.allow_nonphysical_inertia = scene.allow_nonphysical_inertia;

    // Physical checks (SPD inertia, T > 0, N range, ...) live in validateProblem, shared with the
    // planner node; here they gain the file name and the line of the key they name.
    validateAt(root, p);
    applyEffects(scene.effects, &p);
    // The wheels' combinations with effects (actuator_limits) are known only now.
    if (p.reaction_wheels.present()) validateAt(root, p);
    return scene;
  }

 private:
  std::string where(const YAML::Node& node) const {
    return source_ + ":" + std::to_string(node.Mark().line + 1) + ": ";
  }

  /// validateProblem, its error placed at the line of the top-level key it names.
  void validateAt(const YAML::Node& root, const PlanningProblem& p) const {
    try {
      validateProblem(p);
    } catch (const InvalidInput& e) {
      const std::string what = e.what();
      const std::string key = what.substr(0, what.find_first_of(".:["));
      const YAML::Node node = root[key];
      if (node) throw InvalidInput(where(node) + what);
      throw InvalidInput(source_ + ": " + what);
    }
  }

  /// A list of numbers (any length) at `path`; a scalar gives one entry if `scalar_allowed`.
  std::vector<double> numbers(const YAML::Node& node, const std::string& path,
                              bool scalar_allowed) const {
    if (scalar_allowed && node.IsScalar()) return {number(node, path)};
    if (!node.IsSequence()) {
      fail(node, path,
           std::string("expected ") + (scalar_allowed ? "a number or " : "") +
               "a list of numbers (one per wheel), got " + show(node));
    }
    std::vector<double> out;
    for (std::size_t i = 0; i < node.size(); ++i)
      out.push_back(number(node[i], path + "[" + std::to_string(i) + "]"));
    return out;
  }

  /// `actuators: {reaction_wheels: {spin_axes, max_torque, max_momentum, initial_momentum,
  /// max_momentum_norm, spin_inertia}}` (the values are checked by validateProblem).
  ReactionWheels actuators(const YAML::Node& node, const std::string& path) const {
    requireMap(node, path);
    checkKeys(node, path, {"reaction_wheels"}, {"reaction_wheels"});
    const std::string wpath = path + ".reaction_wheels";
    const YAML::Node w = node["reaction_wheels"];
    requireMap(w, wpath);
    checkKeys(w, wpath,
              {"spin_axes", "max_torque", "max_momentum", "initial_momentum", "max_momentum_norm",
               "spin_inertia"},
              {"spin_axes", "max_torque", "max_momentum"});
    ReactionWheels out;
    const YAML::Node axes = w["spin_axes"];
    if (!axes.IsSequence()) {
      fail(axes, wpath + ".spin_axes", "expected a list of axes [x, y, z], got " + show(axes));
    }
    for (std::size_t i = 0; i < axes.size(); ++i)
      out.spin_axes.push_back(vector3(axes[i], wpath + ".spin_axes[" + std::to_string(i) + "]"));
    out.max_torque = numbers(w["max_torque"], wpath + ".max_torque", true);
    out.max_momentum = numbers(w["max_momentum"], wpath + ".max_momentum", true);
    if (w["initial_momentum"]) {
      out.initial_momentum = numbers(w["initial_momentum"], wpath + ".initial_momentum", false);
    }
    if (w["max_momentum_norm"]) {
      out.max_momentum_norm = number(w["max_momentum_norm"], wpath + ".max_momentum_norm");
    }
    if (w["spin_inertia"]) {
      out.spin_inertia = numbers(w["spin_inertia"], wpath + ".spin_inertia", true);
    }
    return out;
  }

  [[noreturn]] void fail(const YAML::Node& node, const std::string& path,
                         const std::string& what) const {
    throw InvalidInput(where(node) + path + ": " + what);
  }

  /// The value a scalar names in `table`; an unknown name is an error listing the table's names.
  template <class Enum, std::size_t N>
  Enum named(const YAML::Node& node, const std::string& path,
             const NamedValue<Enum> (&table)[N]) const {
    const std::string text = scalarString(node, path);
    try {
      return parseIn(table, text, path);
    } catch (const InvalidInput& e) {
      throw InvalidInput(where(node) + e.what());
    }
  }

  void requireMap(const YAML::Node& node, const std::string& path) const {
    if (!node.IsMap()) fail(node, path, "expected a mapping, got " + show(node));
  }

  void requireSequence(const YAML::Node& node, const std::string& path, int size) const {
    if (!node.IsSequence()) {
      fail(node, path,
           "expected a list of " + std::to_string(size) + " numbers, got " + show(node));
    }
    if (static_cast<int>(node.size()) != size) {
      fail(node, path,
           "expected " + std::to_string(size) + " entries, got " + std::to_string(node.size()) +
               ": " + show(node));
    }
  }

  /// Unknown, duplicate and missing keys are all errors; `prefix` is the path of `node`.
  void checkKeys(const YAML::Node& node, const std::string& prefix,
                 const std::vector<std::string>& allowed,
                 const std::vector<std::string>& required) const {
    std::set<std::string> seen;
    for (const auto& entry : node) {
      const std::string key = entry.first.IsScalar() ? entry.first.Scalar() : show(entry.first);
      const std::string path = prefix.empty() ? key : prefix + "." + key;
      bool known = false;
      for (const auto& a : allowed) known = known || a == key;
      if (!known) {
        std::string list;
        for (const auto& a : allowed) list += (list.empty() ? "" : ", ") + a;
        fail(entry.first, path, "unknown key (expected one of: " + list + ")");
      }
      if (!seen.insert(key).second) fail(entry.first, path, "duplicate key");
    }
    for (const auto& r : required) {
      if (!seen.count(r)) {
        fail(node, prefix.empty() ? r : prefix + "." + r, "missing (required)");
      }
    }
  }

  std::string scalarString(const YAML::Node& node, const std::string& path) const {
    if (!node.IsScalar()) fail(node, path, "expected a name, got " + show(node));
    return node.Scalar();
  }

  /// A finite number. Quoted strings are not numbers: "12.8" is a typo more often than intent.
  double number(const YAML::Node& node, const std::string& path) const {
    if (!node.IsScalar() || node.Tag() == "!") {
      fail(node, path, "expected a number, got " + show(node));
    }
    const std::string& s = node.Scalar();
    double value = 0.0;
    if (s == ".nan" || s == ".NaN" || s == ".NAN") {
      value = std::numeric_limits<double>::quiet_NaN();
    } else if (s == ".inf" || s == ".Inf" || s == ".INF" || s == "+.inf" || s == "+.Inf" ||
               s == "+.INF") {
      value = std::numeric_limits<double>::infinity();
    } else if (s == "-.inf" || s == "-.Inf" || s == "-.INF") {
      value = -std::numeric_limits<double>::infinity();
    } else {
      char* end = nullptr;
      errno = 0;
      value = std::strtod(s.c_str(), &end);
      if (s.empty() || end != s.c_str() + s.size()) {
        fail(node, path, "expected a number, got " + show(node));
      }
      if (errno == ERANGE && std::abs(value) > 1.0) {
        fail(node, path, "out of the range of a double: " + show(node));
      }
    }
    if (!std::isfinite(value)) fail(node, path, "not finite: " + show(node));
    return value;
  }

  bool boolean(const YAML::Node& node, const std::string& path) const {
    if (node.IsScalar() && node.Tag() != "!") {
      const std::string& s = node.Scalar();
      if (s == "true" || s == "True" || s == "TRUE") return true;
      if (s == "false" || s == "False" || s == "FALSE") return false;
    }
    fail(node, path, "expected true or false, got " + show(node));
  }

  int integer(const YAML::Node& node, const std::string& path) const {
    if (!node.IsScalar() || node.Tag() == "!") {
      fail(node, path, "expected an integer, got " + show(node));
    }
    const std::string& s = node.Scalar();
    char* end = nullptr;
    errno = 0;
    const long long value = std::strtoll(s.c_str(), &end, 10);
    if (s.empty() || end != s.c_str() + s.size()) {
      fail(node, path, "expected an integer, got " + show(node));
    }
    if (errno == ERANGE || value > std::numeric_limits<int>::max() ||
        value < std::numeric_limits<int>::min()) {
      fail(node, path, "out of range: " + show(node));
    }
    return static_cast<int>(value);
  }

  Vector3 vector3(const YAML::Node& node, const std::string& path) const {
    requireSequence(node, path, 3);
    Vector3 v;
    for (int i = 0; i < 3; ++i) v(i) = number(node[i], path + "[" + std::to_string(i) + "]");
    return v;
  }

  /// 3×3 nested list, or the three principal moments [a, b, c] (diagonal inertia).
  Matrix3 inertia(const YAML::Node& node, const std::string& path) const {
    requireSequence(node, path, 3);
    if (node[0].IsScalar()) return vector3(node, path).asDiagonal();
    Matrix3 J;
    for (int i = 0; i < 3; ++i) {
      const std::string row = path + "[" + std::to_string(i) + "]";
      if (!node[i].IsSequence()) {
        fail(node[i], row,
             "expected a row of 3 numbers (inertia is [[...], [...], [...]] or "
             "[a, b, c]), got " +
                 show(node[i]));
      }
      J.row(i) = vector3(node[i], row).transpose();
    }
    return J;
  }

  Matrix3 attitude(const YAML::Node& node, const std::string& path) const {
    requireMap(node, path);
    if (node["quaternion"]) {
      checkKeys(node, path, {"quaternion"}, {"quaternion"});
      const std::string qpath = path + ".quaternion";
      const YAML::Node qn = node["quaternion"];
      requireSequence(qn, qpath, 4);
      Eigen::Vector4d q;
      for (int i = 0; i < 4; ++i) q(i) = number(qn[i], qpath + "[" + std::to_string(i) + "]");
      try {
        return attitudeFromQuaternion(q, qpath, show(qn));
      } catch (const InvalidInput& e) {
        throw InvalidInput(where(qn) + e.what());
      }
    }
    checkKeys(node, path, {"axis", "angle", "quaternion"}, {"axis", "angle"});
    const Vector3 axis = vector3(node["axis"], path + ".axis");
    if (axis.norm() == 0.0) {
      fail(node["axis"], path + ".axis", "zero vector " + show(node["axis"]) + " has no direction");
    }
    const double angle = number(node["angle"], path + ".angle");
    return so3::fromAxisAngle(axis, angle);
  }

  /// `final.pointing: {body_axis: [..], world_direction: [..]}` (nonzero vectors).
  EndCondition pointingCondition(const YAML::Node& node, const std::string& path) const {
    requireMap(node, path);
    checkKeys(node, path, {"body_axis", "world_direction"}, {"body_axis", "world_direction"});
    EndCondition end;
    end.kind = EndConditionKind::Pointing;
    for (const auto& [key, target] : {std::pair<const char*, Vector3*>{"body_axis", &end.body_axis},
                                      {"world_direction", &end.world_direction}}) {
      *target = vector3(node[key], path + "." + key);
      if (target->norm() == 0.0) {
        fail(node[key], path + "." + key, "zero vector " + show(node[key]) + " has no direction");
      }
    }
    return end;
  }

  /// `rigid`: the rigid body's state (attitude and angular velocity, both required); otherwise
  /// the kinematic drift system's, whose only boundary value is the attitude.
  /// With `end` (the rigid body's final state): `pointing` may stand instead of `attitude`.
  void readState(const YAML::Node& node, const std::string& path, bool rigid, Matrix3* attitude_out,
                 Vector3* velocity_out, EndCondition* end = nullptr) const {
    requireMap(node, path);
    if (!rigid && node["angular_velocity"]) {
      // Not ignored: the body rate of ġ = g(E3 + u1 E1 + u2 E2) is (u1, u2, 1), set by the
      // controls; a boundary velocity would be a second, conflicting condition.
      fail(node["angular_velocity"], path + ".angular_velocity",
           "not allowed with system: drift_two_input (a kinematic system: the body rate "
           "(u1, u2, 1) is set by the controls, only the attitude is a boundary condition)");
    }
    const bool pointing = end && node["pointing"];
    std::vector<std::string> required = {pointing ? "pointing" : "attitude"};
    if (rigid) required.push_back("angular_velocity");
    std::vector<std::string> allowed = {"attitude", "angular_velocity"};
    if (end) allowed.push_back("pointing");
    if (end && !node["pointing"] && !node["attitude"]) {
      fail(node, path + ".attitude",
           "missing: give " + path + ".attitude or " + path + ".pointing (one is required)");
    }
    if (pointing && node["attitude"]) {
      fail(node["pointing"], path + ".pointing",
           "give either " + path + ".attitude or " + path + ".pointing, not both");
    }
    checkKeys(node, path, allowed, required);
    if (pointing) {
      *end = pointingCondition(node["pointing"], path + ".pointing");
    } else {
      *attitude_out = attitude(node["attitude"], path + ".attitude");
    }
    if (node["angular_velocity"]) {
      *velocity_out = vector3(node["angular_velocity"], path + ".angular_velocity");
    }
  }

  /// The `constraints:` list: single-key maps, values checked by validateConstraints.
  std::vector<PlanningConstraint> constraints(const YAML::Node& node,
                                              const std::string& path) const {
    if (!node.IsSequence()) {
      fail(node, path, "expected a list (use [] for none), got " + show(node));
    }
    std::vector<PlanningConstraint> out;
    for (std::size_t i = 0; i < node.size(); ++i) {
      const YAML::Node entry = node[i];
      const std::string epath = path + "[" + std::to_string(i) + "]";
      if (!entry.IsMap() || entry.size() != 1) {
        fail(entry, epath,
             "expected one constraint as {name: value}, got " + show(entry) +
                 " (names: max_torque_norm, max_angular_rate, keep_out, keep_in)");
      }
      const auto kv = *entry.begin();
      const std::string name = kv.first.Scalar();
      const YAML::Node body = kv.second;
      const std::string bpath = epath + "." + name;
      if (name == "max_torque_norm") {
        out.push_back(PlanningConstraint::maxTorqueNorm(number(body, bpath)));
      } else if (name == "max_angular_rate") {
        out.push_back(PlanningConstraint::maxAngularRate(number(body, bpath)));
      } else if (name == "keep_out" || name == "keep_in") {
        requireMap(body, bpath);
        checkKeys(body, bpath, {"body_axis", "world_direction", "half_angle", "margin"},
                  {"body_axis", "world_direction", "half_angle"});
        const Vector3 b = vector3(body["body_axis"], bpath + ".body_axis");
        const Vector3 s = vector3(body["world_direction"], bpath + ".world_direction");
        const double a = number(body["half_angle"], bpath + ".half_angle");
        const double m = body["margin"] ? number(body["margin"], bpath + ".margin") : 0.0;
        out.push_back(name == "keep_out" ? PlanningConstraint::keepOut(b, s, a, m)
                                         : PlanningConstraint::keepIn(b, s, a, m));
      } else {
        fail(kv.first, bpath,
             "unknown constraint (expected max_torque_norm, max_angular_rate, keep_out or "
             "keep_in)");
      }
      try {
        validateConstraints({out.back()}, epath.substr(0, epath.rfind('[')));
      } catch (const InvalidInput& e) {
        // Renumber: the single-entry check names index 0.
        std::string what = e.what();
        const std::string wrong = path + "[0]";
        if (what.compare(0, wrong.size(), wrong) == 0) what = epath + what.substr(wrong.size());
        throw InvalidInput(where(body) + what);
      }
    }
    return out;
  }

  std::vector<EffectSpec> effects(const YAML::Node& node, const std::string& path) const {
    if (!node.IsSequence()) {
      fail(node, path, "expected a list (use [] for none), got " + show(node));
    }
    std::vector<EffectSpec> out;
    for (std::size_t i = 0; i < node.size(); ++i) {
      const YAML::Node entry = node[i];
      const std::string epath = path + "[" + std::to_string(i) + "]";
      if (!entry.IsMap() || entry.size() != 1) {
        fail(entry, epath,
             "expected one effect as {name: {...}}, got " + show(entry) +
                 " (names: gravity_gradient, disturbance_torque, actuator_limits, torque_noise)");
      }
      const auto kv = *entry.begin();
      const std::string name = kv.first.Scalar();
      const YAML::Node body = kv.second;
      const std::string bpath = epath + "." + name;
      const std::optional<EffectKind> kind = findByName(kEffectKindNames, name);
      if (!kind) {
        fail(kv.first, bpath, "unknown effect (expected " + oneOf(namesOf(kEffectKindNames)) + ")");
      }
      if (*kind == EffectKind::GravityGradient) {
        requireMap(body, bpath);
        checkKeys(body, bpath, {"mu", "orbit_radius"}, {"mu", "orbit_radius"});
        GravityGradientSpec g;
        g.mu = number(body["mu"], bpath + ".mu");
        g.orbit_radius = number(body["orbit_radius"], bpath + ".orbit_radius");
        out.emplace_back(g);
      } else if (*kind == EffectKind::DisturbanceTorque) {
        requireMap(body, bpath);
        checkKeys(body, bpath, {"frame", "value"}, {"frame", "value"});
        DisturbanceTorqueSpec d;
        d.frame = named(body["frame"], bpath + ".frame", kTorqueFrameNames);
        d.value = vector3(body["value"], bpath + ".value");
        out.emplace_back(d);
      } else if (*kind == EffectKind::ActuatorLimits) {
        requireMap(body, bpath);
        checkKeys(body, bpath, {"max_torque"}, {"max_torque"});
        ActuatorLimitsSpec a;
        a.max_torque = vector3(body["max_torque"], bpath + ".max_torque");
        out.emplace_back(a);
      } else {
        requireMap(body, bpath);
        checkKeys(body, bpath, {"std", "seed"}, {"std", "seed"});
        TorqueNoiseSpec t;
        t.std = vector3(body["std"], bpath + ".std");
        const YAML::Node seed = body["seed"];
        const std::string& s = seed.IsScalar() ? seed.Scalar() : std::string();
        char* end = nullptr;
        errno = 0;
        const unsigned long long v = std::strtoull(s.c_str(), &end, 10);
        if (s.empty() || s[0] == '-' || end != s.c_str() + s.size() || errno == ERANGE ||
            seed.Tag() == "!") {
          fail(seed, bpath + ".seed", "expected a non-negative integer, got " + show(seed));
        }
        t.seed = v;
        out.emplace_back(t);
      }
      try {
        validateEffect(out.back(), bpath);
      } catch (const InvalidInput& e) {
        throw InvalidInput(where(body) + e.what());
      }
    }
    try {
      validateEffects(out, path);  // what spans entries (duplicates)
    } catch (const InvalidInput& e) {
      throw InvalidInput(where(node) + e.what());
    }
    return out;
  }

  std::string source_;
};

std::string vec(const Eigen::VectorXd& v) {
  std::string s = "[";
  for (int i = 0; i < v.size(); ++i) s += (i ? ", " : "") + exactNumber(v(i));
  return s + "]";
}

std::string quaternionOf(const Matrix3& R) {
  const Eigen::Quaterniond q = so3::toQuaternion(R);
  return "{quaternion: " + vec(Eigen::Vector4d(q.w(), q.x(), q.y(), q.z())) + "}";
}

}  // namespace

EffectKind effectKindOf(const EffectSpec& effect) {
  static_assert(
      std::is_same_v<std::variant_alternative_t<0, EffectSpec>, GravityGradientSpec> &&
          std::is_same_v<std::variant_alternative_t<1, EffectSpec>, DisturbanceTorqueSpec> &&
          std::is_same_v<std::variant_alternative_t<2, EffectSpec>, ActuatorLimitsSpec> &&
          std::is_same_v<std::variant_alternative_t<3, EffectSpec>, TorqueNoiseSpec>,
      "EffectSpec's alternatives follow EffectKind");
  constexpr EffectKind kByIndex[] = {EffectKind::GravityGradient, EffectKind::DisturbanceTorque,
                                     EffectKind::ActuatorLimits, EffectKind::TorqueNoise};
  return kByIndex[effect.index()];
}

std::string effectName(const EffectSpec& effect) {
  return effectKindName(effectKindOf(effect));
}

Matrix3 attitudeFromQuaternion(const Eigen::Vector4d& q, const std::string& field,
                               const std::string& shown) {
  const std::string text = shown.empty() ? vec(q) : shown;
  if (!q.allFinite()) throw InvalidInput(field + ": quaternion not finite: " + text);
  const double norm = q.norm();
  if (norm == 0.0) {
    throw InvalidInput(field + ": zero quaternion " + text +
                       " is not a rotation (expected a unit quaternion [w, x, y, z]; identity is "
                       "[1, 0, 0, 0])");
  }
  if (std::abs(norm - 1.0) > kQuaternionNormTolerance) {
    throw InvalidInput(field + ": not a unit quaternion: " + text + " has norm " +
                       exactNumber(norm) + " (must be within " +
                       exactNumber(kQuaternionNormTolerance) + " of 1; [w, x, y, z])");
  }
  return so3::fromQuaternion(Eigen::Quaterniond(q(0), q(1), q(2), q(3)));
}

void validateEffects(const std::vector<EffectSpec>& effects, const std::string& field) {
  std::set<std::string> seen;
  for (std::size_t i = 0; i < effects.size(); ++i) {
    const std::string name = effectName(effects[i]);
    const std::string path = field + "[" + std::to_string(i) + "]." + name;
    validateEffect(effects[i], path);
    // Several constant disturbances add up; the other effects are one-of-a-kind.
    if (effectKindOf(effects[i]) != EffectKind::DisturbanceTorque && !seen.insert(name).second) {
      throw InvalidInput(path, "duplicate effect (at most one " + name + ")");
    }
  }
}

Scene parseScene(const std::string& yaml_text, const std::string& source) {
  return SceneParser(source).parse(yaml_text);
}

Scene loadScene(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InvalidInput("scene: cannot read '" + path + "'");
  std::stringstream text;
  text << in.rdbuf();
  return parseScene(text.str(), path);
}

std::string formatScene(const Scene& scene) {
  const PlanningProblem& p = scene.problem;
  std::ostringstream out;
  out << "# written by formatScene; units: SI (kg m^2, s, rad, rad/s, N m)\n";
  if (scene.system != SystemKind::RigidBody) {
    out << "system: " << systemName(scene.system) << "\n";
    out << "control_weights: " << vec(scene.control_weights) << "\n";
    if (scene.initial_costate) out << "initial_costate: " << vec(*scene.initial_costate) << "\n";
  }
  out << "inertia: [" << vec(p.inertia.row(0).transpose()) << ", "
      << vec(p.inertia.row(1).transpose()) << ", " << vec(p.inertia.row(2).transpose()) << "]\n";
  if (scene.allow_nonphysical_inertia) out << "allow_nonphysical_inertia: true\n";
  if (p.objective != Objective::MinimumTime || p.duration != 0.0) {
    out << "duration: " << exactNumber(p.duration) << "\n";
  }
  if (p.objective != Objective::MinimumEffort) {
    out << "objective: " << objectiveName(p.objective) << "\n";
  }
  if (p.time_margin != 0.0) out << "time_margin: " << exactNumber(p.time_margin) << "\n";
  out << "steps: " << p.steps << "\n";
  out << "scheme: " << schemeName(p.scheme) << "\n";
  if (p.direction != RotationDirection::Shortest) {
    out << "direction: " << directionName(p.direction) << "\n";
  }
  if (p.extra_revolutions != 0) out << "extra_revolutions: " << p.extra_revolutions << "\n";
  const bool rigid = scene.system == SystemKind::RigidBody;
  out << "initial: {attitude: " << quaternionOf(p.initial_attitude);
  if (rigid) out << ", angular_velocity: " << vec(p.initial_velocity);
  out << "}\n";
  if (p.end_condition.pointing()) {
    out << "final: {pointing: {body_axis: " << vec(p.end_condition.body_axis)
        << ", world_direction: " << vec(p.end_condition.world_direction) << "}";
  } else {
    out << "final: {attitude: " << quaternionOf(p.final_attitude);
  }
  if (rigid) out << ", angular_velocity: " << vec(p.final_velocity);
  out << "}\n";
  if (p.reaction_wheels.present()) {
    const ReactionWheels& w = p.reaction_wheels;
    const auto list = [](const std::vector<double>& v) {
      return vec(Eigen::Map<const Eigen::VectorXd>(v.data(), static_cast<int>(v.size())));
    };
    out << "actuators: {reaction_wheels: {spin_axes: [";
    for (int i = 0; i < w.count(); ++i) out << (i ? ", " : "") << vec(w.spin_axes[i]);
    out << "], max_torque: " << list(w.max_torque) << ", max_momentum: " << list(w.max_momentum);
    if (!w.initial_momentum.empty()) out << ", initial_momentum: " << list(w.initial_momentum);
    if (std::isfinite(w.max_momentum_norm)) {
      out << ", max_momentum_norm: " << exactNumber(w.max_momentum_norm);
    }
    if (w.hasSpinInertia()) out << ", spin_inertia: " << list(w.spin_inertia);
    out << "}}\n";
  }
  out << "effects:";
  if (scene.effects.empty()) out << " []";
  out << "\n";
  for (const EffectSpec& e : scene.effects) {
    out << "  - " << effectName(e) << ": ";
    if (const auto* g = std::get_if<GravityGradientSpec>(&e)) {
      out << "{mu: " << exactNumber(g->mu) << ", orbit_radius: " << exactNumber(g->orbit_radius)
          << "}\n";
    } else if (const auto* d = std::get_if<DisturbanceTorqueSpec>(&e)) {
      out << "{frame: " << torqueFrameName(d->frame) << ", value: " << vec(d->value) << "}\n";
    } else if (const auto* a = std::get_if<ActuatorLimitsSpec>(&e)) {
      out << "{max_torque: " << vec(a->max_torque) << "}\n";
    } else if (const auto* t = std::get_if<TorqueNoiseSpec>(&e)) {
      out << "{std: " << vec(t->std) << ", seed: " << t->seed << "}\n";
    }
  }
  if (!p.constraints.empty()) out << "constraints:\n";
  for (const PlanningConstraint& c : p.constraints) {
    out << "  - " << constraintKindName(c.kind) << ": ";
    if (c.isCone()) {
      out << "{body_axis: " << vec(c.body_axis) << ", world_direction: " << vec(c.world_direction)
          << ", half_angle: " << exactNumber(c.half_angle);
      if (c.margin != 0.0) out << ", margin: " << exactNumber(c.margin);
      out << "}\n";
    } else {
      out << exactNumber(c.limit) << "\n";
    }
  }
  return out.str();
}

std::shared_ptr<const EffectModel> plannableEffects(const std::vector<EffectSpec>& specs,
                                                    const Matrix3& inertia) {
  auto model = std::make_shared<EffectModel>();
  for (const EffectSpec& spec : specs) {
    if (const auto* gg = std::get_if<GravityGradientSpec>(&spec)) {
      model->add(std::make_unique<GravityGradient>(gg->mu, gg->orbit_radius, inertia));
    } else if (const auto* d = std::get_if<DisturbanceTorqueSpec>(&spec)) {
      model->add(std::make_unique<DisturbanceTorque>(d->value, d->frame));
    }
    // actuator_limits and torque_noise act on the commanded torque: see actuationOf().
  }
  return model->empty() ? nullptr : model;
}

void applyEffects(const std::vector<EffectSpec>& specs, PlanningProblem* problem) {
  problem->effects = plannableEffects(specs, problem->inertia);
  for (const EffectSpec& e : specs) {
    if (const auto* limits = std::get_if<ActuatorLimitsSpec>(&e))
      problem->max_torque = limits->max_torque;
  }
}

Actuation actuationOf(const std::vector<EffectSpec>& specs) {
  Actuation actuation;
  for (const EffectSpec& spec : specs) {
    if (const auto* limits = std::get_if<ActuatorLimitsSpec>(&spec)) {
      actuation.setLimits(limits->max_torque);
    } else if (const auto* noise = std::get_if<TorqueNoiseSpec>(&spec)) {
      actuation.setNoise(noise->std, noise->seed);
    }
  }
  return actuation;
}

void requirePlannable(const Scene& scene) {
  if (scene.system != SystemKind::RigidBody) {
    throw InvalidInput(scene.source + ": system: '" + systemName(scene.system) +
                       "' is not planned by planManeuver (rigid_body only; drift_two_input "
                       "scenes go to planDriftTwoInput, as plan_maneuver does)");
  }
  // Gravity gradient and disturbances are in the planning model, actuator limits bound the plan's
  // torques (PlanningProblem::max_torque); torque noise is tracker-only by nature.
}

DriftTwoInputRequest driftTwoInputRequest(const Scene& scene) {
  if (scene.system != SystemKind::DriftTwoInput) {
    throw InvalidInput(scene.source + ": system: '" + systemName(scene.system) +
                       "' is not drift_two_input (planManeuver plans rigid_body scenes)");
  }
  if (!scene.effects.empty()) {
    std::string names;
    for (const EffectSpec& e : scene.effects) {
      const std::string n = effectName(e);
      if (names.find(n) == std::string::npos) names += (names.empty() ? "" : ", ") + n;
    }
    throw InvalidInput(scene.source +
                       ": effects: not modelled for system: drift_two_input (a kinematic system "
                       "has no torques), got: " +
                       names);
  }
  DriftTwoInputRequest r;
  const PlanningProblem& p = scene.problem;
  r.g0 = p.initial_attitude;
  r.g1 = p.final_attitude;
  r.duration = p.duration;
  r.steps = p.steps;
  r.weights.c1 = scene.control_weights(0);
  r.weights.c2 = scene.control_weights(1);
  r.initial_costate = scene.initial_costate;
  return r;
}

}  // namespace attitude_planner
