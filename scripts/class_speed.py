#!/usr/bin/env python3
"""Speed with the class enumeration: ours against IPOPT on the same discrete problem, side by side.

Draws two seeded suites of physical problems (inertia J_i = s_j + s_k, scale 0.1-100 kg m^2, random
principal axes and end attitudes; scripts/extremal_classes.py's generator):
  - rest: rest to rest, T log-uniform in 1-60 s, N = 128;
  - spinning: boundary rates up to 5 rad/s (each end at rest with probability 0.1), T log-uniform
    in 1-25 s, N = 256 (h |Omega| < 0.5 rad at the ends).
For each scene, in one run and in turn: ours with this build's library and with the library before
the change (`benchmark_solvers --solver newton --in-process R`, LD_LIBRARY_PATH picks the library:
the median of the warm solves 2..R in one process), and IPOPT once per scene (`benchmark_solvers
--solver ipopt --in-process R`: exact Hessian, tol 1e-12, from the geodesic). The speed of a
build on a scene is IPOPT's time over ours. Then the seed request (scenes/rest_to_rest.yaml at
N = 128, `benchmark_solvers --solver newton`'s own problem) R2 times per build, in turn.

  class_speed.py --benchmark BIN --before-lib DIR [--before-benchmark BIN0] [--count K]
                 [--seed S] [--repeats R] [--seed-repeats R2] [--out FILE.md] [--work DIR]

--before-benchmark: the benchmark built with the library before the change, where the change
altered the public types the binary is compiled with (default: the same binary for both).
"""
import argparse
import datetime
import json
import math
import os
import statistics
import subprocess
import sys

import numpy as np

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import extremal_classes as ec  # noqa: E402  (the suite's generator)

SUITES = (("rest", 128), ("spinning", 256))


def draw_scene(seed, kind, index, steps):
    rng = np.random.default_rng([seed, index, 0 if kind == "rest" else 1])
    c = ec.draw_case(rng, index)
    if kind == "rest":
        c["w0"] = np.zeros(3)
        c["wN"] = np.zeros(3)
        c["T"] = math.exp(rng.uniform(math.log(1.0), math.log(60.0)))
    return ec.scene_text(c).replace("steps: %d" % ec.STEPS, "steps: %d" % steps)


def run(binary, args, lib=None):
    env = dict(os.environ)
    if lib:
        env["LD_LIBRARY_PATH"] = lib
    out = subprocess.run([binary] + args, capture_output=True, text=True, env=env, timeout=900).stdout
    for line in out.splitlines():
        if line.startswith("{"):
            return json.loads(line)
    return None


STATISTIC = "warm_time_s"  # or "warm_min_time_s" (render sets it for each table)


def timed(m, statistic=None):
    """The warm median (or least, `statistic`) if measured, else the one solve's time."""
    if not m:
        return math.nan
    key = statistic or STATISTIC
    return m[key] if m.get(key, 0) > 0 else m["time_s"]


def quantiles(speeds):
    s = sorted(x for x in speeds if math.isfinite(x))
    if not s:
        return math.nan, math.nan, math.nan
    p10 = s[max(0, int(math.floor(0.1 * (len(s) - 1))))]
    return statistics.median(s), p10, s[0]


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--benchmark", required=True, help="benchmark_solvers built with IPOPT")
    ap.add_argument("--before-lib", required=True, help="directory of the library before the change")
    ap.add_argument("--before-benchmark", default="",
                    help="benchmark_solvers built against the library before (default: --benchmark)")
    ap.add_argument("--count", type=int, default=30)
    ap.add_argument("--seed", type=int, default=5252)
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--seed-repeats", type=int, default=41)
    ap.add_argument("--out", default="")
    ap.add_argument("--work", default="/tmp/class_speed")
    args = ap.parse_args()
    before_benchmark = args.before_benchmark or args.benchmark
    os.makedirs(args.work, exist_ok=True)
    started = datetime.datetime.now(datetime.timezone.utc)
    load0 = os.getloadavg()
    rows = []
    for kind, steps in SUITES:
        for i in range(args.count):
            scene = os.path.join(args.work, "%s_%03d.yaml" % (kind, i))
            with open(scene, "w") as f:
                f.write(draw_scene(args.seed, kind, i, steps))
            common = ["--scene", scene, "--in-process", str(args.repeats), "--time-budget", "120"]
            after = run(args.benchmark, ["--solver", "newton"] + common)
            before = run(before_benchmark, ["--solver", "newton"] + common, args.before_lib)
            ipopt = run(args.benchmark, ["--solver", "ipopt"] + common)
            row = {"kind": kind, "i": i, "after": after, "before": before, "ipopt": ipopt}
            rows.append(row)
            print("%s %2d: ours %.4g s (before %.4g s), IPOPT %.4g s%s" % (
                kind, i, timed(after), timed(before), timed(ipopt),
                "" if ipopt and ipopt["converged"] else " (IPOPT failed)"), file=sys.stderr)
    seed = {"after": [], "before": []}
    for _ in range(args.seed_repeats):
        for build, binary, lib in (("after", args.benchmark, None),
                                   ("before", before_benchmark, args.before_lib)):
            m = run(binary, ["--solver", "newton", "--in-process", "6"], lib)
            seed[build].append(m)
            seed[build + "_iterations"] = m["iterations"] if m else None
    ipopt_seed = run(args.benchmark, ["--solver", "ipopt", "--in-process", str(args.repeats)])
    report = render(rows, seed, ipopt_seed, args, started, load0, os.getloadavg())
    if args.out:
        with open(args.out, "w") as f:
            f.write(report)
    else:
        sys.stdout.write(report)


def speeds(rows, kind, build):
    out = []
    for r in rows:
        if r["kind"] != kind or not r["ipopt"] or not r["ipopt"]["converged"] or not r[build]:
            continue
        out.append(timed(r["ipopt"]) / timed(r[build]))
    return out


def same_answers(rows, kind):
    n = same = 0
    for r in rows:
        if r["kind"] != kind or not r["after"] or not r["before"]:
            continue
        n += 1
        a, b = r["after"], r["before"]
        same += a["cost"] == b["cost"]
    return same, n


def not_costlier(rows, kind, build):
    n = ok = 0
    for r in rows:
        if r["kind"] != kind or not r["ipopt"] or not r["ipopt"]["converged"] or not r[build]:
            continue
        n += 1
        ok += r[build]["converged"] and r[build]["cost"] <= r["ipopt"]["cost"] * (1 + 1e-8)
    return ok, n


def render(rows, seed, ipopt_seed, args, started, load0, load1):
    L = []
    L.append("# Speed with the class enumeration: ours against IPOPT, side by side\n")
    L.append("Generated by `/usr/bin/python3 scripts/class_speed.py --benchmark BENCHMARK_SOLVERS "
             "--before-lib DIR%s --count %d --seed %d --repeats %d --seed-repeats %d` on %s "
             "(load average %.1f at the start, %.1f at the end, 2 cores shared with other builds); "
             "do not edit by hand. `before` is the library of main before the change "
             "(LD_LIBRARY_PATH), `after` this build's; both run the same binary (or, with "
             "--before-benchmark, each its own build), in turn on each "
             "scene. Times are the median and the least of the warm in-process solves 2..%d "
             "(`benchmark_solvers --in-process %d`); speed = IPOPT's time / ours on the same "
             "scene (IPOPT from the geodesic, exact Hessian, tol 1e-12; scenes where IPOPT did "
             "not converge are left out); ours runs on the machine's cores (SolverOptions::threads "
             "0), IPOPT on one. \"p10\" is the slow tail (9 in 10 scenes are faster). On a loaded "
             "machine the least of the runs is the better estimate of an idle machine's time.\n"
             % (" --before-benchmark BENCHMARK_BEFORE" if args.before_benchmark else "",
                args.count, args.seed, args.repeats, args.seed_repeats,
                started.strftime("%Y-%m-%d %H:%M UTC"), load0[0], load1[0], args.repeats,
                args.repeats))
    global STATISTIC
    L.append("| suite | times | scenes | speed before: median / p10 / worst | speed after: "
             "median / p10 / worst | same answer (cost) | ours ≤ IPOPT's cost (1e-8) after |")
    L.append("|---|---|---|---|---|---|---|")
    for kind, steps in SUITES:
        for STATISTIC, name in (("warm_time_s", "median of runs"), ("warm_min_time_s",
                                                                    "least of runs")):
            b = quantiles(speeds(rows, kind, "before"))
            a = quantiles(speeds(rows, kind, "after"))
            same, n = same_answers(rows, kind)
            ok, m = not_costlier(rows, kind, "after")
            L.append("| %s (N = %d) | %s | %d | %.1fx / %.1fx / %.2fx | %.1fx / %.1fx / %.2fx | "
                     "%d / %d | %d / %d |" % (kind, steps, name, len(speeds(rows, kind, "after")),
                                              *b, *a, same, n, ok, m))
    STATISTIC = "warm_time_s"
    L.append("")
    figures = {}
    for build in ("after", "before"):
        ms = [1e3 * timed(m, "warm_min_time_s") for m in seed[build] if m]
        md = [1e3 * timed(m) for m in seed[build] if m]
        figures[build] = (statistics.median(md), min(ms))
    ip_md, ip_min = 1e3 * timed(ipopt_seed), 1e3 * timed(ipopt_seed, "warm_min_time_s")
    L.append("The seed request (scenes/rest_to_rest.yaml, N = 128; %d processes per build, in "
             "turn, each 5 warm solves): **after %.2f ms** median of the processes' medians, "
             "%.2f ms least (%s iterations); **before %.2f ms**, %.2f ms least (%s iterations). "
             "IPOPT %.2f ms median, %.2f ms least (%s iterations): %.1fx after and %.1fx before "
             "by the medians, %.1fx and %.1fx by the least times.\n" % (
                 args.seed_repeats, *figures["after"], seed["after_iterations"],
                 *figures["before"], seed["before_iterations"], ip_md, ip_min,
                 ipopt_seed["iterations"] if ipopt_seed else "-", ip_md / figures["after"][0],
                 ip_md / figures["before"][0], ip_min / figures["after"][1],
                 ip_min / figures["before"][1]))
    L.append("<details><summary>Every scene</summary>\n")
    L.append("| suite | # | ours after [ms] | it | ours before [ms] | it | IPOPT [ms] | it | "
             "cost after | cost IPOPT |")
    L.append("|---|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        a, b, p = r["after"] or {}, r["before"] or {}, r["ipopt"] or {}
        L.append("| %s | %d | %.3g | %s | %.3g | %s | %.3g | %s | %.10g | %s |" % (
            r["kind"], r["i"], 1e3 * timed(a or None), a.get("iterations", "-"),
            1e3 * timed(b or None), b.get("iterations", "-"), 1e3 * timed(p or None),
            p.get("iterations", "-"), a.get("cost", math.nan),
            ("%.10g" % p["cost"]) if p.get("converged") else "failed"))
    L.append("\n</details>\n")
    return "\n".join(L)


if __name__ == "__main__":
    main()
