#!/usr/bin/env python3
"""End-to-end latency of plan_attitude_maneuver: a rospy client calls the running planner node
with the seed's rest-to-rest example (π/3 about x, T = 12.8 s, seed inertia) and times each call
from the request to the deserialized response. Needs a running master and planner.launch.
Usage: /usr/bin/python3 scripts/service_latency.py [--steps 128] [--calls 20]
"""
import argparse
import statistics
import time

import rospy
from attitude_planner.srv import PlanAttitudeManeuver, PlanAttitudeManeuverRequest
from seed_request import fill_seed


def seed_request(steps):
    r = fill_seed(PlanAttitudeManeuverRequest(), steps)
    r.scheme = "paper"
    return r


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--steps", type=int, default=128)
    ap.add_argument("--calls", type=int, default=20)
    args = ap.parse_args()
    rospy.init_node("service_latency", anonymous=True)
    rospy.wait_for_service("plan_attitude_maneuver", timeout=30)
    # A persistent connection (the normal way a client calls repeatedly) and a fresh one per call.
    for persistent in (True, False):
        proxy = rospy.ServiceProxy("plan_attitude_maneuver", PlanAttitudeManeuver,
                                   persistent=persistent)
        req = seed_request(args.steps)
        total, solve = [], []
        for _ in range(args.calls):
            t0 = time.perf_counter()
            res = proxy(req)
            total.append(time.perf_counter() - t0)
            if not res.success:
                raise SystemExit("service failed: " + res.message)
            solve.append(res.solve_time)
        proxy.close()
        print("N = %d, %s connection, %d calls: round trip median %.2f ms (min %.2f, max %.2f); "
              "solve_time median %.2f ms; overhead median %.2f ms; cost %.10g" %
              (args.steps, "persistent" if persistent else "new", args.calls,
               1e3 * statistics.median(total), 1e3 * min(total), 1e3 * max(total),
               1e3 * statistics.median(solve),
               1e3 * statistics.median(t - s for t, s in zip(total, solve)), res.cost))


if __name__ == "__main__":
    main()
