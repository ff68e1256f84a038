#!/usr/bin/env python3
"""plan_maneuver --summary on scene files from two builds side by side: the same optimum (cost,
and T* for minimum time) to a relative tolerance, the same verdict, and the solve times as ratios
AFTER / BEFORE pair by pair (each run BEFORE then AFTER, `repeats` times in turn, so both see the
same load). Prints a Markdown table. A smaller companion of scripts/before_after, for the scenes
the benchmark scripts do not run (minimum time, cones under minimum time).

  scripts/scenes_side_by_side.py --before BIN --after BIN [--repeats R] [--steps N]...
                                 SCENE.yaml ...
BIN is a plan_maneuver binary; --steps adds runs at other N (default: the scene's own).
"""
import argparse
import json
import os
import statistics
import subprocess
import tempfile

REL_TOL = 1e-9


def run(binary, scene, steps):
    with tempfile.TemporaryDirectory() as tmp:
        out = os.path.join(tmp, "summary.json")
        args = [binary, scene, "--summary", out] + (["--steps", str(steps)] if steps else [])
        subprocess.run(args, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        if not os.path.exists(out):
            return None
        with open(out) as f:
            return json.load(f)


def relative(a, b):
    if a is None or b is None:
        return float("nan")
    return abs(a - b) / max(abs(b), 1e-300)


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--before", required=True)
    ap.add_argument("--after", required=True)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--steps", type=int, action="append",
                    help="N to run at (repeatable; default: the scene's own)")
    ap.add_argument("scenes", nargs="+")
    a = ap.parse_args()
    a.steps = a.steps or [0]
    print("| scene | N | verdict before → after | cost before | rel. cost diff | T* before |"
          " rel. T* diff | iterations before → after | time ratio after/before |")
    print("|---|---|---|---|---|---|---|---|---|")
    all_ratios = []
    worst = 0.0
    for scene in a.scenes:
        for steps in a.steps:
            pairs = [(run(a.before, scene, steps), run(a.after, scene, steps))
                     for _ in range(a.repeats)]
            b, f = pairs[0]
            if b is None or f is None:
                print("| %s | %s | no summary | | | | | | |" % (os.path.basename(scene), steps))
                continue
            ratios = [y["solve_time_s"] / x["solve_time_s"] for x, y in pairs
                      if x and y and x["solve_time_s"] > 0]
            all_ratios += ratios
            dc = relative(f["cost"], b["cost"])
            dt = relative(f["minimum_duration"], b["minimum_duration"]) \
                if b["minimum_duration"] else 0.0
            worst = max(worst, dc, dt)
            verdict = b["termination"] if b["termination"] == f["termination"] else \
                "%s → %s" % (b["termination"], f["termination"])
            iters = str(b["iterations"]) if b["iterations"] == f["iterations"] else \
                "%d → %d" % (b["iterations"], f["iterations"])
            print("| %s | %d | %s | %.12g | %.1e%s | %s | %s | %s | %.2f (%.2f–%.2f) |" % (
                os.path.basename(scene), b["steps"], verdict, b["cost"], dc,
                " (same)" if dc <= REL_TOL else " (DIFFERENT)",
                "%.12g" % b["minimum_duration"] if b["minimum_duration"] else "–",
                "%.1e" % dt if b["minimum_duration"] else "–", iters,
                statistics.median(ratios), min(ratios), max(ratios)))
    if all_ratios:
        print("\nAll time ratios together: median %.2f (%.2f–%.2f); largest relative difference"
              " of an optimum %.1e (tolerance %.0e)." % (
                  statistics.median(all_ratios), min(all_ratios), max(all_ratios), worst, REL_TOL))


if __name__ == "__main__":
    main()
