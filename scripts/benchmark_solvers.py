#!/usr/bin/env python3
"""Driver of scripts/benchmark: runs benchmark_solvers once per process and repetition, takes
medians, writes docs/results/performance.md (tables, load, commands) and docs/results/performance_scaling.png.

Hand-written measurements that need a running ROS graph (service round trip, replay jitter) and
the profiles live in docs/notes/performance_notes.md and are appended verbatim.
"""
import argparse
import json
import os
import statistics
import subprocess
import sys
import time

# Complexity exponent used to predict a peer's time at the next size (skip if > the limit).
EXPONENT = {"newton": 1.0, "slsqp": 3.0, "complex_step": 3.0, "auglag": 2.0, "ipopt": 1.5,
            "ipopt_lbfgs": 1.5}
PEERS = ["slsqp", "auglag", "ipopt", "complex_step"]
# Extra rows of the side-by-side table only (not the slew-up table or the plot), run at
# N <= EXTRA_MAX_N: IPOPT with its L-BFGS Hessian, for comparison with the exact-Hessian "ipopt".
EXTRA = ["ipopt_lbfgs"]
EXTRA_MAX_N = 1024
LABEL = {
    "newton": "ours (Newton, reduced problem)",
    "slsqp": "NLopt SLSQP (direct, exact gradients)",
    "auglag": "NLopt AUGLAG_EQ + LD_LBFGS (direct)",
    "ipopt": "IPOPT 3.11 (simultaneous, exact sparse Jacobian and Hessian)",
    "ipopt_lbfgs": "IPOPT 3.11 (simultaneous, exact Jacobian, L-BFGS Hessian)",
    "complex_step": "seed's approach (dense complex-step Newton)",
}


def run_once(binary, solver, scene, steps, scheme, budget, extra=()):
    cmd = [binary, "--solver", solver, "--scene", scene, "--steps", str(steps), "--scheme", scheme,
           "--time-budget", str(budget)] + list(extra)
    out = subprocess.run(cmd, capture_output=True, text=True)
    if out.returncode != 0:
        return {"solver": solver, "steps": steps, "error": out.stderr.strip()}
    return json.loads(out.stdout.strip().splitlines()[-1])


def measure(binary, solver, scene, steps, scheme, repeats, budget, long_run):
    """Median of `repeats` runs; a single run if the first already takes longer than long_run."""
    runs = [run_once(binary, solver, scene, steps, scheme, budget)]
    if "error" in runs[0]:
        return runs[0]
    if runs[0]["time_s"] < long_run:
        runs += [run_once(binary, solver, scene, steps, scheme, budget) for _ in range(repeats - 1)]
    best = dict(runs[0])
    best["runs"] = len(runs)
    best["time_s"] = statistics.median(r["time_s"] for r in runs)
    best["peak_rss_kb"] = statistics.median(r["peak_rss_kb"] for r in runs)
    best["times"] = [r["time_s"] for r in runs]
    return best


def fmt_time(t):
    return "%.3g ms" % (1e3 * t) if t < 1 else "%.3g s" % t


def load():
    return "%.2f %.2f %.2f" % os.getloadavg()


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--binary", required=True)
    ap.add_argument("--scenes", required=True)
    ap.add_argument("--docs", required=True, help="directory of the generated results")
    ap.add_argument("--notes", help="hand-written notes appended verbatim after the tables")
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--limit", type=float, default=60.0, help="time cap of a peer run [s]")
    args = ap.parse_args()
    sizes = [32, 128] if args.quick else [32, 128, 1024, 8192]
    scaling = [1000, 10000] if args.quick else [1000, 10000, 100000, 1000000]
    repeats = 2 if args.quick else args.repeats
    scene = os.path.join(args.scenes, "rest_to_rest.yaml")
    started = time.time()
    load_before = load()

    # 1. Side by side, paper scheme (the problem every peer solves), plus ours on variational.
    rows = {}
    last = {}
    for n in sizes:
        for solver in ["newton"] + PEERS + (EXTRA if n <= EXTRA_MAX_N else []):
            prev = last.get(solver)
            if solver == "complex_step" and 8.0 * (3 * (2 * n - 3)) ** 2 > 4e9:
                rows[(solver, n)] = {"skipped": "not run: its dense %d² Jacobian alone needs %.0f GB"
                                     % (3 * (2 * n - 3), 8.0 * (3 * (2 * n - 3)) ** 2 / 1e9),
                                     "steps": n}
                continue
            if solver == "slsqp" and n > 1024:
                rows[(solver, n)] = {"skipped": "not run: the cross-check refuses N > 1024 (dense "
                                     "SLSQP, O(N³) per iteration)", "steps": n}
                continue
            if prev is not None and (prev.get("capped") or not prev.get("converged")):
                rows[(solver, n)] = {"skipped": "not run: %s at N = %d" % (
                    "exceeded the %g s cap" % args.limit if prev.get("capped")
                    else "did not converge", prev["steps"]), "steps": n}
                continue
            predicted = (prev["time_s"] * (n / prev["steps"]) ** EXPONENT[solver]
                         if prev is not None else 0.0)
            if predicted > args.limit:
                # Run once with the cap as its time budget: "> cap" is a measurement.
                m = run_once(args.binary, solver, scene, n, "paper", args.limit)
                m["runs"] = 1
                m["capped"] = "error" in m or not m.get("converged")
                m["times"] = [m.get("time_s")]
            else:
                m = measure(args.binary, solver, scene, n, "paper", repeats, args.limit, 20.0)
            print(json.dumps(m), flush=True)
            rows[(solver, n)] = m
            if "error" not in m:
                last[solver] = m
        m = measure(args.binary, "newton", scene, n, "variational", repeats, args.limit, 20.0)
        rows[("newton_variational", n)] = m
        print(json.dumps(m), flush=True)
        if n <= 1024:
            # Warm: 21 solves in one process, median of the last 20 (what a node serving
            # requests sees); the table's times are the cold first solve of a fresh process.
            m = run_once(args.binary, "newton", scene, n, "paper", args.limit, ["--in-process", "21"])
            rows[("newton_warm", n)] = m
            print(json.dumps(m), flush=True)
    slew = os.path.join(args.scenes, "slew_up.yaml")
    slew_rows = {s: measure(args.binary, s, slew, 128, "paper", repeats, args.limit, 20.0)
                 for s in ["newton"] + PEERS}
    for m in slew_rows.values():
        print(json.dumps(m), flush=True)

    # 2. Ours alone to a million steps.
    scale_rows = []
    for n in scaling:
        for scheme in ["paper", "variational"]:
            m = measure(args.binary, "newton", scene, n, scheme, repeats, 600.0, 20.0)
            print(json.dumps(m), flush=True)
            scale_rows.append(m)
    load_after = load()
    write_doc(args, sizes, rows, slew_rows, scale_rows, repeats, load_before, load_after,
              time.time() - started)
    plot(args, sizes, rows, scale_rows)


def cell(m):
    if m is None:
        return "—"
    if "skipped" in m:
        return "skipped"
    if "error" in m:
        return "error"
    return fmt_time(m["time_s"])


def write_doc(args, sizes, rows, slew_rows, scale_rows, repeats, load_before, load_after, wall):
    L = []
    L.append("# Performance: ours against every peer, and scaling to a million steps\n")
    L.append("Regenerate: `scripts/benchmark` (this file and `docs/results/performance_scaling.png`; the "
             "sections after the tables come from `docs/notes/performance_notes.md`). Smoke test: "
             "`test/unit/test_benchmark_solvers.cpp` runs `benchmark_solvers --quick` (no timing).\n")
    L.append("Machine: %d cores, shared with other builds. Load average (1/5/15 min) at the start "
             "%s, at the end %s; the run took %.0f s. Every figure is the median of %d runs, one "
             "process per run (peak memory = that process's VmHWM, including the ~%s of a "
             "process that only loads the library); a run slower than 20 s is done once (marked "
             "¹). Times are the wall time of the solver call only (ours: planManeuver, which "
             "also validates and replays).\n" % (os.cpu_count(), load_before, load_after, wall,
                                                  repeats, "4 MB"))
    L.append("Problem: the seed's rest-to-rest example (`scenes/rest_to_rest.yaml`: seed inertia, "
             "π/3 about x, T = 12.8 s) on the `paper` scheme at N steps; every solver starts from "
             "the same geodesic guess (SLSQP from zero torques, as the cross-check does) and every "
             "solver's torques are replayed through the same `evaluatePlan`, which gives the "
             "cost and the terminal miss reported.\n")
    L.append("## 1. Side by side (paper scheme)\n")
    L.append("| solver | N | time (median) | runs | iterations | peak memory | cost Σ½\\|τ\\|² | "
             "\\|cost − ours\\|/ours | terminal miss | converged | ours faster by |")
    L.append("|---|---|---|---|---|---|---|---|---|---|---|")
    for n in sizes:
        ours = rows.get(("newton", n))
        for solver in ["newton"] + PEERS + EXTRA:
            m = rows.get((solver, n))
            if m is None:
                continue
            if m.get("capped"):
                L.append("| %s | %d | **> %g s (cap)** | 1 | %s | %s | | | | no (stopped at the cap) "
                         "| > %.0f× |" % (LABEL[solver], n, args.limit, m.get("iterations", ""),
                                          "%.1f MB" % (m["peak_rss_kb"] / 1024)
                                          if "peak_rss_kb" in m else "", args.limit / ours["time_s"]))
                continue
            if "skipped" in m or "error" in m:
                L.append("| %s | %d | skipped: %s | | | | | | | | |" %
                         (LABEL[solver], n, m.get("skipped", m.get("error"))))
                continue
            rel = abs(m["cost"] - ours["cost"]) / ours["cost"] if ours and "cost" in ours else float("nan")
            ratio = ("—" if solver == "newton" or not m["converged"]
                     else "%.0f×" % (m["time_s"] / ours["time_s"]))
            L.append("| %s | %d | %s | %d%s | %d | %.1f MB | %.10g | %.1e | %.1e | %s | %s |" %
                     (LABEL[solver], n, fmt_time(m["time_s"]), m["runs"],
                      "¹" if m["runs"] == 1 else "", m["iterations"], m["peak_rss_kb"] / 1024,
                      m["cost"], rel, m["terminal_miss"], "yes" if m["converged"] else "**no**",
                      ratio))
        v = rows.get(("newton_variational", n))
        if v and "time_s" in v:
            L.append("| ours, variational scheme (different problem) | %d | %s | %d | %d | %.1f MB | "
                     "%.10g | — | %.1e | %s | — |" % (n, fmt_time(v["time_s"]), v["runs"],
                                                      v["iterations"], v["peak_rss_kb"] / 1024,
                                                      v["cost"], v["terminal_miss"],
                                                      "yes" if v["converged"] else "**no**"))
    L.append("\nIterations: ours, IPOPT and the complex-step Newton count Newton/interior-point "
             "iterations; SLSQP counts constraint-Jacobian evaluations (≈ iterations); AUGLAG "
             "counts objective evaluations of the LBFGS subsolver summed over the outer "
             "iterations.\n")
    L.append("Slew-up example (`scenes/slew_up.yaml`), N = 128, paper scheme:\n")
    L.append("| solver | time (median) | iterations | cost | \\|cost − ours\\|/ours | converged | "
             "ours faster by |")
    L.append("|---|---|---|---|---|---|---|")
    ours = slew_rows["newton"]
    for s, m in slew_rows.items():
        if "error" in m:
            L.append("| %s | error | | | | | |" % LABEL[s])
            continue
        L.append("| %s | %s | %d | %.10g | %.1e | %s | %s |" %
                 (LABEL[s], fmt_time(m["time_s"]), m["iterations"], m["cost"],
                  abs(m["cost"] - ours["cost"]) / ours["cost"], "yes" if m["converged"] else "**no**",
                  "—" if s == "newton" or not m["converged"]
                  else "%.0f×" % (m["time_s"] / ours["time_s"])))
    L.append("\n## 2. Ours to a million steps\n")
    L.append("| scheme | N | time (median) | runs | iterations (all grid levels) | time per step | "
             "peak memory | memory per step | converged |")
    L.append("|---|---|---|---|---|---|---|---|---|")
    for m in scale_rows:
        if "error" in m:
            L.append("| %s | %d | error | | | | | | |" % (m.get("scheme", "?"), m["steps"]))
            continue
        L.append("| %s | %d | %s | %d | %d | %.2f µs | %.1f MB | %.0f B | %s |" %
                 (m["scheme"], m["steps"], fmt_time(m["time_s"]), m["runs"], m["iterations"],
                  1e6 * m["time_s"] / m["steps"], m["peak_rss_kb"] / 1024,
                  1024 * m["peak_rss_kb"] / m["steps"], "yes" if m["converged"] else "**no**"))
    L.append("\n![scaling](performance_scaling.png)\n")
    L.extend(targets(sizes, rows, scale_rows, args.limit))
    if args.notes and os.path.exists(args.notes):
        L.append(open(args.notes).read())
    with open(os.path.join(args.docs, "performance.md"), "w") as f:
        f.write("\n".join(L) + "\n")
    with open(os.path.join(args.docs, "performance_raw.json"), "w") as f:
        json.dump({"rows": {"%s@%d" % k: v for k, v in rows.items()},
                   "slew": slew_rows, "scaling": scale_rows}, f, indent=1)


def targets(sizes, rows, scale_rows, limit):
    """The benchmark's targets, judged from this run's figures (nothing typed by hand)."""
    L = ["## Targets (issue 9) against this run\n",
         "| target | measured | met? |", "|---|---|---|"]

    def ratio(solver, n):
        m, ours = rows.get((solver, n)), rows.get(("newton", n))
        if not m or not ours or "time_s" not in ours:
            return None, "—"
        if m.get("capped"):
            return None, "> %.0f× (stopped at the %g s cap, not converged)" % (
                limit / ours["time_s"], limit)
        if "time_s" not in m or not m.get("converged"):
            return None, m.get("skipped", "did not converge")
        r = m["time_s"] / ours["time_s"]
        return r, "%.0f×" % r

    ours128 = rows.get(("newton", 128), {})
    t128 = ours128.get("time_s")
    warm128 = rows.get(("newton_warm", 128), {}).get("warm_time_s")
    L.append("| seed example N = 128 in ≤ 2 ms | cold (first solve of a fresh process, median of "
             "5 processes): %s; warm (median of 20 solves in one process, as a node serving "
             "requests): %s; %s iterations, all levels | cold: %s; warm: %s |" % (
                 fmt_time(t128) if t128 else "—", fmt_time(warm128) if warm128 else "—",
                 ours128.get("iterations", "—"), "yes" if t128 and t128 <= 2e-3 else "**no**",
                 "yes" if warm128 and warm128 <= 2e-3 else "**no**"))
    for solver, goal in [("ipopt", 10), ("slsqp", 100), ("complex_step", 100)]:
        if solver not in LABEL:
            continue
        r, text = ratio(solver, 128)
        by_n = ", ".join("N = %d: %s" % (n, ratio(solver, n)[1]) for n in sizes)
        L.append("| ≥ %d× faster than %s at N = 128 | %s (%s) | %s |" % (
            goal, LABEL[solver], text, by_n, "yes" if r and r >= goal else "**no**"))
    for scheme in ["paper", "variational"]:
        big = [m for m in scale_rows if m.get("scheme") == scheme and m.get("steps") == 1000000]
        if big and "time_s" in big[0]:
            m = big[0]
            L.append("| N = 10⁶ in ≤ 30 s (%s) | %s, %d iterations, %s | %s |" % (
                scheme, fmt_time(m["time_s"]), m["iterations"],
                "converged" if m["converged"] else "not converged",
                "yes" if m["time_s"] <= 30 and m["converged"] else "**no**"))
    per_step = ["N = %d: %.0f B" % (m["steps"], 1024 * m["peak_rss_kb"] / m["steps"])
                for m in scale_rows if m.get("scheme") == "paper" and "peak_rss_kb" in m]
    L.append("| memory linear in N (paper) | %s per step | see the column: flat from 10⁴ on |" %
             ", ".join(per_step))
    L.append("")
    return L


def plot(args, sizes, rows, scale_rows):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, (a, b) = plt.subplots(1, 2, figsize=(11, 4.2))
    for solver in ["newton"] + PEERS:
        pts = [(n, rows[(solver, n)]["time_s"]) for n in sizes
               if (solver, n) in rows and "time_s" in rows[(solver, n)]
               and not rows[(solver, n)].get("capped")]
        if pts:
            a.loglog(*zip(*pts), "o-", label=LABEL[solver])
    a.set_xlabel("N (steps)")
    a.set_ylabel("solve time [s]")
    a.set_title("seed rest-to-rest, paper scheme")
    a.grid(True, which="both", alpha=0.3)
    a.legend(fontsize=7)
    for scheme in ["paper", "variational"]:
        pts = [(m["steps"], m["time_s"], m["peak_rss_kb"] * 1024.0) for m in scale_rows
               if m.get("scheme") == scheme and "time_s" in m]
        if pts:
            n, t, mem = zip(*pts)
            b.loglog(n, t, "o-", label="time [s], " + scheme)
            b.loglog(n, [x / 1e9 for x in mem], "s--", label="peak memory [GB], " + scheme)
    b.set_xlabel("N (steps)")
    b.set_title("ours, scaling")
    b.grid(True, which="both", alpha=0.3)
    b.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(os.path.join(args.docs, "performance_scaling.png"), dpi=110)


if __name__ == "__main__":
    main()
