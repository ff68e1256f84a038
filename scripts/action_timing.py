#!/usr/bin/env python3
"""Cancel latency and deadline keeping of the planner node at N = 1e5 (docs/ros_timing.md).

1. Cancel latency: an action goal that never converges (seed slew, N = 1e5, tolerance 1e-300) is
   cancelled at a spread of moments after its first feedback; the latency is the wall time from
   cancel_goal() to the result arriving in this client (transport both ways included).
2. Deadline: service calls at N = 1e5 with a time_budget below, near and above what the solve
   needs; the answer's status, its round trip against the budget, and whether it carries the
   plan the stopped solve reached (unconverged_plan, with its residuals).
Needs a running master and planner.launch. Prints markdown tables.
Usage: /usr/bin/python3 scripts/action_timing.py [--steps 100000] [--cancels 8] [--deadline-only]
"""
import argparse
import statistics
import threading
import time

import actionlib
import rospy
from actionlib_msgs.msg import GoalStatus
from attitude_planner.msg import (PlanAttitudeManeuverAction, PlanAttitudeManeuverGoal,
                                  PlanErrorCode)
from attitude_planner.srv import PlanAttitudeManeuver, PlanAttitudeManeuverRequest
from seed_request import fill_seed

STATES = {v: k for k, v in GoalStatus.__dict__.items() if k.isupper() and isinstance(v, int)}
CODES = {v: k for k, v in PlanErrorCode.__dict__.items() if k.isupper() and isinstance(v, int)}


def seed_without_plan(r, steps):
    """The seed's slew, answered without the maneuver (the timings measure the solve)."""
    r = fill_seed(r, steps)
    r.return_maneuver = "none"
    return r


def cancel_latency(client, steps, delay, with_plan=False):
    """Sends an endless goal, cancels it `delay` s after its first feedback; returns
    (latency [s], state, error code, iterations at the cancel, whether the stopped plan was
    handed over, rows of it in the result). `with_plan`: the goal asks for every node."""
    goal = seed_without_plan(PlanAttitudeManeuverGoal(), steps)
    if with_plan:
        goal.return_maneuver = ""
    goal.tolerance = 1e-300
    goal.max_iterations = 1000000
    goal.time_budget = 600.0
    first = threading.Event()
    seen = {"iteration": 0}

    def on_feedback(f):
        seen["iteration"] = f.iteration
        first.set()

    for _ in range(600):
        first.clear()
        client.send_goal(goal, feedback_cb=on_feedback)
        while not first.wait(0.05):
            if client.get_state() not in (GoalStatus.PENDING, GoalStatus.ACTIVE):
                break  # REJECTED: the workers are still stopping the last cancelled solves
        if first.is_set():
            break
        time.sleep(0.2)
    else:
        raise SystemExit("no goal accepted and fed back in 120 s")
    time.sleep(delay)
    at = seen["iteration"]
    t0 = time.perf_counter()
    client.cancel_goal()
    client.wait_for_result(rospy.Duration(120.0))
    latency = time.perf_counter() - t0
    result = client.get_result()
    return (latency, client.get_state(), result.error_code.val, at, result.unconverged_plan,
            len(result.maneuver.attitude))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--steps", type=int, default=100000)
    ap.add_argument("--cancels", type=int, default=8)
    ap.add_argument("--deadline-only", action="store_true", help="skip the cancels")
    args = ap.parse_args()
    rospy.init_node("action_timing", anonymous=True)
    client = actionlib.SimpleActionClient("plan_attitude_maneuver_action",
                                          PlanAttitudeManeuverAction)
    if not client.wait_for_server(rospy.Duration(30.0)):
        raise SystemExit("no action server")

    print("### Cancel latency, N = %d\n" % args.steps)
    for with_plan in (() if args.deadline_only else (False, True)):
        print("return_maneuver %s:\n" % ('"" (every node)' if with_plan else '"none"'))
        print("| cancel sent after first feedback [s] | iteration at cancel | cancel -> result "
              "[ms] | state | error | plan handed over | rows in the result |")
        print("|---|---|---|---|---|---|---|")
        latencies = []
        for i in range(args.cancels if not with_plan else max(1, args.cancels // 2)):
            delay = 0.05 + 0.137 * i  # spread over several iterations' phases
            latency, state, code, at, handed, rows = cancel_latency(client, args.steps, delay,
                                                                    with_plan)
            latencies.append(latency)
            print("| %.3f | %d | %.1f | %s | %s | %s | %d |" %
                  (delay, at, 1e3 * latency, STATES.get(state, state), CODES.get(code, code),
                   "yes" if handed else "no", rows))
        print("\nmedian %.1f ms, max %.1f ms over %d cancels\n" %
              (1e3 * statistics.median(latencies), 1e3 * max(latencies), len(latencies)))

    rospy.wait_for_service("plan_attitude_maneuver", timeout=30)
    proxy = rospy.ServiceProxy("plan_attitude_maneuver", PlanAttitudeManeuver)
    print("### Deadline, N = %d (service; the seed slew, default tolerance)\n" % args.steps)
    print("| time_budget [s] | round trip [s] | solve_time [s] | over budget | status | "
          "iterations | plan handed over | step residual | max residual |")
    print("|---|---|---|---|---|---|---|---|---|")
    for budget in (0.01, 0.1, 0.3, 1.0, 2.0, 5.0, 30.0):
        req = seed_without_plan(PlanAttitudeManeuverRequest(), args.steps)
        req.time_budget = budget
        t0 = time.perf_counter()
        res = proxy(req)
        total = time.perf_counter() - t0
        print("| %g | %.3f | %.3f | %+.0f %% | %s | %d | %s | %.2g | %.3g |" %
              (budget, total, res.solve_time, 100.0 * (total - budget) / budget,
               CODES.get(res.error_code.val, res.error_code.val), res.iterations,
               "yes" if res.unconverged_plan else "no", res.step_residual, res.max_residual))


if __name__ == "__main__":
    main()
