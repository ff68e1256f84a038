"""Resident memory of attitude_planner_node around timed-out N = 1e5 solves (is the
memory returned after stopped solves?). Needs a running planner node (scripts/planner_memory starts one on
a private master). Calls the service `--solves` times with the seed's slew at N = `--steps` and a
budget far below the solve (each answered TIMED_OUT, its solve told to stop), then one small
request (which joins the stopped solves), and prints the node's VmRSS / VmHWM (/proc) after each
phase as a markdown table; the last row once the stopped solves have returned."""
import argparse
import time
import xmlrpc.client

import rosgraph
import rospy

from attitude_planner.srv import PlanAttitudeManeuver, PlanAttitudeManeuverRequest
from seed_request import fill_seed


def node_pid(name):
    uri = rosgraph.Master("/planner_memory").lookupNode(name)
    return xmlrpc.client.ServerProxy(uri).getPid("/planner_memory")[2]


def memory_mb(pid):
    fields = {}
    with open("/proc/%d/status" % pid) as f:
        for line in f:
            key, _, value = line.partition(":")
            if key in ("VmRSS", "VmHWM"):
                fields[key] = int(value.split()[0]) / 1024.0
    return fields["VmRSS"], fields["VmHWM"]


def main():
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--node", default="/attitude_planner")
    parser.add_argument("--solves", type=int, default=20)
    parser.add_argument("--steps", type=int, default=100000)
    parser.add_argument("--budget", type=float, default=0.3)
    args = parser.parse_args()
    rospy.init_node("planner_memory", anonymous=True)
    rospy.wait_for_service("plan_attitude_maneuver", timeout=60)
    plan = rospy.ServiceProxy("plan_attitude_maneuver", PlanAttitudeManeuver)
    pid = node_pid(args.node)
    rows = [("started", 0, "") + memory_mb(pid)]
    for i in range(args.solves):
        req = fill_seed(PlanAttitudeManeuverRequest(), args.steps)
        req.time_budget = args.budget
        req.return_maneuver = "none"
        res = plan(req)
        if i in (0, args.solves // 2 - 1, args.solves - 1):
            rows.append(("after timed-out solve %d" % (i + 1), res.error_code.val, res.message[:40])
                        + memory_mb(pid))
    # The stopped solves still run until they notice the stop and return (seconds each, all
    # sharing the cores); a small request joins those that have returned (reapLateSolves). Asked
    # every 2 s until the resident size settles (two readings within 1 MB) or 120 s.
    started = time.time()
    previous = None
    while time.time() - started < 120.0:
        time.sleep(2.0)
        res = plan(fill_seed(PlanAttitudeManeuverRequest(), 32))
        rss, hwm = memory_mb(pid)
        if previous is not None and abs(rss - previous) < 1.0:
            break
        previous = rss
    rows.append(("settled, %.0f s after the last (small requests every 2 s)"
                 % (time.time() - started), res.error_code.val, "", rss, hwm))
    print("| phase | error code | message | VmRSS [MB] | VmHWM (peak) [MB] |")
    print("|---|---|---|---|---|")
    for phase, code, message, rss, hwm in rows:
        print("| %s | %s | %s | %.0f | %.0f |" % (phase, code, message, rss, hwm))


if __name__ == "__main__":
    main()
