#!/usr/bin/env python3
"""What a minimum-effort request just above T* costs, without and with a keep-out cone.

The requests of minimum_time_cost.py (rest-to-rest slews of physical bodies under per-axis torque
bounds, one keep-out cone across the eigenaxis path), for several seeds: each is planned for
minimum time (the defaults), and where that converged, once for minimum effort at 1.05 T* (the
user who does not know T*: the planner's default recipe from the unconstrained optimum). The page
says how many iterations and how much time the minimum-effort answer took, where its iterations
went (by the trail's attempt stages), and how often it took longer than the minimum-time solve of
the same request. Beside it, the other route to the same plan: `--time-margin 0.05` (minimum time,
then minimum effort at 1.05 T* from the T* plan, time-scaled: strictly inside every bound), its
iterations, time and cost against the default's. One run of each (iterations are deterministic;
times are one sample).

With --before-plan-maneuver BIN2 every request is also planned with BIN2 (e.g. main's build:
a wrapper setting LD_LIBRARY_PATH) and a section compares the two request by request: the
minimum-effort cost (1e-9 relative), the termination, the iterations.

  near_minimum_time_cones.py --plan-maneuver BIN [--before-plan-maneuver BIN2]
                             [--seeds S,S,...] [--count K] [--out FILE.md]
"""
import argparse
import datetime
import os
import statistics
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from study_page import load_average, write_page  # noqa: E402

import minimum_time_cost as mtc  # noqa: E402

SLOW = 300  # iterations: "many" for one minimum-effort request at N = 128 (the median is 49-77)


def measure(binary, case, cone, steps, work):
    text = mtc.scene_text(case, steps, cone)
    fastest = mtc.plan(binary, text, work)
    row = {"index": case["index"], "cone": cone, "T": fastest.get("duration")}
    if not fastest.get("converged"):
        row["termination"] = fastest.get("termination", "?")
        return row
    effort = mtc.plan(binary, mtc.as_effort(text, mtc.EFFORT_AT * fastest["duration"]), work)
    stages = {}
    for a in effort.get("attempts", []):
        stages[a["stage"]] = stages.get(a["stage"], 0) + a["iterations"]
    row.update(termination=effort.get("termination", "?"),
               converged=bool(effort.get("converged")),
               time_iterations=fastest.get("iterations", 0),
               time_s=float(fastest.get("solve_time_s", float("nan"))),
               iterations=effort.get("iterations", 0),
               effort_s=float(effort.get("solve_time_s", float("nan"))),
               cost=effort.get("cost"), stages=stages)
    margin = mtc.plan(binary, text, work, ["--time-margin", "%g" % (mtc.EFFORT_AT - 1)])
    row.update(margin_converged=bool(margin.get("converged")),
               margin_iterations=margin.get("iterations", 0),
               margin_s=float(margin.get("solve_time_s", float("nan"))),
               margin_cost=margin.get("cost", float("nan")))
    return row


def against_default(r):
    """How many rows' route via minimum time ends lower / the same (1e-6) / higher in cost."""
    lower = sum(1 for x in r if x["margin_cost"] < x["cost"] * (1 - 1e-6))
    higher = sum(1 for x in r if x["margin_cost"] > x["cost"] * (1 + 1e-6))
    return "%d / %d / %d" % (lower, len(r) - lower - higher, higher)


def route_summary(rows, cone, slow_only):
    r = [x for x in rows if x["cone"] == cone and "iterations" in x and x["converged"] and
         x["margin_converged"] and (not slow_only or x["iterations"] > SLOW)]
    if not r:
        return "| %s | %s | 0 | - | - | - | - |" % ("yes" if cone else "no",
                                                  "above %d" % SLOW if slow_only else "all")
    its = [x["iterations"] for x in r]
    m_its = [x["margin_iterations"] for x in r]
    secs = [x["effort_s"] for x in r]
    m_secs = [x["margin_s"] for x in r]
    return "| %s | %s | %d | %d / %d | %d / %d | %.1f / %.1f | %s |" % (
        "yes" if cone else "no", "above %d" % SLOW if slow_only else "all", len(r),
        statistics.median(its), statistics.median(m_its), max(its), max(m_its),
        1e3 * statistics.median(secs), 1e3 * statistics.median(m_secs), against_default(r))


def summary(rows, cone):
    r = [x for x in rows if x["cone"] == cone and "iterations" in x]
    its = [x["iterations"] for x in r]
    secs = [x["effort_s"] for x in r]
    via_time = sum(1 for x in r if "minimum_time_solve" in x["stages"])
    slower = sum(1 for x in r if x["effort_s"] > x["time_s"])
    return ("| %s | %d | %d | %d / %d / %d | %.1f / %.0f | %d | %d | %d |" % (
        "yes" if cone else "no", len(r), sum(1 for x in r if x["converged"]),
        statistics.median(its), mtc.quantile(its, 0.9), max(its), 1e3 * statistics.median(secs),
        1e3 * max(secs), sum(1 for i in its if i > SLOW), via_time, slower))


def same_cost(a, b):
    """Whether two figures agree to 1e-9 relative (a missing one agrees with nothing)."""
    if a is None or b is None:
        return False
    return abs(a - b) <= 1e-9 * max(abs(a), abs(b))


def figure(cost):
    return "-" if cost is None else "%.10g" % cost


def before_after_summary(rows, cone):
    """One line of the before/after table: the rows where both converged at the same T*."""
    r = [x for x in rows if x["cone"] == cone and "iterations" in x and "iterations" in x["before"]]
    same_t = [x for x in r if same_cost(x["T"], x["before"]["T"])]
    its_b = sum(x["before"]["iterations"] for x in same_t)
    its_a = sum(x["iterations"] for x in same_t)
    above_b = sum(1 for x in same_t if x["before"]["iterations"] > SLOW)
    above_a = sum(1 for x in same_t if x["iterations"] > SLOW)
    both = [x for x in same_t if x["cost"] is not None and x["before"]["cost"] is not None]
    lower = sum(1 for x in both if x["cost"] < x["before"]["cost"] and
                not same_cost(x["cost"], x["before"]["cost"]))
    higher = sum(1 for x in both if x["cost"] > x["before"]["cost"] and
                 not same_cost(x["cost"], x["before"]["cost"]))
    terms = sum(1 for x in same_t if x["termination"] != x["before"]["termination"])
    more = sum(1 for x in same_t if x["iterations"] > x["before"]["iterations"])
    fewer = sum(1 for x in same_t if x["iterations"] < x["before"]["iterations"])
    via_b = sum(1 for x in same_t if "minimum_time_solve" in x["before"]["stages"])
    via_a = sum(1 for x in same_t if "minimum_time_solve" in x["stages"])
    return "| %s | %d | %d | %d -> %d | %d -> %d | %d / %d | %d / %d / %d | %d | %d -> %d |" % (
        "yes" if cone else "no", len(r), len(r) - len(same_t), its_b, its_a, above_b, above_a,
        fewer, more, lower, len(same_t) - lower - higher, higher, terms, via_b, via_a)


def before_after_section(rows):
    out = ["## Before and after (--before-plan-maneuver)\n",
           "Each request planned by both builds (minimum time, then minimum effort at 1.05 T* "
           "from each build's own T*), compared where the two T* agree (1e-9 relative).\n",
           "| cone | requests | T* differs | iterations (sum) before -> after | above %d before "
           "-> after | fewer / more iterations | cost lower / same / higher | termination "
           "changed | through the minimum-time phase before -> after |" % SLOW,
           "|---|---|---|---|---|---|---|---|---|"]
    out += [before_after_summary(rows, cone) for cone in (False, True)]
    changed = [x for x in rows if "iterations" in x and "iterations" in x.get("before", {}) and
               (not same_cost(x["cost"], x["before"]["cost"]) or
                x["termination"] != x["before"]["termination"] or
                x["iterations"] > x["before"]["iterations"])]
    if changed:
        out += ["", "Requests whose cost or termination changed, or that took more iterations:\n",
                "| seed | # | cone | cost before -> after | termination before -> after | "
                "iterations before -> after |", "|---|---|---|---|---|---|"]
        out += ["| %d | %d | %s | %s -> %s | %s -> %s | %d -> %d |" % (
            x["seed"], x["index"], "yes" if x["cone"] else "no", figure(x["before"]["cost"]),
            figure(x["cost"]), x["before"]["termination"], x["termination"], x["before"]["iterations"],
            x["iterations"]) for x in changed]
    out.append("")
    return out


def render(args, rows, wall, load):
    out = []
    w = out.append
    w("# Minimum effort just above T*: what a keep-out cone costs\n")
    w("Generated by `/usr/bin/python3 scripts/near_minimum_time_cones.py --plan-maneuver "
      "PLAN_MANEUVER%s --seeds %s --count %d` on %s UTC, %.0f s wall, load average at the start %s "
      "(2 shared cores); do not edit by hand.\n" % (
          " --before-plan-maneuver BEFORE" if args.before_plan_maneuver else "",
          args.seeds, args.count, datetime.datetime.utcnow().strftime("%Y-%m-%d %H:%M"), wall,
          load))
    w("The requests of `scripts/minimum_time_cost.py` (rest-to-rest slews of physical bodies under "
      "per-axis torque bounds of 0.005-0.05 x the largest moment, one keep-out cone across the "
      "eigenaxis path; second_order, N = %d), seeds %s, %d each, without and with the cone. Each "
      "is planned for minimum time; where that converged, the same request is planned for "
      "minimum effort at %.2f T* with the defaults (a user who does not know T*). One run each: "
      "iterations are deterministic, times one sample on a shared machine.\n" % (
          args.steps, args.seeds, args.count, mtc.EFFORT_AT))
    w("| cone | requests | converged | iterations: median / p90 / max | time [ms]: median / max "
      "| above %d iterations | through the minimum-time phase | slower than minimum time |" % SLOW)
    w("|---|---|---|---|---|---|---|---|")
    w(summary(rows, False))
    w(summary(rows, True))
    w("")
    w("The route via minimum time (`--time-margin 0.05`) on the same requests, where both "
      "converged: the default's figure / the route's (its iterations and time include the "
      "minimum-time solve).\n")
    w("| cone | requests | count | iterations: median | max | time [ms]: median | route's cost "
      "against the default's: lower / same / higher |")
    w("|---|---|---|---|---|---|---|")
    for cone in (False, True):
        for slow_only in (False, True):
            w(route_summary(rows, cone, slow_only))
    w("")
    totals = {}
    for x in rows:
        for stage, n in x.get("stages", {}).items():
            key = (x["cone"], stage)
            totals[key] = totals.get(key, 0) + n
    w("Where the minimum-effort iterations go, summed over the requests (the trail's stages):\n")
    w("| cone | stage | iterations |")
    w("|---|---|---|")
    for (cone, stage), n in sorted(totals.items(), key=lambda kv: (kv[0][0], -kv[1])):
        w("| %s | %s | %d |" % ("yes" if cone else "no", stage, n))
    w("")
    if args.before_plan_maneuver:
        out.extend(before_after_section(rows))
    w("<details><summary>Every request above %d iterations</summary>\n" % SLOW)
    w("| seed | # | cone | T* [s] | minimum time: iterations, time [s] | minimum effort: "
      "termination, iterations, time [s] | cost | stages | route via minimum time: iterations, "
      "time [s], cost |")
    w("|---|---|---|---|---|---|---|---|---|")
    for x in rows:
        if x.get("iterations", 0) <= SLOW:
            continue
        w("| %d | %d | %s | %.6g | %d, %.3f | %s, %d, %.3f | %.10g | %s |" % (
            x["seed"], x["index"], "yes" if x["cone"] else "no", x["T"], x["time_iterations"],
            x["time_s"], x["termination"], x["iterations"], x["effort_s"], x["cost"],
            ", ".join("%s %d" % kv for kv in x["stages"].items())))
    w("\n</details>\n")
    return "\n".join(out)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--plan-maneuver", required=True)
    ap.add_argument("--seeds", default="6464,7474,9191")
    ap.add_argument("--count", type=int, default=40)
    ap.add_argument("--steps", type=int, default=128)
    ap.add_argument("--before-plan-maneuver", default=None)
    ap.add_argument("--out", default=None)
    ap.add_argument("--work", default="/tmp/near_minimum_time_cones")
    args = ap.parse_args()
    os.makedirs(args.work, exist_ok=True)
    load = load_average()
    start = time.time()
    rows = []
    for seed in (int(s) for s in args.seeds.split(",")):
        rng = np.random.default_rng(seed)
        for case in [mtc.draw_request(rng, i) for i in range(args.count)]:
            for cone in (False, True):
                row = measure(args.plan_maneuver, case, cone, args.steps, args.work)
                row["seed"] = seed
                if args.before_plan_maneuver:
                    row["before"] = measure(args.before_plan_maneuver, case, cone, args.steps,
                                            args.work)
                rows.append(row)
                print("seed %d request %d cone %s: %s %s iterations" % (
                    seed, case["index"], cone, row["termination"], row.get("iterations", "-")),
                    file=sys.stderr, flush=True)
    write_page(render(args, rows, time.time() - start, load), args.out)


if __name__ == "__main__":
    main()
