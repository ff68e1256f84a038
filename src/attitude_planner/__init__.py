"""Plan rigid-body attitude maneuvers on SO(3) from Python, without a ROS master.

A thin layer over the package's ROS-free C++ core (the extension ``attitude_planner._core``): the
scene keys, the planning flags and the JSON summary are those of ``plan_maneuver`` (README.md,
docs/DESIGN.md), and a plan is bit for bit the one the command-line tool writes.

    >>> import attitude_planner as ap
    >>> problem = ap.Problem("scenes/rest_to_rest.yaml", steps=64)
    >>> result = ap.plan(problem, objective="minimum_time")
    >>> result.converged, result.minimum_duration

The generated message modules of the package live beside it (``attitude_planner.msg``,
``attitude_planner.srv``), as in any catkin package. Batch planning (slew tables, Monte Carlo
lists) is ``attitude_planner.batch.plan_batch`` and the ``plan_batch`` tool.
"""
import json
import numbers
import os
from pkgutil import extend_path

# Imported through catkin's relay (devel space), __path__ already holds this directory and the
# devel one with _core and msg/srv; imported from here directly (a process that inherited the
# relay's sys.path, such as a spawned worker), it gains the devel one the same way.
__path__ = extend_path(__path__, __name__)

import numpy as np
import yaml

from attitude_planner._core import InputError, StepTooLargeError
from attitude_planner import _core

__all__ = ["Problem", "Result", "Simulation", "plan", "simulate", "InputError",
           "StepTooLargeError"]

InputError.__doc__ = ("Bad input (a scene key, a planning option, a warm start): a ValueError "
                      "whose message names the field and the value; `field` holds the field "
                      "(scene key such as 'initial.attitude.angle', or the option keyword) and "
                      "`detail` the message without it.")
InputError.field = ""
InputError.detail = ""
StepTooLargeError.__doc__ = ("An implicit step of the scheme has no solution at h = T/N (h*|Omega| "
                             "too large): increase steps. A subclass of InputError.")


# libyaml's emitter and parser where PyYAML has them (Debian's does): the Python ones take
# milliseconds for a scene, a tenth of a small solve in a batch worker.
_YAML_DUMPER = getattr(yaml, "CSafeDumper", yaml.SafeDumper)
_YAML_LOADER = getattr(yaml, "CSafeLoader", yaml.SafeLoader)


def _input_error(field, detail):
    """InputError("field: detail") with its field and detail set (as the core's errors have)."""
    error = InputError("%s: %s" % (field, detail))
    error.field, error.detail = field, detail
    return error


def _plain(value):
    """`value` with numpy arrays and scalars turned into lists and floats (for YAML)."""
    if isinstance(value, np.ndarray):
        return value.tolist()
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, dict):
        return {str(k): _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    return value


class Problem:
    """A scene to plan: the keys of a scene file (docs/DESIGN.md, "Scene file").

    Problem(scene=None, **keys): `scene` is a dict of scene keys or the path of a scene YAML file;
    `keys` are scene keys given as keywords (they override the dict's or the file's). The scene
    is parsed and checked at once by the core's scene parser (the one plan_maneuver uses): an
    unknown key or a bad value raises InputError naming the key and the value. Only rigid_body
    scenes are planned here (drift_two_input: plan_maneuver).

    Attributes: `yaml` (the scene text the core parsed), `source` (a name for messages). A
    Problem pickles as that text (and is parsed again when unpickled).
    """

    def __init__(self, scene=None, **keys):
        source = "<dict>"
        if scene is None:
            scene = {}
        elif isinstance(scene, (str, os.PathLike)):
            source = os.fspath(scene)
            try:
                with open(source) as f:
                    text = f.read()
            except OSError as e:
                raise _input_error("scene", "cannot read '%s' (%s)" % (source, e.strerror)) from None
            if not keys:
                self._set(text, source)
                return
            source += " with keywords"  # the text parsed is the file's keys and the keywords
            scene = yaml.load(text, Loader=_YAML_LOADER) or {}
            if not isinstance(scene, dict):
                raise _input_error("scene", "'%s' is not a mapping of scene keys" % source)
        elif not isinstance(scene, dict):
            raise _input_error("scene", "expected a dict of scene keys or a YAML path, got %r"
                               % (scene,))
        merged = dict(scene)
        merged.update(keys)
        self._set(yaml.dump(_plain(merged), Dumper=_YAML_DUMPER, sort_keys=False), source)

    @classmethod
    def from_yaml(cls, text, source="<yaml>"):
        """A Problem from scene YAML text."""
        problem = cls.__new__(cls)
        problem._set(text, source)
        return problem

    def _set(self, text, source):
        self._parsed = _core.parse_scene(text, source)  # parsed once, not at every plan()
        self.yaml = text
        self.source = source

    def __getstate__(self):
        return {"yaml": self.yaml, "source": self.source}

    def __setstate__(self, state):
        self._set(state["yaml"], state["source"])

    @property
    def scene(self):
        """The scene keys as a dict (the YAML parsed)."""
        return yaml.load(self.yaml, Loader=_YAML_LOADER) or {}

    def __eq__(self, other):
        return isinstance(other, Problem) and (self.yaml, self.source) == (other.yaml, other.source)

    def __repr__(self):
        return "Problem(%r)" % (self.source,)


class _Trajectory:
    """Rows k = 0..N of a maneuver as numpy arrays: t (N+1,), quaternions (N+1, 4) Hamilton
    (w, x, y, z) body to world, rotations (N+1, 3, 3), rates (N+1, 3) body [rad/s], torques
    (N+1, 3) body [N m]; time_step h [s]. The columns of plan_maneuver's CSV."""

    def _take(self, arrays):
        for name in ("t", "quaternions", "rotations", "rates", "torques", "time_step"):
            setattr(self, name, arrays[name])

    @property
    def steps(self):
        """N."""
        return len(self.t) - 1


class Result(_Trajectory):
    """What plan() returns: the maneuver's arrays (see below), how the solve ended and why.

    termination: "converged", "not_converged", "infeasible", "step_too_large", "timed_out",
    "cancelled"; message: why; converged: termination == "converged"; cost [N^2 m^2], duration
    T [s], minimum_duration T* [s] (0 unless minimum_time), solve_time_s: the summary's figures
    of the same names; summary: the JSON summary
    of plan_maneuver --summary as a dict (cost, duration, minimum_duration, attempts, ...);
    attempts: summary["attempts"], the solves the planner ran. Arrays: t, quaternions (w, x, y,
    z), rotations, rates, torques, time_step. A Result pickles, and warm-starts a later plan()
    (plan(problem, warm_start=result)).
    """

    def __init__(self, arrays):
        self._take(arrays)
        self.termination = arrays["termination"]
        self.message = arrays["message"]
        for name in ("cost", "duration", "minimum_duration", "solve_time_s"):
            setattr(self, name, arrays[name])  # the summary's numbers, without the JSON
        self._plan_call_s = arrays["plan_call_s"]  # planManeuver's wall time (the benchmark's)
        self._held = arrays["summary"]  # the C++ plan, until the summary is asked for
        self._summary = None

    @property
    def summary(self):
        """The JSON summary of plan_maneuver --summary, as a dict (written on first use)."""
        if self._summary is None:
            self._summary = json.loads(self._held.json())
            self._held = None
        return self._summary

    def __getstate__(self):
        state = dict(self.__dict__, _held=None)
        state["_summary"] = self.summary
        return state

    converged = property(lambda self: self.termination == "converged")
    attempts = property(lambda self: self.summary.get("attempts", []))

    def __repr__(self):
        return "Result(%s, N=%d, cost=%r)" % (self.termination, self.steps, self.cost)


class Simulation(_Trajectory):
    """What simulate() returns: the replayed maneuver's arrays and the implicit steps' worst
    residual [N m s] and Newton count."""

    def __init__(self, arrays):
        self._take(arrays)
        self.max_step_residual = arrays["max_step_residual"]
        self.max_step_iterations = arrays["max_step_iterations"]


def _flag_value(keyword, value):
    """A planning option's value as plan_maneuver takes it on its command line."""
    if isinstance(value, bool) or not isinstance(value, (str, numbers.Real)):
        raise _input_error(keyword, "expected a number or a name, got %r" % (value,))
    if isinstance(value, numbers.Integral):
        return str(int(value))
    if isinstance(value, numbers.Real) and not isinstance(value, str):
        return repr(float(value))  # shortest round-trip text: the same double in C++
    return value


def _advanced_flags(value, prefix=""):
    """The solvers' tuning as plan_maneuver's --advanced flags, one NAME=VALUE per field: from a
    dict of field names ("newton.armijo") or of nested dicts ({"newton": {"armijo": ...}}), or
    from one "NAME=VALUE" text."""
    if isinstance(value, str) and not prefix:
        return [("--advanced", value)]
    if not isinstance(value, dict):
        raise _input_error("advanced" + ("." + prefix[:-1] if prefix else ""),
                           "expected a dict of field names and values, got %r" % (value,))
    flags = []
    for name, field_value in value.items():
        if not isinstance(name, str):
            raise _input_error("advanced", "a field name must be a str, got %r" % (name,))
        if isinstance(field_value, dict):
            flags += _advanced_flags(field_value, prefix + name + ".")
        else:
            text = _flag_value("advanced." + prefix + name, field_value)
            flags.append(("--advanced", prefix + name + "=" + text))
    return flags


def plan(problem, warm_start=None, **options):
    """Plans `problem` (a Problem, or a dict / path Problem() accepts) and returns a Result.

    `options` are plan_maneuver's planning flags as keywords, with the same meaning and checks:
    steps, scheme, solver, precision, tolerance, max_iterations, time_budget, threads, target_miss,
    target_cost_error, objective, time_margin, direction, extra_revolutions, and `advanced`, the
    solvers' tuning as a dict ({"newton.armijo": 1e-3} or {"newton": {"armijo": 1e-3}}), one
    --advanced NAME=VALUE per field. `warm_start` is a previous Result (the CLI's --warm-start).
    The GIL is released during the solve, so threads plan in parallel. Raises InputError (a
    ValueError) naming the field and the value for bad input; a solve that does not converge is
    not an error (Result.termination says how it ended).
    """
    if not isinstance(problem, Problem):
        problem = Problem(problem)
    flags = []
    for key, value in options.items():
        if key == "advanced":
            flags += _advanced_flags(value)
        else:
            flags.append(("--" + key.replace("_", "-"), _flag_value(key, value)))
    warm = None
    if warm_start is not None:
        if not isinstance(warm_start, _Trajectory):
            raise _input_error("warm_start", "expected a Result, got %r" % (warm_start,))
        warm = {name: getattr(warm_start, name)
                for name in ("t", "rotations", "rates", "torques", "time_step")}
    try:
        arrays = _core.plan(problem._parsed, flags, warm)
    except InputError as e:
        _rename_flag(e)
        raise
    return Result(arrays)


def _rename_flag(error):
    """An error about a flag ("--time-margin: ...") names the keyword instead ("time_margin")."""
    field = getattr(error, "field", "")
    if field.startswith("--"):
        keyword = field[2:].replace("-", "_")
        error.field = keyword
        error.args = (keyword + ": " + error.detail,)


def simulate(problem, torques, time_step=None, scheme=None):
    """Replays torques through the discrete dynamics from the problem's initial state, with the
    scene's effects (as simulate_torques does); returns a Simulation.

    `torques`: a Result (its torques and time step) or an (N+1, 3) array [N m] with `time_step`
    h [s]; `scheme`: the integrator (default: the scene's).
    """
    if not isinstance(problem, Problem):
        problem = Problem(problem)
    if isinstance(torques, _Trajectory):
        time_step = torques.time_step if time_step is None else time_step
        torques = torques.torques
    if time_step is None:
        raise _input_error("time_step", "required with a torque array")
    return Simulation(_core.simulate(problem._parsed, np.asarray(torques, dtype=float),
                                     float(time_step), scheme or ""))
