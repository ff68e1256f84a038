// attitude_planner._core: the Python module's C++ side (pybind11), a thin adapter over the ROS-free
// core. It parses scenes with io/scene (as plan_maneuver does), applies the planning flags with
// io/plan_flags (the CLI's own parser), calls planManeuver / replayPlan with the GIL released and
// hands back plain arrays and the JSON summary of io/report. The Python classes (Problem, Result)
// live in src/attitude_planner/__init__.py; everything here returns builtins and numpy arrays
// (and an opaque parsed Scene that a Problem keeps but pickles as its text), so those classes
// pickle without help from C++.
#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>
#include <pybind11/stl.h>

#include <chrono>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "attitude_planner/dynamics/simulation.hpp"
#include "attitude_planner/errors.hpp"
#include "attitude_planner/io/plan_flags.hpp"
#include "attitude_planner/io/report.hpp"
#include "attitude_planner/io/scene.hpp"
#include "attitude_planner/planner.hpp"
#include "attitude_planner/planning/warm_start.hpp"

namespace py = pybind11;
namespace ap = attitude_planner;

namespace {

/// The Python exception types, created once at import (InputError subclasses ValueError).
PyObject* g_input_error = nullptr;
PyObject* g_step_too_large_error = nullptr;

/// Whether `text` is a location "SOURCE:LINE" (the scene parser's prefix of a message).
bool isLocation(const std::string& text) {
  const std::size_t colon = text.rfind(':');
  return colon != std::string::npos && colon + 1 < text.size() &&
         text.find_first_not_of("0123456789", colon + 1) == std::string::npos;
}

/// Raises `type`(message) with the attributes `field` (the scene key or flag) and `detail` set from
/// the core's FieldError. Where the thrower gave only a message, it is "[SOURCE:LINE: ]field:
/// detail" (errors.hpp, io/scene): the field is the part before the detail.
[[noreturn]] void raiseFieldError(PyObject* type, const ap::FieldError& error) {
  const std::string message = error.what();
  std::string field = error.field();
  std::string detail = error.detail();
  std::size_t start = 0;
  std::size_t colon = message.find(": ");
  if (colon != std::string::npos && isLocation(message.substr(0, colon))) {
    start = colon + 2;
    colon = message.find(": ", start);
  }
  if (field.empty() && colon != std::string::npos) {
    field = message.substr(start, colon - start);
    detail = message.substr(colon + 2);
  }
  py::object instance = py::reinterpret_borrow<py::object>(type)(message);
  instance.attr("field") = field;
  instance.attr("detail") = detail;
  PyErr_SetObject(type, instance.ptr());
  throw py::error_already_set();
}

/// Runs `body`, turning the core's input errors into the module's Python exceptions.
template <class Body>
auto translatingErrors(const Body& body) -> decltype(body()) {
  try {
    return body();
  } catch (const ap::StepTooLarge& e) {
    raiseFieldError(g_step_too_large_error, e);
  } catch (const ap::InvalidInput& e) {
    raiseFieldError(g_input_error, e);
  }
}

/// A rigid-body scene the planner can plan (the CLI's checks: parseScene, requirePlannable).
ap::Scene plannableScene(const std::string& yaml_text, const std::string& source) {
  ap::Scene scene = ap::parseScene(yaml_text, source);
  if (scene.system != ap::SystemKind::RigidBody) {
    throw ap::InvalidInput("system", "the Python module plans rigid_body scenes; '" +
                                         ap::systemName(scene.system) +
                                         "' is planned by plan_maneuver");
  }
  ap::requirePlannable(scene);
  return scene;
}

/// A plan's problem and result, kept for the JSON summary (io/report's planResultJson).
struct HeldSummary {
  ap::PlanningProblem problem;
  ap::PlanResult result;
  std::string json() const { return ap::planResultJson(problem, result); }
};

/// rows × columns array of doubles filled by fill(row, column).
template <class Fill>
py::array_t<double> matrixOf(std::size_t rows, std::size_t columns, const Fill& fill) {
  py::array_t<double> out({rows, columns});
  auto view = out.mutable_unchecked<2>();
  for (std::size_t r = 0; r < rows; ++r) {
    for (std::size_t c = 0; c < columns; ++c) view(r, c) = fill(r, c);
  }
  return out;
}

/// The maneuver as arrays: t (N+1), quaternions (N+1)×4 (w, x, y, z, as the CSV writes them),
/// rotations (N+1)×3×3, rates and torques (N+1)×3, time_step.
py::dict maneuverArrays(const ap::Maneuver& m) {
  const std::size_t rows = m.attitude.size();
  std::vector<Eigen::Quaterniond> q(rows);
  for (std::size_t k = 0; k < rows; ++k) q[k] = ap::so3::toQuaternion(m.attitude[k]);
  py::array_t<double> rotations({rows, std::size_t{3}, std::size_t{3}});
  auto r = rotations.mutable_unchecked<3>();
  for (std::size_t k = 0; k < rows; ++k) {
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) r(k, i, j) = m.attitude[k](i, j);
    }
  }
  py::dict out;
  out["t"] = py::array_t<double>(m.time.size(), m.time.data());
  out["quaternions"] = matrixOf(rows, 4, [&](std::size_t k, std::size_t c) {
    return c == 0 ? q[k].w() : q[k].vec()(static_cast<int>(c) - 1);
  });
  out["rotations"] = rotations;
  out["rates"] = matrixOf(rows, 3, [&](std::size_t k, std::size_t c) {
    return m.angular_velocity[k](static_cast<int>(c));
  });
  out["torques"] = matrixOf(
      rows, 3, [&](std::size_t k, std::size_t c) { return m.torque[k](static_cast<int>(c)); });
  out["time_step"] = m.time_step;
  return out;
}

/// rows × 3 vectors of a (rows, 3) array (checked by the caller's numpy conversion).
std::vector<ap::Vector3> vectorsOf(
    const py::array_t<double, py::array::c_style | py::array::forcecast>& a,
    const std::string& field) {
  if (a.ndim() != 2 || a.shape(1) != 3) {
    throw ap::InvalidInput(
        field, "expected an array of shape (N+1, 3), got ndim " + std::to_string(a.ndim()));
  }
  auto v = a.unchecked<2>();
  std::vector<ap::Vector3> out(static_cast<std::size_t>(a.shape(0)));
  for (std::size_t k = 0; k < out.size(); ++k) out[k] = ap::Vector3(v(k, 0), v(k, 1), v(k, 2));
  return out;
}

/// A warm start from a Result's arrays (t, rotations, rates, torques), checked as the CLI checks
/// --warm-start (validateInitialGuess).
ap::Maneuver guessOf(const py::dict& warm) {
  using Array = py::array_t<double, py::array::c_style | py::array::forcecast>;
  ap::Maneuver guess;
  const Array t = warm["t"].cast<Array>();
  const Array rotations = warm["rotations"].cast<Array>();
  if (rotations.ndim() != 3 || rotations.shape(1) != 3 || rotations.shape(2) != 3 ||
      rotations.shape(0) != t.size()) {
    throw ap::InvalidInput("warm_start", "rotations must have shape (len(t), 3, 3)");
  }
  auto r = rotations.unchecked<3>();
  for (py::ssize_t k = 0; k < rotations.shape(0); ++k) {
    ap::Matrix3 R;
    for (int i = 0; i < 3; ++i) {
      for (int j = 0; j < 3; ++j) R(i, j) = r(k, i, j);
    }
    guess.attitude.push_back(R);
    guess.time.push_back(t.at(k));
  }
  guess.angular_velocity = vectorsOf(warm["rates"].cast<Array>(), "warm_start.rates");
  guess.torque = vectorsOf(warm["torques"].cast<Array>(), "warm_start.torques");
  guess.time_step = warm["time_step"].cast<double>();
  ap::validateInitialGuess(guess, "warm_start");
  return guess;
}

/// plan(): the parsed scene, the flags ("--steps" → "64", as plan_maneuver takes them) and an
/// optional warm start → dict of arrays, termination, message, the figures a table needs, summary
/// (a HeldSummary: the JSON written on request), plan_call_s.
py::dict plan(const ap::Scene& parsed,
              const std::vector<std::pair<std::string, std::string>>& flags,
              const py::object& warm) {
  return translatingErrors([&] {
    ap::Scene scene = parsed;  // the flags change this call's copy only
    ap::PlanFlags parsed;
    for (const auto& [flag, value] : flags) ap::applyPlanFlag(flag, value, &parsed);
    ap::checkPlanFlagCombination(parsed);
    ap::SolverOptions options;
    ap::applyPlanFlags(parsed, &scene.problem, &options);
    ap::Maneuver guess;
    if (!warm.is_none()) {
      guess = guessOf(warm.cast<py::dict>());
      options.warm_start = &guess;
    }
    ap::PlanResult result;
    double call_s = 0.0;  // planManeuver's own wall time, for the overhead benchmark
    {
      py::gil_scoped_release released;  // other Python threads run during the solve
      const auto start = std::chrono::steady_clock::now();
      result = ap::planManeuver(scene.problem, options);
      call_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    }
    py::dict out = maneuverArrays(result.maneuver);
    out["plan_call_s"] = call_s;
    out["cost"] = result.cost;
    out["duration"] = result.duration;
    out["minimum_duration"] = result.minimum_duration;
    out["solve_time_s"] = result.solve_time_s;
    out["termination"] = ap::terminationName(result.termination);
    out["message"] = result.message();
    // The JSON summary is written when Python first asks for it (Result.summary): it costs as
    // much as the rest of the call's overhead together, and a batch row needs three numbers.
    out["summary"] = std::make_shared<HeldSummary>(HeldSummary{scene.problem, std::move(result)});
    return out;
  });
}

/// simulate(): replays torques (N+1)×3 from the scene's initial state with its effects (as
/// simulate_torques does) → dict of arrays, max_step_residual, max_step_iterations.
py::dict simulate(const ap::Scene& scene,
                  const py::array_t<double, py::array::c_style | py::array::forcecast>& torques,
                  double time_step, const std::string& scheme) {
  return translatingErrors([&] {
    const ap::PlanningProblem& p = scene.problem;
    const ap::SchemeKind kind = scheme.empty() ? p.scheme : ap::parseScheme(scheme, "scheme");
    if (!(time_step > 0.0) || !std::isfinite(time_step)) {
      throw ap::InvalidInput("time_step",
                             "must be a finite number > 0 s, got " + ap::exactNumber(time_step));
    }
    ap::SimulationInput input;
    input.initial_attitude = p.initial_attitude;
    input.initial_velocity = p.initial_velocity;
    input.torque = vectorsOf(torques, "torques");
    if (input.torque.size() < 2)
      throw ap::InvalidInput("torques", "needs at least 2 rows (N >= 1)");
    const auto effects = ap::plannableEffects(scene.effects, p.inertia);
    ap::Actuation actuation = ap::actuationOf(scene.effects);
    input.effects = effects.get();
    input.actuation = &actuation;
    ap::SimulationReport report;
    ap::Maneuver replay;
    {
      py::gil_scoped_release released;
      replay = ap::replayPlan(kind, p.inertia, time_step, input, &report);
    }
    py::dict out = maneuverArrays(replay);
    out["max_step_residual"] = report.max_step_residual;
    out["max_step_iterations"] = report.max_step_iterations;
    return out;
  });
}

}  // namespace

PYBIND11_MODULE(_core, m) {
  m.doc() = "C++ side of attitude_planner (use the attitude_planner package, not this module).";
  // Created here so that the C++ side can raise them; __init__.py re-exports them with docs.
  g_input_error = PyErr_NewException("attitude_planner.InputError", PyExc_ValueError, nullptr);
  g_step_too_large_error =
      PyErr_NewException("attitude_planner.StepTooLargeError", g_input_error, nullptr);
  m.add_object("InputError", py::handle(g_input_error));
  m.add_object("StepTooLargeError", py::handle(g_step_too_large_error));
  // A parsed scene, held by a Problem so that each plan() call does not parse its text again
  // (a Problem pickles as its text and parses it again when unpickled).
  py::class_<ap::Scene, std::shared_ptr<ap::Scene>>(m, "Scene", "A parsed, checked scene.");
  m.def(
      "parse_scene",
      [](const std::string& yaml_text, const std::string& source) {
        return translatingErrors(
            [&] { return std::make_shared<ap::Scene>(plannableScene(yaml_text, source)); });
      },
      py::arg("yaml_text"), py::arg("source"), "Parses and checks a scene; raises InputError.");
  py::class_<HeldSummary, std::shared_ptr<HeldSummary>>(m, "HeldSummary",
                                                        "A plan's summary, written on request.")
      .def("json", &HeldSummary::json, "The JSON summary of plan_maneuver --summary.");
  m.def("plan", &plan, py::arg("scene"), py::arg("flags"), py::arg("warm_start"),
        "Plans a scene (see attitude_planner.plan).");
  m.def("simulate", &simulate, py::arg("scene"), py::arg("torques"), py::arg("time_step"),
        py::arg("scheme"), "Replays torques (see attitude_planner.simulate).");
}
