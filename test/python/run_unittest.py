"""Runs the unittest modules given and writes one JUnit result file (one <testcase> per test
method), which catkin_test_results and scripts/test count. Run by catkin with the devel space
sourced (cmake/python_tests.cmake).

  python3 run_unittest.py --results XML MODULE.py [MODULE.py ...]
"""
import argparse
import os
import sys
import time
import traceback
import unittest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "packaging"))
from junit_result import Suite  # noqa: E402


class Recorder(unittest.TestResult):
    """Records every test in the Suite: passed, failed (failure or error), or skipped (written as
    a failure: a test here has no reason to skip, and a silent skip would hide a broken setup)."""

    def __init__(self, suite):
        super().__init__()
        self.suite = suite
        self.started = 0.0

    def startTest(self, test):
        super().startTest(test)
        self.started = time.monotonic()
        print("RUN    %s" % test.id(), flush=True)

    def _record(self, test, message):
        name = "%s (%.1f s)" % (test.id().split(".", 1)[-1], time.monotonic() - self.started)
        self.suite.check(name.split(" (")[0], message is None, message or "")

    def addSuccess(self, test):
        super().addSuccess(test)
        self._record(test, None)

    def addFailure(self, test, err):
        super().addFailure(test, err)
        self._record(test, "".join(traceback.format_exception(*err)))

    def addError(self, test, err):
        super().addError(test, err)
        self._record(test, "".join(traceback.format_exception(*err)))

    def addSkip(self, test, reason):
        super().addSkip(test, reason)
        self._record(test, "skipped: " + reason)


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--results", required=True)
    parser.add_argument("modules", nargs="+")
    args = parser.parse_args()
    name = os.path.splitext(os.path.basename(args.results))[0]
    suite = Suite(name)
    loader = unittest.defaultTestLoader
    tests = unittest.TestSuite()
    for path in args.modules:
        directory, module = os.path.split(os.path.abspath(path))
        sys.path.insert(0, directory)
        try:
            tests.addTests(loader.loadTestsFromName(os.path.splitext(module)[0]))
        except Exception:  # an import error is a failure, never an empty suite
            suite.check("Import_" + module, False, traceback.format_exc())
    if tests.countTestCases() == 0:
        suite.check("SomeTestRan", False, "no test found in %s" % args.modules)
    tests.run(Recorder(suite))
    return 0 if suite.write(args.results) else 1


if __name__ == "__main__":
    sys.exit(main())
