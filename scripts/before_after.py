#!/usr/bin/env python3
"""Runs the problems of the four benchmark scripts on two builds side by side and writes the
before/after table (docs/results/refactor_before_after.md). Run through scripts/before_after.

The problems are those of scripts/benchmark (rest_to_rest at N = 32..8192 on both schemes,
slew_up, the scaling runs), scripts/constraints_benchmark (every constrained scene, torque limits
at N = 64..2048, SLSQP), scripts/robustness --random (the seeded random suite, case by case),
scripts/accuracy (accuracy_study) and minimum time: `plan_maneuver --objective minimum_time` on
the min_time_* scenes x {paper, second_order} x N in {32, 64, 128} (T*, termination,
iterations), the bounded minimum effort (objective minimum_effort) of each at 1.02 T* (T* the
BEFORE build's), and `benchmark_solvers --solver free_time` (one free-time solve, paper) on
FREE_TIME_SCENES and the same N. Both builds read the same scene files (the BEFORE commit's: scene
keys are only ever extended). Every problem runs BEFORE then AFTER, `repeats` times in
turn, so both see the same load; times are each process's own solver time (the structured
`time_s` of benchmark_solvers, the whole process for accuracy_study), quoted as the median of
the pair-by-pair ratios AFTER / BEFORE.

Same optimum: |cost_after − cost_before| ≤ 1e-9 |cost_before| (minimum time: T* in place of the
cost). Same verdict: the same
`converged` (benchmark_solvers) or `termination` (random suite). Iterations are reported too.
"""
import argparse
import json
import math
import os
import statistics
import subprocess
import tempfile
import time

import yaml

REL_TOL = 1e-9  # optima equal to this relative tolerance count as the same
RANDOM_BUDGET_S = 60.0  # the random suite's time budget per case (as scripts/robustness)
# A case whose time reaches this fraction of the budget was stopped by the clock: what it did
# (iterations, which starts ran) depends on the machine's speed at that moment.
AT_BUDGET_FRACTION = 0.95
MIN_TIME_SCENES = ["min_time_betts", "min_time_bilimoria_wie", "min_time_keep_out",
                   "min_time_sphere"]
MIN_TIME_SCHEMES = ["paper", "second_order"]
MIN_TIME_STEPS = [32, 64, 128]
# benchmark_solvers --solver free_time starts from an excursion sized by the torque box: on
# min_time_sphere (a norm bound, no box) and min_time_keep_out (a pointing cone) it ends before
# any iteration (measured: not_converged, 0 iterations), so those compare nothing: no rows.
FREE_TIME_SCENES = ["min_time_betts", "min_time_bilimoria_wie"]
BOUNDED_FACTOR = 1.02  # the bounded minimum-effort rows plan at this multiple of T*


def cell(text):
    """Text for a Markdown table cell (a literal | would split the cell)."""
    return str(text).replace("|", "\\|")


def find_binary(ws, name):
    for sub in ("build/attitude_planner/bin", "devel/lib/attitude_planner"):
        path = os.path.join(ws, sub, name)
        if os.path.exists(path):
            return path
    raise SystemExit("before_after: %s not found in %s" % (name, ws))


def last_json_line(text):
    lines = [l for l in text.splitlines() if l.startswith("{")]
    return json.loads(lines[-1]) if lines else None


def run_benchmark(binary, args):
    out = subprocess.run([binary] + args, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL,
                         text=True)
    return last_json_line(out.stdout) or {"error": "no JSON line (exit %d)" % out.returncode}


def run_random_case(binary, count, case, budget):
    with tempfile.TemporaryDirectory() as tmp:
        out = subprocess.run([binary, "--random-suite", str(count), "--seed", "19", "--time-budget",
                              str(budget), "--cases", str(case), "--out",
                              os.path.join(tmp, "r.md")],
                             stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    return last_json_line(out.stderr) or {"error": "no JSON line (exit %d)" % out.returncode}


def run_plan(binary, scene, args):
    """plan_maneuver SCENE ARGS --summary: its JSON summary (time: solve_time_s)."""
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "s.json")
        out = subprocess.run([binary, scene] + args + ["--summary", path],
                             stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        try:
            with open(path) as f:
                summary = json.load(f)
        except (OSError, ValueError):
            return {"error": "no summary (exit %d)" % out.returncode}
    summary["time_s"] = summary.get("solve_time_s", 0.0)
    return summary


def scene_with(scene, tmp, name, **keys):
    """A copy of the scene file with some top-level keys replaced (scene keys never change)."""
    with open(scene) as f:
        data = yaml.safe_load(f)
    data.update(keys)
    path = os.path.join(tmp, name)
    with open(path, "w") as f:
        yaml.safe_dump(data, f)
    return path


def run_accuracy(binary, scenes, max_steps):
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "a.json")
        start = time.monotonic()
        subprocess.run([binary, path] + scenes + ["--max-steps", str(max_steps), "--repeats", "1"],
                       stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        wall = time.monotonic() - start
        with open(path) as f:
            return {"json": json.load(f), "time_s": wall}


def same_cost(a, b):
    if a is None or b is None:
        return a is None and b is None
    return abs(a - b) <= REL_TOL * max(abs(b), 1e-300) or (a == b)


def numeric_leaves(x, path=""):
    """(path, value) of every number in a JSON tree, times and load figures left out."""
    if isinstance(x, dict):
        for k, v in x.items():
            if "time" in k or k.startswith("load"):
                continue
            yield from numeric_leaves(v, path + "." + k)
    elif isinstance(x, list):
        for i, v in enumerate(x):
            yield from numeric_leaves(v, "%s[%d]" % (path, i))
    elif isinstance(x, bool) or isinstance(x, str) or x is None:
        yield path, x
    else:
        yield path, float(x)


def benchmark_cases(scenes, quick):
    rest = os.path.join(scenes, "rest_to_rest.yaml")
    slew = os.path.join(scenes, "slew_up.yaml")
    tl = os.path.join(scenes, "torque_limited.yaml")
    cases = []
    for n in ([32, 128, 1024] if quick else [32, 128, 1024, 8192]):
        cases.append(("benchmark", "rest_to_rest paper N=%d" % n,
                      ["--solver", "newton", "--scene", rest, "--steps", str(n), "--scheme", "paper"]))
        cases.append(("benchmark", "rest_to_rest variational N=%d" % n,
                      ["--solver", "newton", "--scene", rest, "--steps", str(n), "--scheme",
                       "variational"]))
    cases.append(("benchmark", "slew_up paper N=128",
                  ["--solver", "newton", "--scene", slew, "--steps", "128", "--scheme", "paper"]))
    cases.append(("benchmark", "rest_to_rest SLSQP N=32",
                  ["--solver", "slsqp", "--scene", rest, "--steps", "32", "--scheme", "paper"]))
    for n in ([10000] if quick else [10000, 100000]):
        for scheme in ("paper", "variational"):
            cases.append(("benchmark", "scaling %s N=%d" % (scheme, n),
                          ["--solver", "newton", "--scene", rest, "--steps", str(n), "--scheme",
                           scheme]))
    for n in ([64, 128, 512] if quick else [64, 128, 512, 2048]):
        cases.append(("constraints", "torque_limited N=%d" % n,
                      ["--solver", "newton", "--scene", tl, "--steps", str(n)]))
    cases.append(("constraints", "torque_limited SLSQP N=64",
                  ["--solver", "slsqp", "--scene", tl, "--steps", "64", "--time-budget", "60"]))
    for name in ["torque_norm_limited", "rate_limited", "sun_keep_out", "leo_slew_limited"]:
        cases.append(("constraints", "%s N=128" % name,
                      ["--solver", "newton", "--scene", os.path.join(scenes, name + ".yaml"),
                       "--steps", "128"]))
    return cases


def paired_runs(run_side, repeats):
    """BEFORE then AFTER, `repeats` times in turn: the first run of each and the time ratios."""
    runs = {"before": [], "after": []}
    for _ in range(repeats):
        for side in ("before", "after"):
            runs[side].append(run_side(side))
    ratios = [a["time_s"] / b["time_s"] for b, a in zip(runs["before"], runs["after"])
              if a.get("time_s") and b.get("time_s")]
    return runs["before"][0], runs["after"][0], ratios


def minimum_time_rows(args, plan, bench, tmp):
    """(source, problem, before, after, ratios, figure): the figure compared is T*
    (minimum_duration) or the cost; the verdict is `termination` (`status` of benchmark_solvers)."""
    rows = []
    for name in MIN_TIME_SCENES:
        scene = os.path.join(args.scenes, name + ".yaml")
        for scheme in MIN_TIME_SCHEMES:
            for n in MIN_TIME_STEPS:
                grid = ["--scheme", scheme, "--steps", str(n)]
                label = "%s %s N=%d" % (name, scheme, n)
                b, a, ratios = paired_runs(
                    lambda side: run_plan(plan[side], scene, ["--objective", "minimum_time"] + grid),
                    args.repeats)
                rows.append(("minimum_time", label, b, a, ratios, "minimum_duration"))
                print(json.dumps({"case": label, "ratios": ratios}), flush=True)
                t_star = b.get("minimum_duration")
                if b.get("termination") != "converged" or not t_star:
                    continue
                bounded = scene_with(scene, tmp, "%s_%s_%d.yaml" % (name, scheme, n),
                                     objective="minimum_effort", duration=BOUNDED_FACTOR * t_star)
                b, a, ratios = paired_runs(lambda side: run_plan(plan[side], bounded, grid),
                                           args.repeats)
                rows.append(("bounded_effort", "%s at %g T*" % (label, BOUNDED_FACTOR), b, a, ratios,
                             "cost"))
        for n in MIN_TIME_STEPS if name in FREE_TIME_SCENES else []:
            cmd = ["--solver", "free_time", "--scene", scene, "--steps", str(n)]
            b, a, ratios = paired_runs(lambda side: run_benchmark(bench[side], cmd), args.repeats)
            for run in (b, a):
                if "status" in run:
                    run["termination"] = run["status"]
            rows.append(("free_time", "%s paper N=%d" % (name, n), b, a, ratios,
                         "minimum_duration"))
    return rows


def ratio_text(ratios):
    if not ratios:
        return "—"
    return "%.2f (%.2f–%.2f)" % (statistics.median(ratios), min(ratios), max(ratios))


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--before-ws", required=True)
    ap.add_argument("--after-ws", required=True)
    ap.add_argument("--before-label", required=True)
    ap.add_argument("--after-label", required=True)
    ap.add_argument("--scenes", required=True, help="the scene files both builds read")
    ap.add_argument("--out", required=True)
    ap.add_argument("--command", required=True, help="the command line, for the page's header")
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--random", type=int, default=40, help="random-suite cases 0..COUNT-1")
    ap.add_argument("--accuracy-max-steps", type=int, default=1024)
    args = ap.parse_args()
    sides = {"before": args.before_ws, "after": args.after_ws}
    bench = {s: find_binary(ws, "benchmark_solvers") for s, ws in sides.items()}
    acc = {s: find_binary(ws, "accuracy_study") for s, ws in sides.items()}
    plan = {s: find_binary(ws, "plan_maneuver") for s, ws in sides.items()}
    started = time.time()
    load_start = "%.2f %.2f %.2f" % os.getloadavg()

    rows = []  # (group, label, before, after, ratios)
    for group, label, cmd in benchmark_cases(args.scenes, args.quick):
        runs = {"before": [], "after": []}
        for _ in range(args.repeats):
            for side in ("before", "after"):
                runs[side].append(run_benchmark(bench[side], cmd))
        ratios = [a["time_s"] / b["time_s"] for b, a in zip(runs["before"], runs["after"])
                  if "time_s" in a and "time_s" in b and b["time_s"] > 0]
        rows.append((group, label, runs["before"][0], runs["after"][0], ratios))
        print(json.dumps({"case": label, "ratios": ratios}), flush=True)

    with tempfile.TemporaryDirectory() as tmp:
        min_time = minimum_time_rows(args, plan, bench, tmp)

    random_rows = []
    for case in range(args.random):
        b = run_random_case(bench["before"], args.random, case, RANDOM_BUDGET_S)
        a = run_random_case(bench["after"], args.random, case, RANDOM_BUDGET_S)
        random_rows.append((case, b, a))
        print(json.dumps({"random": case, "before": b.get("termination"),
                          "after": a.get("termination")}), flush=True)

    scenes = [os.path.join(args.scenes, "rest_to_rest.yaml"),
              os.path.join(args.scenes, "slew_up.yaml")]
    acc_before = run_accuracy(acc["before"], scenes, args.accuracy_max_steps)
    acc_after = run_accuracy(acc["after"], scenes, args.accuracy_max_steps)

    write_page(args, rows, min_time, random_rows, acc_before, acc_after, load_start,
               time.time() - started)


def verdict_cell(b, a, key):
    vb, va = b.get(key), a.get(key)
    return ("%s" % vb) if vb == va else "**%s → %s**" % (vb, va)


def minimum_time_table(min_time, differ):
    L = ["## Minimum time: plan_maneuver and benchmark_solvers --solver free_time\n"]
    L.append("minimum_time: `plan_maneuver SCENE --objective minimum_time --scheme S --steps N`, "
             "figure T* (`minimum_duration`); bounded_effort: the same scene as objective "
             "minimum_effort at duration %g T* (T* BEFORE's), figure the cost; free_time: "
             "`benchmark_solvers --solver free_time --scene SCENE --steps N` (one free-time solve, "
             "paper; on %s), figure T*.\n" % (BOUNDED_FACTOR, ", ".join(FREE_TIME_SCENES)))
    L.append("| source | problem | figure before | relative difference | termination before → "
             "after | iterations before → after | time ratio after/before |")
    L.append("|---|---|---|---|---|---|---|")
    for source, label, b, a, ratios, key in min_time:
        if "error" in b or "error" in a:
            L.append("| %s | %s | error: %s / %s | | | | |" % (source, label, b.get("error", "ok"),
                                                                a.get("error", "ok")))
            differ.append(label)
            continue
        vb, va = b.get(key), a.get(key)
        rel = (abs(va - vb) / max(abs(vb), 1e-300)) if vb is not None and va is not None \
            else math.nan
        if not (same_cost(va, vb) and b.get("termination") == a.get("termination")
                and b.get("iterations") == a.get("iterations")):
            differ.append(label)
        L.append("| %s | %s | %s | %s | %s | %s | %s |" % (
            source, cell(label), "%.12g" % vb if vb is not None else "—",
            "%.1e" % rel if not rel <= REL_TOL else "%.1e (same)" % rel,
            verdict_cell(b, a, "termination"),
            "%s" % b.get("iterations") if b.get("iterations") == a.get("iterations")
            else "**%s → %s**" % (b.get("iterations"), a.get("iterations")), ratio_text(ratios)))
    L.append("\nAll time ratios of this table together: %s.\n"
             % ratio_text([r for row in min_time for r in row[4]]))
    return L


def write_page(args, rows, min_time, random_rows, acc_before, acc_after, load_start, wall):
    L = ["# Refactor before/after: the benchmarks' problems on two builds\n"]
    L.append("Generated by `%s` (scripts/before_after.py); do not edit by hand. BEFORE = `%s`, "
             "AFTER = `%s`. Both read the same scene files (BEFORE's). Every problem ran BEFORE "
             "then AFTER, %d times in turn; a time ratio is AFTER / BEFORE of the solver's own "
             "`time_s` pair by pair, quoted as the median (min–max); below 1 AFTER is faster. "
             "Same optimum: relative cost difference ≤ %g. Machine: %d cores shared with other "
             "jobs, load average (1/5/15 min) %s at the start; the run took %.0f s.\n"
             % (args.command, args.before_label, args.after_label, args.repeats, REL_TOL,
                os.cpu_count(), load_start, wall))
    L.append("## scripts/benchmark and scripts/constraints_benchmark problems\n")
    L.append("| source | problem | cost before | relative cost difference | converged before → after "
             "| iterations before → after | time ratio after/before |")
    L.append("|---|---|---|---|---|---|---|")
    differ = []
    all_ratios = []
    for group, label, b, a, ratios in rows:
        if "error" in b or "error" in a:
            L.append("| %s | %s | error: %s / %s | | | | |" % (group, label, b.get("error", "ok"),
                                                                a.get("error", "ok")))
            differ.append(label)
            continue
        rel = abs(a["cost"] - b["cost"]) / max(abs(b["cost"]), 1e-300)
        same = same_cost(a["cost"], b["cost"]) and a["converged"] == b["converged"]
        if not same:
            differ.append(label)
        all_ratios.extend(ratios)
        L.append("| %s | %s | %.12g | %s | %s | %s | %s |" % (
            group, cell(label), b["cost"], "%.1e" % rel if rel > REL_TOL else "%.1e (same)" % rel,
            verdict_cell(b, a, "converged"),
            "%d" % b["iterations"] if b["iterations"] == a["iterations"]
            else "%d → %d" % (b["iterations"], a["iterations"]), ratio_text(ratios)))
    L.append("\nAll time ratios of this table together: %s.\n" % ratio_text(all_ratios))
    L.extend(minimum_time_table(min_time, differ))

    L.append("## scripts/robustness --random problems (seed 19, cases 0..%d)\n" % (args.random - 1))
    same_verdict = sum(1 for _, b, a in random_rows if b.get("termination") == a.get("termination"))
    same_opt = sum(1 for _, b, a in random_rows if b.get("termination") == a.get("termination")
                   and same_cost(a.get("cost"), b.get("cost")))
    conv_b = sum(1 for _, b, _a in random_rows if b.get("termination") == "converged")
    conv_a = sum(1 for _, _b, a in random_rows if a.get("termination") == "converged")
    rr = [a["time_s"] / b["time_s"] for _, b, a in random_rows
          if b.get("time_s") and a.get("time_s")]
    L.append("%d cases: converged %d before, %d after; the same verdict in %d, the same verdict "
             "and optimum in %d; time ratio after/before (per case, ours only) %s.\n"
             % (len(random_rows), conv_b, conv_a, same_verdict, same_opt, ratio_text(rr)))
    table = ["| case | termination before → after | cost before | relative cost difference | "
             "iterations before → after | time before → after [s] |", "|---|---|---|---|---|---|"]
    for case, b, a in random_rows:
        cb, ca = b.get("cost"), a.get("cost")
        rel = (abs(ca - cb) / max(abs(cb), 1e-300)) if cb is not None and ca is not None else math.nan
        if same_cost(ca, cb) and b.get("termination") == a.get("termination") \
                and b.get("iterations") == a.get("iterations"):
            continue  # identical: only differences are listed
        at_budget = max(b.get("time_s", 0.0), a.get("time_s", 0.0)) >= \
            AT_BUDGET_FRACTION * RANDOM_BUDGET_S
        table.append("| %s | %s | %.12g | %.1e | %s → %s | %.3g → %.3g%s |" % (
            cell(b.get("label", case)), verdict_cell(b, a, "termination"), cb or math.nan, rel,
            b.get("iterations"), a.get("iterations"), b.get("time_s", math.nan),
            a.get("time_s", math.nan),
            " (the %g s budget: iterations depend on the machine's speed)" % RANDOM_BUDGET_S
            if at_budget else ""))
    if len(table) > 2:
        L.extend(table)
        L.append("\n(Rows: only the cases where the verdict, the optimum or the iteration count "
                 "differ.)\n")
    else:
        L.append("Every case: the same verdict, optimum and iteration count.\n")

    L.append("## scripts/accuracy problems (accuracy_study, N up to %d)\n" % args.accuracy_max_steps)
    lb = dict(numeric_leaves(acc_before["json"]))
    la = dict(numeric_leaves(acc_after["json"]))
    keys = sorted(set(lb) | set(la))
    diffs = []
    for k in keys:
        vb, va = lb.get(k), la.get(k)
        if isinstance(vb, float) and isinstance(va, float):
            if not same_cost(va, vb) and not (math.isnan(va) and math.isnan(vb)):
                diffs.append((k, vb, va))
        elif vb != va:
            diffs.append((k, vb, va))
    L.append("%d figures compared (every number, flag and name of the raw JSON but times); %d "
             "differ. Whole process: %.1f s before, %.1f s after (ratio %.2f, one run each).\n"
             % (len(keys), len(diffs), acc_before["time_s"], acc_after["time_s"],
                acc_after["time_s"] / acc_before["time_s"]))
    if diffs:
        L.append("| figure | before | after |")
        L.append("|---|---|---|")
        for k, vb, va in diffs[:40]:
            L.append("| `%s` | %s | %s |" % (k, vb, va))
        if len(diffs) > 40:
            L.append("\n(%d more)\n" % (len(diffs) - 40))
    L.append("\n## Differences\n")
    L.append("Benchmark and minimum-time rows whose optimum or verdict differ (minimum time: "
             "or iterations): %s.\n"
             % (", ".join(differ) if differ else "none"))
    with open(args.out, "w") as f:
        f.write("\n".join(L) + "\n")


if __name__ == "__main__":
    main()
