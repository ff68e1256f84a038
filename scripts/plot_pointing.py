#!/usr/bin/python3
"""Writes docs/results/pointing.md and docs/results/pointing.png from the raw data of pointing_study.

usage: plot_pointing.py RAW.json DOCS_DIR [COMMAND]

For every seeded pointing request: the pointing answer's cost against the best fixed twist of a
5-degree sweep refined by golden section (target: at most best + 1e-6 relative) and against the
worst fixed twist, the end condition's residual, and the time of one pointing solve beside one
fixed-attitude solve at the chosen twist (target: at most 3x). Requests with a binding constraint
(a keep-out cone, a torque box or norm bound) are summarized apart.
"""
import json
import math
import os
import statistics
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

raw_path, docs = sys.argv[1], sys.argv[2]
command = sys.argv[3] if len(sys.argv) > 3 else "scripts/pointing"
data = json.load(open(raw_path))
cases = data["cases"]
COST_TARGET = 1e-6
TIME_TARGET = 3.0


def excess(c):
    """The answer's cost over the sweep's best, relative; NaN without a sweep reference."""
    if c["sweep_best"] is None:
        return math.nan
    return (c["cost"] - c["sweep_best"]) / c["sweep_best"] if c["cost"] is not None else math.inf


def fmt(form, v):
    return form % v if v is not None else "-"


def ms(t):
    return "%.3g" % (1e3 * t)


def answered(c):
    """yes, or no with the answer's outcome (an infeasible verdict names the least T found)."""
    if c["converged"]:
        return "yes"
    outcome = c.get("outcome", "not converged")
    if outcome.startswith("infeasible") and c.get("least_duration_found"):
        return "no: %s, least T found %.6g s (T = %.6g s)" % (outcome, c["least_duration_found"], c["duration"])
    return "no: %s" % outcome


rows = []
for i, c in enumerate(cases):
    ratio = c["time"] / c["fixed_time"]
    best_twist = c["sweep_best_twist"] if c["sweep_best_twist"] <= math.pi else c["sweep_best_twist"] - 2 * math.pi
    rows.append("| %d | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %s | %.1e | %.1e | %s | %s | %.2f |" % (
        i + 1, c["seed"], c["scheme"], "spinning" if c["spinning"] else "rest", c.get("binding", "none"),
        answered(c), fmt("%.10g", c["cost"]), fmt("%.10g", c["sweep_best"]),
        fmt("%.4g", c["sweep_worst"] if c["sweep_best"] is not None else None),
        fmt("%+.2e", excess(c) if c["sweep_best"] is not None else None), fmt("%.3f", c["twist"]),
        fmt("%.3f", best_twist if c["sweep_best"] is not None else None), c["error"], c["stationarity"], ms(c["time"]),
        ms(c["fixed_time"]), ratio))



def p90(values):
    """The 90th percentile (nearest rank: the smallest value at least 90% of them are at or below)."""
    ordered = sorted(values)
    return ordered[max(0, math.ceil(0.9 * len(ordered)) - 1)]


def summary(group, what):
    """The summary lines of one group of requests."""
    if not group:
        return ""
    referenced = [c for c in group if c["sweep_best"] is not None]
    unreferenced = [c for c in group if c["sweep_best"] is None]
    excesses = [excess(c) for c in referenced]
    ratios = [c["time"] / c["fixed_time"] for c in group]
    worst_over_best = [c["sweep_worst"] / c["sweep_best"] for c in referenced]
    note = ""
    if unreferenced:
        infeasible = sum(c.get("outcome", "").startswith("infeasible") for c in unreferenced)
        note = (" %d more: no swept twist converged (every 5 degrees, planManeuver); the pointing "
                "answer converged in %d of them, and was infeasible (naming the least T found) in %d." % (
                    len(unreferenced), sum(c["converged"] for c in unreferenced), infeasible))
    return """%s (%d requests):
- Cost: %d of %d at most the sweep's best + %g relative (largest excess %+.2e).%s
  The worst fixed twist costs %.3g-%.3gx the best (median %.3g).
- End condition: largest angle(R_N b, d) %.1e rad; largest relative stationarity in psi %.1e.
- Time: pointing / fixed at the chosen twist median %.2fx, p90 %.2fx, largest %.2fx; %d of %d within %gx.
""" % (what, len(group), sum(e <= COST_TARGET for e in excesses), len(referenced), COST_TARGET,
       max(excesses), note, min(worst_over_best), max(worst_over_best), statistics.median(worst_over_best),
       max(c["error"] for c in group if c["converged"]), max(c["stationarity"] for c in group if c["converged"]),
       statistics.median(ratios), p90(ratios), max(ratios), sum(r <= TIME_TARGET for r in ratios), len(group),
       TIME_TARGET)


free = [c for c in cases if c.get("binding", "none") == "none"]
bound = [c for c in cases if c.get("binding", "none") != "none"]
first_bound = [c for c in bound[:2]]

fig, axes = plt.subplots(2, 2, figsize=(10, 7))
for ax, c in zip(axes.flat, free[:2] + first_bound if first_bound else cases[:4]):
    twists = [t if t <= math.pi else t - 2 * math.pi for t in c["sweep_twists"]]
    pairs = sorted((t, k) for t, k in zip(twists, c["sweep_costs"]) if k is not None)
    ax.plot([p[0] for p in pairs], [p[1] for p in pairs], ".-", label="fixed twist (5 deg sweep)")
    if c["cost"] is not None:
        ax.plot([c["twist"]], [c["cost"]], "r*", markersize=14, label="pointing answer")
    ax.set_yscale("log")
    ax.set_title("seed %d, %s, %s, %s" % (c["seed"], c["scheme"], "spinning" if c["spinning"] else "rest",
                                          c.get("binding", "none")))
    ax.set_xlabel("twist psi [rad]")
    ax.set_ylabel("cost [N^2 m^2]")
    ax.legend(fontsize=7)
fig.tight_layout()
fig.savefig(os.path.join(docs, "pointing.png"), dpi=90)

with open(os.path.join(docs, "pointing.md"), "w") as out:
    out.write("""# Pointing targets: the twist chosen against a sweep of fixed twists

Generated by `%s` (studies/pointing_study.cpp, scripts/plot_pointing.py); %d seeded random
requests (seed %d): random inertia (moments in [1, 2] kg m^2, random axes), random boresight b, target d
and R_0, T in [8, 12] s, rest to rest or spinning (|Omega_0| = 0.2, |Omega(T)| = 0.1 rad/s), paper and
second_order, N = %d, minimum effort; without constraints, and with one binding constraint each (a
keep-out cone about b whose world direction bisects R_0 b and d, half angle 0.35 of their angle; a
torque box or a torque norm bound at 0.7 of the unconstrained pointing answer's largest torque).
Load while measuring: %s.

Each request is planned once as a pointing request (`final.pointing`), and judged against the
fixed-attitude optimum over the twist psi (R_N = R_ref exp(psi b^)): a sweep every 5 degrees
(planManeuver, homotopy classes enumerated), the best bracket refined by golden section to 1e-7
rad. Times: the median thread CPU time of %d runs each (immune to the other processes of a
shared machine, which made wall times vary 4x between repeats), the pointing solve beside one
fixed-attitude solve at the twist it chose (same N and scheme, one after the other).

## Summary

%s
%s
With constraints the stationarity is the Lagrangian's, |dL/dpsi| relative. A constrained pointing
request is one problem: the twist Newton's starts (4 twists x 2 ways round, the constraints not
seen) give the unconstrained twist optima, and the interior point with psi free starts from each
distinct one, cheapest first, while its unconstrained cost is below the cheapest constrained
answer found (constraints only add cost within a start's basin, and the interior point keeps the
way round it starts in); an optimum that meets every constraint is that basin's answer as it is,
and an interior point whose lower bound (at a feasible, locally convex iterate with a small step:
C - sum z c + g'd/2) passes the cheapest such answer or the cheapest constrained answer found is
stopped there.
An optimum whose path comes within 15 %% of a cone's half angle of its axis and crosses it deeper
than the fixed-twist unconstrained optima 45 degrees either side of its psi do (a ridge of the constrained cost over psi: the plan passes the cone on
one side or the other, each side's optimum at another twist) starts it from those two optima
instead, both run. Where none of those converges (a cone across the optimum's path): the same from each optimum
the other way round at its psi and from the fixed-twist unconstrained optima at the 4 start
twists (a path that passes the cone on one side); only where none of those converges either, and
the interior point has not certified local infeasibility from 4 distinct starts (then the loop
stops: a local verdict), each start twist from its fixed-twist constrained optimum (every way
round solved under the constraints there) frees psi from that plan. In both kinds a survey start
whose Newton model's minimum lies on an answer the survey already holds (relative decrement d at
most 0.3, cost within max(1e-3, 2 d^3), psi within max(1e-2, d^2) rad, its cost not below that
answer's) is stopped there. The fixed solve it is timed
against is one request's whole driver: the class survey, the interior point from the
unconstrained optimum and, where that has no plan, the other classes under the constraints.

Minimum time to a pointing target (Betts's body, T* against a swept twist): [pointing_minimum_time.md](pointing_minimum_time.md).

![cost against the twist](pointing.png)

## Requests

| # | seed | scheme | start | binding | converged | pointing cost | sweep best | sweep worst | excess | psi | sweep psi | angle(R_N b, d) | stationarity | pointing [ms CPU] | fixed [ms CPU] | ratio |
|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|
%s
""" % (command, len(cases), data["seed"], data["steps"], data["load"], data["repeats"],
       summary(free, "Without constraints"), summary(bound, "With one binding constraint"),
       "\n".join(rows)))
