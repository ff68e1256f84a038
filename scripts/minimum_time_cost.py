#!/usr/bin/env python3
"""What minimum time costs against one minimum-effort solve, on seeded random requests.

Draws rest-to-rest slews of physical bodies (keep_out_grids.py's suite: random principal axes,
rotations up to a half turn, one keep-out cone across the eigenaxis path with both ends' boresights
outside it) under per-axis torque bounds, and plans each with plan_maneuver's minimum time
(second_order, N = 128 unless told) without the cone and with it. For each answer that converged:
one minimum-effort solve of the same request at 1.05 T* (the interior point from its own start),
and the ratio of the two solve_time_s (each the median of --repeats runs, the two run in turn).

Called by scripts/minimum_time_cost; usable alone:
  minimum_time_cost.py --plan-maneuver BIN [--count K] [--seed S] [--steps N] [--repeats R]
                       [--out FILE.md] [--work DIR]
"""
import argparse
import datetime
import json
import math
import os
import statistics
import subprocess
import sys
import time

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from study_page import load_average, write_page  # noqa: E402

import keep_out_grids  # noqa: E402
vec = keep_out_grids.vec

TARGET = 10.0  # the target: minimum time at most 10x one minimum-effort solve at 1.05 T*
EFFORT_AT = 1.05  # the minimum-effort solve's duration over T*
MIN_BOUND, MAX_BOUND = 0.005, 0.05  # the torque bound per axis over the largest moment [1/s^2]


def draw_request(rng, index):
    """keep_out_grids.py's slew and cone, and per-axis torque bounds a_i = f_i * J_max."""
    case = keep_out_grids.draw_case(rng, index)
    largest = float(np.max(np.linalg.eigvalsh(case["inertia"])))
    case["max_torque"] = largest * rng.uniform(MIN_BOUND, MAX_BOUND, size=3)
    return case


def scene_text(c, steps, cone):
    J = c["inertia"]
    text = (
        "# minimum_time_cost.py request %d (generated)\n" % c["index"] +
        "inertia: [%s, %s, %s]\n" % (vec(J[0]), vec(J[1]), vec(J[2])) +
        "steps: %d\nscheme: second_order\nobjective: minimum_time\n" % steps +
        "initial: {attitude: {quaternion: %s}, angular_velocity: [0, 0, 0]}\n" % vec(c["q0"]) +
        "final: {attitude: {quaternion: %s}, angular_velocity: [0, 0, 0]}\n" % vec(c["qN"]) +
        "effects: [{actuator_limits: {max_torque: %s}}]\n" % vec(c["max_torque"]))
    if cone:
        text += ("constraints:\n  - keep_out: {body_axis: %s, world_direction: %s, "
                 "half_angle: %.17g}\n" % (vec(c["body_axis"]), vec(c["direction"]),
                                           c["half_angle"]))
    return text


def as_effort(text, duration):
    return text.replace("objective: minimum_time", "objective: minimum_effort") + \
        "duration: %.17g\n" % duration


def request_files(text, work):
    """The request written to WORK/request.yaml, and its summary's path (cleared)."""
    scene = os.path.join(work, "request.yaml")
    summary = os.path.join(work, "summary.json")
    with open(scene, "w") as f:
        f.write(text)
    if os.path.exists(summary):
        os.remove(summary)
    return scene, summary


def plan(binary, text, work, flags=()):
    scene, summary = request_files(text, work)
    subprocess.run([binary, scene, "--summary", summary] + list(flags), stdout=subprocess.DEVNULL,
                   stderr=subprocess.DEVNULL, timeout=900)
    try:
        with open(summary) as f:
            return json.load(f)
    except (OSError, ValueError):
        return {"converged": False, "termination": "no summary"}


def measure(args, c, cone):
    """T*, the minimum-time and minimum-effort solve times (medians, run in turn), iterations."""
    text = scene_text(c, args.steps, cone)
    first = plan(args.plan_maneuver, text, args.work)
    attempts = first.get("attempts", [])
    row = {"cone": cone, "termination": first.get("termination", "?"),
           "T": first.get("duration", math.nan) if first.get("converged") else math.nan,
           "iterations": first.get("iterations", 0),
           # where the iterations go: the starts on coarser grids, and the requested grid
           "coarse": sum(a["iterations"] for a in attempts if a["steps"] < args.steps),
           "starts": sum(1 for a in attempts if a["steps"] < args.steps),
           "fine": sum(a["iterations"] for a in attempts if a["steps"] >= args.steps)}
    if not first.get("converged"):
        return row
    effort_text = as_effort(text, EFFORT_AT * row["T"])
    times = {"time": [float(first["solve_time_s"])], "one": [], "effort": []}
    effort = None
    for r in range(args.repeats):
        one = plan(args.plan_maneuver, text, args.work, ["--threads", "1"])
        times["one"].append(float(one.get("solve_time_s", math.nan)))
        effort = plan(args.plan_maneuver, effort_text, args.work)
        times["effort"].append(float(effort.get("solve_time_s", math.nan)))
        if r + 1 < args.repeats:
            times["time"].append(float(plan(args.plan_maneuver, text, args.work)["solve_time_s"]))
    row.update(time=statistics.median(times["time"]), one=statistics.median(times["one"]),
               effort=statistics.median(times["effort"]),
               effort_converged=bool(effort.get("converged")),
               effort_iterations=effort.get("iterations", 0))
    row["ratio"] = row["time"] / row["effort"]
    row["ratio_one"] = row["one"] / row["effort"]
    return row


def quantile(values, q):
    values = sorted(values)
    return values[min(len(values) - 1, int(math.ceil(q * len(values))) - 1)] if values else math.nan


def summary_line(rows, label, key="ratio"):
    ratios = [r[key] for r in rows if key in r]
    within = sum(1 for x in ratios if x <= TARGET)
    return ("| %s | %d of %d | %.2f | %.2f | %.2f | %d of %d |" %
            (label, len(ratios), len(rows), statistics.median(ratios) if ratios else math.nan,
             quantile(ratios, 0.9), max(ratios) if ratios else math.nan, within, len(ratios)))


def render(args, cases, rows, wall, load):
    out = []
    w = out.append
    w("# What minimum time costs: against one minimum-effort solve, on random requests\n")
    w("Generated by `scripts/minimum_time_cost --count %d --seed %d` (scripts/minimum_time_cost.py)"
      " on %s UTC, %.0f s wall, load average at the start %s (2 shared cores); do not edit by hand."
      "%s\n" % (args.count, args.seed, datetime.datetime.utcnow().strftime("%Y-%m-%d %H:%M"), wall,
               load, " Build: %s." % args.build_label if args.build_label else ""))
    w("%d seeded rest-to-rest slews (scripts/keep_out_grids.py's suite: physical inertias, random "
      "principal axes, rotations of 0.5 to pi - 0.02 rad, a keep-out cone across the eigenaxis "
      "path with both ends' boresights outside it) under per-axis torque bounds |tau_i| <= a_i, "
      "a_i uniform in [%g, %g] x the largest moment; scheme second_order, N = %d. Each is planned "
      "for minimum time (`objective: minimum_time`, the defaults) without the cone and with it; "
      "where it converged, the same request is planned once for minimum effort at %.2f T* (the "
      "interior point from its own start). Times are `solve_time_s`, the median of %d runs, the "
      "three run in turn: minimum time with the defaults (its starts on the machine's cores, "
      "`SolverOptions::threads`), minimum time on one thread (`--threads 1`: the same answer), "
      "minimum effort (one thread: one solve). Issue 40's target: minimum time at most %gx one "
      "minimum-effort solve.\n" %
      (args.count, MIN_BOUND, MAX_BOUND, args.steps, EFFORT_AT, args.repeats, TARGET))
    w("| requests | converged | median ratio | p90 | max | within %gx |" % TARGET)
    w("|---|---|---|---|---|---|")
    w(summary_line([r for r in rows if not r["cone"]], "no cone"))
    w(summary_line([r for r in rows if r["cone"]], "keep-out cone"))
    w(summary_line([r for r in rows if not r["cone"]], "no cone, one thread", "ratio_one"))
    w(summary_line([r for r in rows if r["cone"]], "keep-out cone, one thread", "ratio_one"))
    w("")
    coarse = sum(r["coarse"] for r in rows)
    total = sum(r["coarse"] + r["fine"] for r in rows)
    w("Where minimum time's iterations go (all requests): %d of %d (%.0f %%) in its solves on "
      "coarser grids (the starts: the eigenaxis slew, the excursions, the classes; %.1f solves a "
      "request on average), the rest on N = %d (the refinement from the best coarse answer, and "
      "any solve there).\n" % (coarse, total, 100.0 * coarse / max(total, 1),
                                sum(r["starts"] for r in rows) / max(len(rows), 1), args.steps))
    w("| # | θ [rad] | cone | minimum time | T* [s] | iterations (coarse solves / on N) | "
      "time [s] | one thread [s] | minimum effort at 1.05 T* | iterations | time [s] | ratio | "
      "ratio, one thread |")
    w("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        c = cases[r["index"]]
        if "ratio" not in r:
            w("| %d | %.3f | %s | %s | | %d (%d in %d / %d) | | | | | | | |" %
              (r["index"], c["theta"], "yes" if r["cone"] else "no", r["termination"],
               r["iterations"], r["coarse"], r["starts"], r["fine"]))
            continue
        bold = lambda x: ("**%.2f**" if x > TARGET else "%.2f") % x  # noqa: E731
        w("| %d | %.3f | %s | %s | %.6g | %d (%d in %d / %d) | %.4g | %.4g | %s | %d | %.4g | %s "
          "| %s |" % (r["index"], c["theta"], "yes" if r["cone"] else "no", r["termination"],
                      r["T"], r["iterations"], r["coarse"], r["starts"], r["fine"], r["time"],
                      r["one"], "converged" if r["effort_converged"] else "not converged",
                      r["effort_iterations"], r["effort"], bold(r["ratio"]), bold(r["ratio_one"])))
    return "\n".join(out) + "\n"


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--plan-maneuver", required=True)
    ap.add_argument("--count", type=int, default=20)
    ap.add_argument("--seed", type=int, default=4949)
    ap.add_argument("--steps", type=int, default=128)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--only", type=int, default=None)
    ap.add_argument("--build-label", default=None, help="the build's name, said in the page")
    ap.add_argument("--out", default=None)
    ap.add_argument("--work", default="/tmp/minimum_time_cost")
    args = ap.parse_args()
    os.makedirs(args.work, exist_ok=True)
    rng = np.random.default_rng(args.seed)
    cases = [draw_request(rng, i) for i in range(args.count)]
    chosen = [cases[args.only]] if args.only is not None else cases
    load = load_average()
    start = time.time()
    rows = []
    for c in chosen:
        for cone in (False, True):
            row = measure(args, c, cone)
            row["index"] = c["index"]
            rows.append(row)
            print("request %d cone %s: %s T* %.6g ratio %s" %
                  (c["index"], cone, row["termination"], row["T"], row.get("ratio", "-")),
                  flush=True)
    page = render(args, cases, rows, time.time() - start, load)
    write_page(page, args.out)


if __name__ == "__main__":
    main()
