"""What `rosrun attitude_planner <TAB>` offers and what rosrun searches, in the built workspace
(run by scripts/test through catkin, with the devel space sourced). One JUnit result.

- the libexec directory (catkin_find --libexec: devel/lib/attitude_planner) holds exactly the
  nodes and the command-line tools: no test, no study;
- rosbash's own completion function lists those plus the package's scripts/ entry points;
- rosrun reports no file-system loop (the workspace is outside the package tree);
- replay.launch sets no global parameter (no /use_sim_time left on the master) and resolves a
  relative bag against the caller's directory.

  python3 rosrun_offers.py --results XML --expect NAME [NAME ...]
"""
import argparse
import os
import subprocess
import sys

from junit_result import Suite

PACKAGE = "attitude_planner"
COMPLETION = "/usr/share/bash-completion/completions/rosbash"


def shell(command):
    done = subprocess.run(["bash", "-c", command], stdout=subprocess.PIPE,
                          stderr=subprocess.STDOUT, universal_newlines=True)
    return done.returncode, done.stdout


def executables_under(directory):
    """Executable files below `directory`, symlinks followed, as rosrun's find -L sees them."""
    found = set()
    for root, _, files in os.walk(directory, followlinks=True):
        for name in files:
            path = os.path.join(root, name)
            if os.path.isfile(path) and os.access(path, os.X_OK):
                found.add(name)
    return found


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--results", required=True)
    parser.add_argument("--expect", nargs="+", required=True, help="the nodes and the tools")
    args = parser.parse_args()
    expected = set(args.expect)
    suite = Suite("rosrun_offers")

    _, libexec = shell("catkin_find --first-only --without-underlays --libexec %s" % PACKAGE)
    libexec = libexec.strip()
    offered = executables_under(libexec) if os.path.isdir(libexec) else set()
    suite.check("LibexecHoldsOnlyTheNodesAndTools", offered == expected,
                "%s holds %s; expected exactly %s" % (libexec, sorted(offered), sorted(expected)))

    status, package_dir = shell("rospack find %s" % PACKAGE)
    package_dir = os.path.realpath(package_dir.strip())
    scripts = executables_under(os.path.join(package_dir, "scripts"))
    status, completion = shell(
        "source %s && COMP_WORDS=(rosrun %s '') && COMP_CWORD=2 && _roscomplete_exe "
        "&& printf '%%s\\n' \"${COMPREPLY[@]}\"" % (COMPLETION, PACKAGE))
    listed = set(completion.split())
    suite.check("TabCompletionOffersNodesToolsAndScripts",
                status == 0 and listed == expected | scripts,
                "completion (status %d) lists %s; expected the nodes and tools %s and scripts/ %s"
                % (status, sorted(listed), sorted(expected), sorted(scripts)))

    workspace = os.path.realpath(os.path.join(libexec, "..", "..", ".."))
    status, output = shell("rosrun %s no_such_executable" % PACKAGE)
    suite.check("RosrunFindsNoFileSystemLoop",
                "loop" not in output and "Couldn't find executable" in output and
                not (workspace + os.sep).startswith(package_dir + os.sep),
                "rosrun (status %d) printed:\n%s\npackage %s, workspace %s"
                % (status, output, package_dir, workspace))

    status, dump = shell("roslaunch --dump-params %s replay.launch bag:=maneuver.bag" % PACKAGE)
    suite.check("ReplayLaunchSetsNoGlobalParameter",
                status == 0 and "/use_sim_time" not in dump.replace("/rviz/use_sim_time", "")
                and "/rviz/use_sim_time: true" in dump,
                "roslaunch --dump-params (status %d):\n%s" % (status, dump))
    status, play = shell("cd /tmp && roslaunch --args /play %s replay.launch bag:=maneuver.bag"
                         % PACKAGE)
    suite.check("ReplayLaunchResolvesARelativeBagAgainstTheCaller",
                status == 0 and " /tmp/maneuver.bag" in play,
                "roslaunch --args /play (status %d): %s" % (status, play))
    return 0 if suite.write(args.results) else 1


if __name__ == "__main__":
    sys.exit(main())
