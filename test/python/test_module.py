"""The Python module attitude_planner (README.md "Python"), run by scripts/test through catkin with
the workspace sourced (cmake/python_tests.cmake), from the package directory.

The module is a thin adapter: what it must show is that it plans exactly what plan_maneuver plans
(the same parser, flags and core), that its errors name the field and the value, that its objects
pickle and warm-start, and that the GIL is released during a solve.
"""
import csv
import json
import os
import pickle
import re
import subprocess
import sys
import tempfile
import threading
import unittest

import numpy as np

import attitude_planner as ap
from support import REPO, tool

SCENES = os.path.join(REPO, "scenes")
REST_TO_REST = os.path.join(SCENES, "rest_to_rest.yaml")
MIN_TIME_SPHERE = os.path.join(SCENES, "min_time_sphere.yaml")


def run_cli(scene, flags, directory):
    """plan_maneuver SCENE FLAGS --csv --summary → (CSV rows as text cells, summary dict)."""
    csv_path = os.path.join(directory, "plan.csv")
    json_path = os.path.join(directory, "plan.json")
    done = subprocess.run([tool("plan_maneuver"), scene] + flags +
                          ["--csv", csv_path, "--summary", json_path],
                          stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                          universal_newlines=True)
    if done.returncode not in (0, 1):
        raise AssertionError("plan_maneuver failed (%d):\n%s" % (done.returncode, done.stdout))
    with open(csv_path, newline="") as f:
        rows = list(csv.reader(f))
    with open(json_path) as f:
        summary = json.load(f)
    return rows, summary


def csv_cells(result):
    """The Result's arrays as plan_maneuver writes its CSV (%.17g), row by row."""
    rows = []
    for k in range(result.steps + 1):
        values = ([result.t[k]] + list(result.quaternions[k]) + list(result.rates[k]) +
                  list(result.torques[k]))
        rows.append([str(k)] + ["%.17g" % v for v in values])
    return rows


def without_timing(summary):
    """The summary without the wall-clock fields (the only ones two identical solves differ in)."""
    if isinstance(summary, dict):
        return {k: without_timing(v) for k, v in summary.items() if "time_s" not in k}
    if isinstance(summary, list):
        return [without_timing(v) for v in summary]
    return summary


class SameAsTheCommandLine(unittest.TestCase):
    """plan() and plan_maneuver: the same trajectory to the last digit and the same summary."""

    def check_same(self, scene, flags, options):
        with tempfile.TemporaryDirectory() as directory:
            rows, cli_summary = run_cli(scene, flags, directory)
        result = ap.plan(ap.Problem(scene), **options)
        self.assertEqual(rows[0], "k,t,qw,qx,qy,qz,wx,wy,wz,tx,ty,tz".split(","))
        self.assertEqual(len(rows) - 1, result.steps + 1)
        self.assertEqual(rows[1:], csv_cells(result))
        self.assertEqual(without_timing(result.summary), without_timing(cli_summary))
        return result

    def test_minimum_effort_with_flags(self):
        result = self.check_same(REST_TO_REST, ["--steps", "32", "--scheme", "variational"],
                                 {"steps": 32, "scheme": "variational"})
        self.assertTrue(result.converged, result.message)

    def test_pointing_flags(self):
        # A pointing target from the flags: the same plan and final_twist as the CLI's.
        result = self.check_same(REST_TO_REST,
                                 ["--steps", "32", "--point-body-axis", "0,0,1",
                                  "--point-world-direction", "1,1,0"],
                                 {"steps": 32, "point_body_axis": "0,0,1",
                                  "point_world_direction": "1,1,0"})
        self.assertTrue(result.converged, result.message)
        self.assertLess(result.summary["pointing"]["error"], 1e-12)
        self.assertEqual(result.summary["final_twist"], result.summary["pointing"]["final_twist"])

    def test_minimum_time_with_a_float_flag(self):
        # time_margin goes through Python's repr and strtod: the same double as the CLI's text.
        result = self.check_same(MIN_TIME_SPHERE, ["--steps", "32", "--time-margin", "0.1"],
                                 {"steps": 32, "time_margin": 0.1})
        self.assertTrue(result.converged, result.message)
        self.assertGreater(result.minimum_duration, 0.0)
        self.assertAlmostEqual(result.duration, 1.1 * result.minimum_duration, places=9)

    def test_advanced_as_a_dict_is_one_flag_per_field(self):
        # Nested and dotted names alike; each field reaches the solver as the CLI's flag does.
        flags = ["--steps", "32", "--advanced", "newton.coarsest_steps=32",
                 "--advanced", "newton.armijo=0.001"]
        advanced = {"newton": {"coarsest_steps": 32}, "newton.armijo": 1e-3}
        result = self.check_same(REST_TO_REST, flags, {"steps": 32, "advanced": advanced})
        self.assertTrue(result.converged, result.message)
        default = ap.plan(ap.Problem(REST_TO_REST), steps=32)
        self.assertNotEqual(result.summary["iterations"], default.summary["iterations"])
        self.assertAlmostEqual(result.summary["cost"], default.summary["cost"],
                               delta=1e-8 * default.summary["cost"])


class Problems(unittest.TestCase):

    def test_a_dict_a_path_and_keywords_are_one_scene(self):
        import yaml
        with open(REST_TO_REST) as f:
            keys = yaml.safe_load(f)
        from_path = ap.plan(ap.Problem(REST_TO_REST, steps=16))
        from_dict = ap.plan(dict(keys, steps=16))
        from_keywords = ap.plan(ap.Problem(**dict(keys, steps=16)))
        for other in (from_dict, from_keywords):
            np.testing.assert_array_equal(other.quaternions, from_path.quaternions)
            np.testing.assert_array_equal(other.torques, from_path.torques)
        self.assertEqual(from_path.steps, 16)

    def test_messages_live_beside_the_module(self):
        from attitude_planner.msg import AttitudeManeuver, PlanErrorCode  # noqa: F401
        from attitude_planner.srv import PlanAttitudeManeuver  # noqa: F401
        self.assertTrue(hasattr(AttitudeManeuver(), "constraints"))
        self.assertIs(ap.plan, __import__("attitude_planner").plan)


class BadInput(unittest.TestCase):
    """An InputError (a ValueError) names the field and the value."""

    def assert_names(self, error, field, value):
        self.assertIsInstance(error, ValueError)
        self.assertEqual(error.field, field)
        self.assertIn(field, str(error))
        self.assertIn(value, str(error))

    def test_unknown_scene_key(self):
        with self.assertRaises(ap.InputError) as caught:
            ap.Problem(REST_TO_REST, stepz=4)
        self.assertIn("stepz", str(caught.exception))

    def test_bad_scene_value(self):
        with self.assertRaises(ap.InputError) as caught:
            ap.Problem(REST_TO_REST, duration=-3.5)
        self.assert_names(caught.exception, "duration", "-3.5")

    def test_bad_option_value_names_the_keyword(self):
        with self.assertRaises(ap.InputError) as caught:
            ap.plan(ap.Problem(REST_TO_REST), time_margin=-0.25)
        self.assert_names(caught.exception, "time_margin", "-0.25")
        with self.assertRaises(ap.InputError) as caught:
            ap.plan(ap.Problem(REST_TO_REST), scheme="euler")
        self.assert_names(caught.exception, "scheme", "euler")

    def test_unknown_option_and_wrong_type(self):
        with self.assertRaises(ap.InputError) as caught:
            ap.plan(ap.Problem(REST_TO_REST), stepz=8)
        self.assertEqual(caught.exception.field, "stepz")
        with self.assertRaises(ap.InputError) as caught:
            ap.plan(ap.Problem(REST_TO_REST), steps=True)
        self.assert_names(caught.exception, "steps", "True")

    def test_a_bad_advanced_field_is_named(self):
        with self.assertRaises(ap.InputError) as caught:
            ap.plan(ap.Problem(REST_TO_REST), advanced={"newton.armijo": 0.75})
        self.assert_names(caught.exception, "advanced", "0.75")
        self.assertIn("advanced.newton.armijo", str(caught.exception))
        with self.assertRaises(ap.InputError) as caught:
            ap.plan(ap.Problem(REST_TO_REST), advanced={"newton": {"armijo_typo": 0.1}})
        self.assertIn("newton.armijo_typo", str(caught.exception))
        with self.assertRaises(ap.InputError) as caught:
            ap.plan(ap.Problem(REST_TO_REST), advanced=[0.1])
        self.assertEqual(caught.exception.field, "advanced")

    def test_step_too_large_is_an_input_error(self):
        spinning = {"initial": {"attitude": {"axis": [1, 0, 0], "angle": 0.0},
                                "angular_velocity": [40.0, 0, 0]}}
        with self.assertRaises(ap.InputError):
            ap.plan(ap.Problem(REST_TO_REST, steps=8, **spinning))


class PickleAndWarmStart(unittest.TestCase):

    def test_round_trip(self):
        problem = ap.Problem(REST_TO_REST, steps=24)
        result = ap.plan(problem)
        problem2 = pickle.loads(pickle.dumps(problem))
        result2 = pickle.loads(pickle.dumps(result))
        self.assertEqual(problem2, problem)
        for name in ("t", "quaternions", "rotations", "rates", "torques"):
            np.testing.assert_array_equal(getattr(result2, name), getattr(result, name))
        self.assertEqual(result2.summary, result.summary)
        self.assertEqual((result2.termination, result2.message),
                         (result.termination, result.message))
        again = ap.plan(problem2)
        np.testing.assert_array_equal(again.torques, result.torques)

    def test_warm_start_from_a_result(self):
        problem = ap.Problem(REST_TO_REST, steps=32)
        cold = ap.plan(problem)
        warm = ap.plan(problem, warm_start=pickle.loads(pickle.dumps(cold)))
        self.assertTrue(warm.converged, warm.message)
        self.assertEqual(warm.attempts[0]["start"], "warm_start")
        self.assertLess(warm.summary["iterations"], cold.summary["iterations"])
        self.assertAlmostEqual(warm.cost, cold.cost, delta=1e-8 * cold.cost)


class Simulate(unittest.TestCase):

    def test_replay_of_the_planned_torques_is_the_plan(self):
        # An independent integration of the planned torques (replayPlan, as simulate_torques
        # does) lands where the plan does.
        problem = ap.Problem(REST_TO_REST, steps=32)
        result = ap.plan(problem)
        replay = ap.simulate(problem, result)
        self.assertEqual(replay.steps, result.steps)
        np.testing.assert_allclose(replay.rotations, result.rotations, atol=1e-9)
        np.testing.assert_allclose(replay.rates, result.rates, atol=1e-9)
        from_array = ap.simulate(problem, result.torques, time_step=result.time_step)
        np.testing.assert_array_equal(from_array.rotations, replay.rotations)
        with self.assertRaises(ap.InputError) as caught:
            ap.simulate(problem, np.zeros((5, 2)), time_step=0.1)
        self.assertEqual(caught.exception.field, "torques")


class GilReleased(unittest.TestCase):

    def test_another_thread_runs_during_a_solve(self):
        # With a switch interval far longer than the solve, a thread that holds the GIL keeps it:
        # the main thread, woken by `started`, can run while the worker is inside plan() only if
        # plan() released the GIL. It then sees `inside` still set. Held, it would first run after
        # the worker has cleared `inside` and ended. No timing is measured.
        problem = ap.Problem(MIN_TIME_SPHERE, steps=64)
        state = {"inside": False}
        started = threading.Event()

        def worker():
            state["inside"] = True
            started.set()
            ap.plan(problem)
            state["inside"] = False

        interval = sys.getswitchinterval()
        sys.setswitchinterval(30.0)
        try:
            thread = threading.Thread(target=worker)
            thread.start()
            started.wait()
            seen_inside = state["inside"]
            thread.join()
        finally:
            sys.setswitchinterval(interval)
        self.assertTrue(seen_inside)
        self.assertFalse(state["inside"])


class ReadmeExample(unittest.TestCase):

    def test_readme_python_example_runs_and_prints_what_it_says(self):
        # README.md's Python block (after "## Planning from Python") is run as written, from
        # the package directory; its "It prints:" block shows the output (a line ending in "..."
        # shows the start of the line printed).
        with open(os.path.join(REPO, "README.md")) as f:
            readme = f.read()
        section = readme[readme.index("\n## Planning from Python"):]
        code = re.search(r"```python\n(.*?)```", section, re.S).group(1)
        shown = re.search(r"It prints:\n\n```\n(.*?)```", section, re.S).group(1).splitlines()
        done = subprocess.run([sys.executable, "-c", code], cwd=REPO, stdout=subprocess.PIPE,
                              stderr=subprocess.STDOUT, universal_newlines=True)
        self.assertEqual(done.returncode, 0, done.stdout)
        printed = done.stdout.splitlines()
        self.assertEqual(len(printed), len(shown), done.stdout)
        for line, expected in zip(printed, shown):
            self.assertTrue(line.startswith(expected.rstrip(". ")),
                            "README shows %r, the example prints %r" % (expected, line))


if __name__ == "__main__":
    unittest.main()
