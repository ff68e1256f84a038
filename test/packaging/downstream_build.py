"""Builds test/packaging/attitude_planner_client, a downstream catkin package, in a workspace of
its own on top of attitude_planner's devel space, as a user would (find_package(catkin
COMPONENTS attitude_planner), ${catkin_LIBRARIES}); runs its C++ program (scene parsing,
planManeuver, maneuverToMsg) and its Python script (the srv and the action). One JUnit result.

  python3 downstream_build.py --devel DEVEL --work DIR --results XML [--cmake-arg ARG ...]
"""
import argparse
import os
import shutil
import subprocess
import sys

from junit_result import Suite

HERE = os.path.dirname(os.path.abspath(__file__))
CLIENT = "attitude_planner_client"


def run_in(setup, command, cwd, log):
    """Runs `command` (bash) after sourcing `setup`; returns (status, output)."""
    script = "source '%s' && %s" % (setup, command)
    # A fresh make: not a child of the make running the tests (its jobserver, its flags).
    env = {k: v for k, v in os.environ.items() if k not in ("MAKEFLAGS", "MFLAGS", "MAKELEVEL")}
    done = subprocess.run(["bash", "-c", script], cwd=cwd, env=env, stdout=subprocess.PIPE,
                          stderr=subprocess.STDOUT, universal_newlines=True)
    with open(log, "a") as f:
        f.write("$ %s\n%s\n" % (command, done.stdout))
    return done.returncode, done.stdout


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--devel", required=True, help="attitude_planner's devel space")
    parser.add_argument("--work", required=True, help="the downstream workspace (recreated)")
    parser.add_argument("--results", required=True, help="JUnit XML to write")
    parser.add_argument("--cmake-arg", action="append", default=[],
                        help="passed to the downstream catkin_make (e.g. sanitizer flags)")
    args = parser.parse_args()

    suite = Suite("downstream_build")
    shutil.rmtree(args.work, ignore_errors=True)
    os.makedirs(os.path.join(args.work, "src"))
    shutil.copytree(os.path.join(HERE, CLIENT), os.path.join(args.work, "src", CLIENT))
    log = os.path.join(args.work, "downstream.log")
    print("downstream workspace %s (log: %s)" % (args.work, log))

    cmake_args = ["-DPYTHON_EXECUTABLE=/usr/bin/python3"] + args.cmake_arg
    if shutil.which("ccache"):
        cmake_args.append("-DCMAKE_CXX_COMPILER_LAUNCHER=ccache")
    quoted = " ".join("'%s'" % a for a in cmake_args)
    status, output = run_in(os.path.join(args.devel, "setup.bash"),
                            "catkin_make -j1 %s" % quoted, args.work, log)
    built = suite.check("CatkinMakeBuildsTheClient", status == 0,
                        "catkin_make exited %d:\n%s" % (status, output[-4000:]))

    client_setup = os.path.join(args.work, "devel", "setup.bash")
    if built:
        status, output = run_in(client_setup, "rosrun %s plan_and_convert" % CLIENT,
                                args.work, log)
        suite.check("CppPlansAndConvertsThroughTheExportedLibraries", status == 0,
                    "plan_and_convert exited %d:\n%s" % (status, output[-4000:]))
    else:
        suite.check("CppPlansAndConvertsThroughTheExportedLibraries", False, "not built")
    status, output = run_in(client_setup if built else os.path.join(args.devel, "setup.bash"),
                            "/usr/bin/python3 '%s'" % os.path.join(
                                args.work, "src", CLIENT, "scripts", "use_interfaces.py"),
                            args.work, log)
    suite.check("PythonImportsTheServiceAndTheAction", status == 0,
                "use_interfaces.py exited %d:\n%s" % (status, output[-4000:]))
    return 0 if suite.write(args.results) else 1


if __name__ == "__main__":
    sys.exit(main())
