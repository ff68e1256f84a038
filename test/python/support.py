"""Shared by the Python tests: the package directory and the built command-line tools."""
import os
import subprocess

REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def tool(name):
    """The built command-line tool `name` (devel/lib/attitude_planner, found as rosrun finds it)."""
    libexec = subprocess.run(["catkin_find", "--first-only", "--without-underlays", "--libexec",
                              "attitude_planner"], stdout=subprocess.PIPE,
                             universal_newlines=True, check=True).stdout.strip()
    return os.path.join(libexec, name)
