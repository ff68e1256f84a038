#!/usr/bin/python3
"""Writes docs/results/accuracy.md and its plots from the raw data of accuracy_study.

usage: plot_accuracy.py RAW.json DOCS_DIR
"""
import json
import math
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

raw_path, docs = sys.argv[1], sys.argv[2]
data = json.load(open(raw_path))
cases = data["cases"]

MEASURES = [  # key, label, unit
    ("cost_error", "cost error |h·Σ½|τ_k|² − ½∫|τ|²dt|", "N² m² s"),
    ("trajectory_error", "trajectory error max_k ‖log(R(t_k)ᵀR_k)‖", "rad"),
    ("torque_error", "torque error max_k |τ_k − τ(t_k)|", "N m"),
    ("attitude_miss", "terminal attitude miss (ZOH replay)", "rad"),
    ("velocity_miss", "terminal velocity miss (ZOH replay)", "rad/s"),
]
# Least-squares fits use FIT_FROM <= N <= FIT_TO (the range the issues define orders on; above it
# the second_order torque reaches its round-off floor at the end nodes, see the text).
FIT_FROM, FIT_TO = 32, 1024
# fourth_order reaches the torque's round-off floor eps·(2N)² near N = 512: its orders are also
# fitted on N = 16 … 256, before the floor.
EARLY_FROM, EARLY_TO = 16, 256


def fit_order(rows, key, lo=None, hi=None):
    lo = FIT_FROM if lo is None else lo
    hi = FIT_TO if hi is None else hi
    pts = [(math.log(r["N"]), math.log(r[key])) for r in rows
           if lo <= r["N"] <= hi and r[key] > 0]
    n = len(pts)
    sx = sum(p[0] for p in pts)
    sy = sum(p[1] for p in pts)
    sxx = sum(p[0] ** 2 for p in pts)
    sxy = sum(p[0] * p[1] for p in pts)
    return -(n * sxy - sx * sy) / (n * sxx - sx * sx)


def label(c):
    return "%s, %s" % (c["scene"], c["scheme"])


# Series: the scheme by colour and marker, the scene by line style and marker fill, so that every
# legend entry differs in two ways and stays distinguishable in grey print. The reference slopes
# are labelled on the plot, not in the legend; one legend per figure, outside the axes.
SCHEME_STYLE = {"paper": ("tab:blue", "o"), "variational": ("tab:orange", "s"),
                "second_order": ("tab:green", "^"), "fourth_order": ("tab:purple", "D")}
SCENE_STYLE = {"rest_to_rest": ("-", True), "slew_up": ("--", False)}


def series(ax, x, y, c):
    color, marker = SCHEME_STYLE[c["scheme"]]
    linestyle, filled = SCENE_STYLE[c["scene"]]
    return ax.loglog(x, y, linestyle=linestyle, color=color, marker=marker, ms=4, lw=1.2,
                     markerfacecolor=color if filled else "white", markeredgecolor=color,
                     label=label(c))[0]


def reference_slopes(ax):
    N0 = [16, 16384]
    for scale, order, text in ((1e-1, 1, "N⁻¹"), (1e-2, 2, "N⁻²"), (1e-4, 4, "N⁻⁴")):
        y = [scale * (16 / n) ** order for n in N0]
        ax.loglog(N0, y, color="0.55", lw=0.8, zorder=0)
        ax.annotate("∝ " + text, (N0[1], y[1]), xytext=(3, 0), textcoords="offset points",
                    fontsize=7, color="0.4", va="center")


def figure_legend(fig, handles, top):
    fig.legend(handles=handles, loc="upper center", bbox_to_anchor=(0.5, top), ncol=4,
               fontsize=8, frameon=False)


# ---- plots -----------------------------------------------------------------------------------
fig, axes = plt.subplots(2, 3, figsize=(15, 9.6))
for ax, (key, title, unit) in zip(axes.flat, MEASURES):
    handles = [series(ax, [r["N"] for r in c["sweep"]], [r[key] for r in c["sweep"]], c)
               for c in cases]
    reference_slopes(ax)
    ax.set_xlim(right=16384 * 3.5)  # room for the slope labels
    ax.set_title(title, fontsize=10)
    ax.set_xlabel("steps N")
    ax.set_ylabel(unit)
    ax.grid(True, which="both", alpha=0.3)
ax = axes.flat[5]
for c in cases:
    series(ax, [r["N"] for r in c["sweep"]], [r["solve_time_s"] * 1e3 for r in c["sweep"]], c)
ax.set_title("solve time (median of %d)" % data["repeats"], fontsize=10)
ax.set_xlabel("steps N")
ax.set_ylabel("ms")
ax.grid(True, which="both", alpha=0.3)
fig.tight_layout(rect=(0, 0, 1, 0.93))
figure_legend(fig, handles, 0.995)
fig.text(0.5, 0.935, "fitted orders p: the table in accuracy.md (Observed orders)",
         ha="center", fontsize=8, color="0.3")
fig.savefig(docs + "/accuracy_vs_steps.png", dpi=90)

fig, axes = plt.subplots(1, 3, figsize=(15, 5.6))
for ax, key in zip(axes, ["attitude_miss", "cost_error", "trajectory_error"]):
    title, unit = [(t, u) for k, t, u in MEASURES if k == key][0]
    handles = [series(ax, [r["solve_time_s"] * 1e3 for r in c["sweep"]],
                      [r[key] for r in c["sweep"]], c) for c in cases]
    ax.set_title(title + " vs solve time", fontsize=10)
    ax.set_xlabel("solve time [ms] (median)")
    ax.set_ylabel(unit)
    ax.grid(True, which="both", alpha=0.3)
fig.tight_layout(rect=(0, 0, 1, 0.88))
figure_legend(fig, handles, 0.995)
fig.savefig(docs + "/accuracy_vs_time.png", dpi=90)

# ---- the document ----------------------------------------------------------------------------
out = []
w = out.append


def sci(x):
    return "%.2e" % x


def ms(t):
    return "%.3g ms" % (t * 1e3) if t < 1 else "%.3g s" % t


by = {(c["scene"], c["scheme"]): c for c in cases}
rest_var = by[("rest_to_rest", "variational")]
miss6 = [t for t in rest_var["targets"] if t["measure"] == "terminal_miss" and t["target"] == 1e-6][0]
rest_paper = by[("rest_to_rest", "paper")]

w("# What accuracy costs in time")
w("")
w("Regenerate: `scripts/accuracy` (this file, `docs/results/accuracy_vs_steps.png`, "
  "`docs/results/accuracy_vs_time.png` and the raw data `docs/results/accuracy_raw.json`; tool "
  "`src/tools/accuracy_study.cpp`, plots `scripts/plot_accuracy.py`). Tests: "
  "`test/unit/test_accuracy.cpp`.")
w("")
w("Machine: 2 cores shared with other builds. Load average (1/5/15 min) at the start %s, at the end "
  "%s; the run took %.0f s. Solve times are the median of %d runs of `planManeuver` (Newton, "
  "tolerance 1e-10) in one process." % (data["load_average_start"], data["load_average_end"],
                                       data["wall_time_s"], data["repeats"]))
w("")
w("Against a peer a user would pick instead (IPOPT on Hermite–Simpson collocation of the same "
  "continuous problem), the accuracy-versus-solve-time frontier: [frontier.md](frontier.md) "
  "(`scripts/frontier`).")
w("")
w("## The answer")
w("")
# The paper scheme's miss is order 1: the N it would need for 1e-6, from its finest point.
paper_needed = rest_paper["sweep"][-1]["N"] * rest_paper["sweep"][-1]["attitude_miss"] / 1e-6
miss6_all = []
for (scene, scheme), c in by.items():
    if scene != "rest_to_rest":
        continue
    for t in c["targets"]:
        if t["measure"] == "terminal_miss" and t["target"] == 1e-6 and t["converged"]:
            miss6_all.append((t["plain_solve_time_s"], scheme, t))
miss6_all.sort(key=lambda x: x[0])
best_time, best_scheme, best = miss6_all[0]
others = ", ".join("`%s` N = %d, %s" % (sch, t["N"], ms(tm)) for tm, sch, t in miss6_all[1:])
w("- **For a 1e-6 rad terminal attitude miss on the seed's rest-to-rest example use the "
  "`%s` scheme: N = %d, %s** (planned to the target by `plan_maneuver "
  "scenes/rest_to_rest.yaml --target-miss 1e-6 --scheme %s`, %s including the coarse resolutions "
  "it solves first; measured miss %s). Others: %s. The `paper` scheme would need N ≈ %s for the "
  "same miss (its miss converges at order 1): the planner refuses that up front."
  % (best_scheme, best["N"], ms(best["plain_solve_time_s"]), best_scheme, ms(best["solve_time_s"]),
     sci(best["actual"]), others, "{:,}".format(int(round(paper_needed, -3)))))
w("- **`second_order` converges at order 2 in every measure** (effort, trajectory, torque at every "
  "node, attitude and velocity miss): its boundary velocities act at the instants 0 and T through "
  "the node momenta, the end torques are unknowns and the cost is the trapezoidal rule "
  "(docs/design/second_order.md). `paper` and `variational` stay as the seed has them: cost, trajectory and "
  "torque errors of order 1, the physical miss of order 2 only with `variational`. The seed's "
  "\"effective order two\" (Sec. 3.4) does not hold for them as measured.")
# The torque target: relative torque error <= 1e-6 on the seed's rest-to-rest example.
fo_case = by[("rest_to_rest", "fourth_order")]
fo = fo_case["sweep"]
w("- **`fourth_order` converges at order 4** (effort, trajectory, torque, attitude and velocity "
  "miss; table below): it is one Richardson extrapolation step of `second_order` (plans at N and "
  "2N combined node by node, docs/design/fourth_order.md), not a new discretization, and costs one "
  "`second_order` solve at N plus one at 2N (≈ 3× a `second_order` solve at N). Its torque "
  "error reaches the round-off floor of the `second_order` torques (≈ eps·(2N)², second "
  "differences of attitudes) near N = 512, so its least-squares torque order over N = %d … %d is "
  "%.2f; over N = %d … %d, before the floor, %.2f." % (
      FIT_FROM, FIT_TO, fit_order(fo, "torque_error"), EARLY_FROM, EARLY_TO,
      fit_order(fo, "torque_error", EARLY_FROM, EARLY_TO)))
for scheme_name in ("second_order", "fourth_order"):
    sw = by[("rest_to_rest", scheme_name)]["sweep"]
    rel = [(r["N"], r["torque_error"] / r["max_torque"], r["solve_time_s"]) for r in sw]
    hit = [x for x in rel if x[1] <= 1e-6]
    if hit:
        w("- Relative torque error ≤ 1e-6 on the seed's rest-to-rest example with `%s`: first at "
          "N = %d (%s, %s). Target ≤ 5 ms: %s." % (
              scheme_name, hit[0][0], sci(hit[0][1]), ms(hit[0][2]),
              "**met**" if hit[0][2] <= 5e-3 else "**not met**"))
    else:
        w("- Relative torque error ≤ 1e-6 on the seed's rest-to-rest example with `%s`: not reached "
          "within the sweep (N = %d: %s, %s)." % (scheme_name, rel[-1][0], sci(rel[-1][1]),
                                                 ms(rel[-1][2])))
# The seed's default accuracy: the relative torque error of the default plan (paper, N = 128) on
# the rest-to-rest example, and the first N (coarse grids N = 4 … 32, then the sweep) at which
# each scheme reaches it.
paper128 = [r for r in rest_paper["sweep"] if r["N"] == 128][0]
default_error = paper128["torque_error"] / paper128["max_torque"]
reach = []
for scheme_name in ("paper", "variational", "second_order", "fourth_order"):
    c = by[("rest_to_rest", scheme_name)]
    rows = [(r["N"], r["relative_torque_error"], r["solve_time_s"]) for r in c.get("coarse", [])
            if r["converged"]]
    rows += [(r["N"], r["torque_error"] / r["max_torque"], r["solve_time_s"]) for r in c["sweep"]
             if r["N"] > 32 and r["converged"]]
    hit = [x for x in rows if x[1] <= default_error]
    if hit:
        reach.append((hit[0][2], scheme_name, hit[0][0], hit[0][1]))
reach.sort()
w("- The seed's default accuracy (the default plan, `paper` at N = 128: relative torque error %s, "
  "%s) is reached first by: %s." % (
      sci(default_error), ms(paper128["solve_time_s"]),
      "; ".join("`%s` at N = %d (%s, %s)" % (sch, N_, sci(e_), ms(t_)) for t_, sch, N_, e_ in reach)))
rp128 = [r for r in by[("rest_to_rest", "paper")]["sweep"] if r["N"] == 128][0]
w("- Every `paper`/`variational` plan's cost is too high by ≈ 3h/T of the optimum on the "
  "rest-to-rest example (the boundary velocities are held over a whole step, see *Why order 1*): "
  "relative cost error %s at N = 128, where 3h/T = %s." % (
      sci(rp128["cost_error"] / by[("rest_to_rest", "paper")]["reference"]["cost"]), sci(3 / 128)))
w("")
w("![error vs N](accuracy_vs_steps.png)")
w("")
w("![error vs solve time](accuracy_vs_time.png)")
w("")
w("## Observed orders")
w("")
so_rest = by[("rest_to_rest", "second_order")]["sweep"]
floor = [r for r in so_rest if r["N"] >= 8192]
w("Least-squares slope of log(error) against log(N) over N = %d … %d. The seed (Sec. 3.4) claims "
  "effective order two for the cost and the trajectory. Above N = 4096 the `second_order` torque "
  "error stops falling (relative %s): the solve's round-off floor, largest at the end torque τ_0 "
  "(comparing the plans at N and 2N node by node puts the largest difference at k = 0); "
  "effort, trajectory and miss keep order 2 to N = %d." % (
      FIT_FROM, FIT_TO, ", ".join("%s at N = %d" % (sci(r["torque_error"] / r["max_torque"]), r["N"])
                                  for r in floor), so_rest[-1]["N"]))
w("")
w("| case | scheme | cost | trajectory | torque | attitude miss | velocity miss | attitude miss, step-start hold | seed's claim |")
w("|---|---|---|---|---|---|---|---|---|")
for c in cases:
    w("| %s | %s | %.2f | %.2f | %.2f | %.2f | %.2f | %.2f | 2 |" % (
        c["scene"], c["scheme"], fit_order(c["sweep"], "cost_error"),
        fit_order(c["sweep"], "trajectory_error"), fit_order(c["sweep"], "torque_error"),
        fit_order(c["sweep"], "attitude_miss"), fit_order(c["sweep"], "velocity_miss"),
        fit_order(c["sweep"], "attitude_miss_step_start")))
w("")
w("`fourth_order` over N = %d … %d (before the torque's round-off floor; its attitude miss is that "
  "of the cubic hold):" % (EARLY_FROM, EARLY_TO))
w("")
w("| case | cost | trajectory | torque | attitude miss | velocity miss |")
w("|---|---|---|---|---|---|")
for c in cases:
    if c["scheme"] != "fourth_order":
        continue
    w("| %s | %.2f | %.2f | %.2f | %.2f | %.2f |" % (
        c["scene"], *[fit_order(c["sweep"], k, EARLY_FROM, EARLY_TO) for k in
                      ("cost_error", "trajectory_error", "torque_error", "attitude_miss",
                       "velocity_miss")]))
w("")
w("The planner uses the documented orders (`measuredOrder()` in `src/analysis/accuracy.cpp`): cost "
  "error 1 (`paper`, `variational`), 2 (`second_order`) and 4 (`fourth_order`), attitude miss 1 "
  "(`paper`), 2 (`variational`, `second_order`) and 4 (`fourth_order`); "
  "`FourthOrder.SmallSweepMeasuresOrderFourInEveryMeasure` measures ≥ 3.5 in every measure on "
  "N = 32 … 256 (test_fourth_order.cpp). "
  "`MeasuredOrders.SmallSweepAgreesWithDocumentedOrders` re-measures them (and trajectory/torque "
  "= 1, or 2 for `second_order`, which must also reach ≥ 1.9 in every measure) on N = 128 … 1024 "
  "for both cases and all schemes and fails if any differs by more than 0.2.")
w("")
w("### Why order 1 and not two (paper, variational)")
w("")
w("`second_order` removes defects 1 and 3 (the boundary velocities act at t = 0 and T through the "
  "node momenta Π_0 = JΩ(0), Π_N = JΩ(T), with the end torques τ_0, τ_N as unknowns and the "
  "trapezoidal weights ½ at the ends) and uses the symmetric integrator of item 2: "
  "docs/design/second_order.md derives it.")
w("")
w("1. **The boundary velocities are held over a whole step.** The discrete problem fixes "
  "R_1 = R_0 exp(hΩ_0) and R_{N−1} = R_N exp(−hΩ_{N−1}): the prescribed velocity acts over the "
  "first and last *step*, not at the instants 0 and T. For J = jI rest to rest the discrete optimum "
  "is exactly a cubic in k with zero slope at k ≈ ½ and N − ½ (its fourth difference vanishes), "
  "i.e. the continuous optimum of a maneuver h shorter: cost ∝ 1/(T − h)³, relative error "
  "3h/T + O(h²), trajectory error O(h). On the seed's (anisotropic) rest-to-rest example the "
  "measured relative cost error times N/3 is %s (N = 128 … %d, paper), i.e. exactly this term. "
  "Symplectic conjugacy (Sec. 3.4) would give order two only if the boundary data were "
  "pre-processed by the conjugating map T⁻¹, which neither the seed's Sec. 4 nor this planner do."
  % (", ".join("%.3f" % (r["cost_error"] / by[("rest_to_rest", "paper")]["reference"]["cost"] * r["N"] / 3)
               for r in by[("rest_to_rest", "paper")]["sweep"][3::2]), cases[0]["sweep"][-1]["N"]))
w("2. **The `paper` scheme is a first-order integrator of the rigid body.** Its step holds the "
  "body velocity log(F_k)/h constant over the step and applies the momentum update "
  "JΩ_k = F_kᵀ(hτ_k + JΩ_{k−1}) (seed eq. (18)); the gyroscopic term is then first-order "
  "accurate, so even the torques of its exact discrete optimum, applied to the real body, miss by "
  "O(h). The `variational` scheme (Lee–Leok–McClamroch) is a symmetric second-order integrator: "
  "its plans land to O(h²) in attitude although their cost and trajectory are O(h) off (item 1). "
  "(For J = jI and rest to rest both schemes land exactly: there is no gyroscopic term.)")
w("3. **The terminal velocity miss stays order 1 when Ω_T ≠ 0** (slew-up, both schemes): Ω_{N−1} "
  "is imposed on the last step (paper: its mean velocity; variational: the velocity at its start, "
  "t_{N−1}), h/2 or h before T.")
w("4. The seed's printed necessary conditions drop a dexp factor (docs/results/necessary_conditions.md); "
  "that does not enter here: the planner minimizes the discrete cost exactly (Newton on the exact "
  "gradient), so these orders belong to the discretization, not to a solver defect.")
w("")
w("### The hold")
w("")
w("`second_order`: τ_k are samples of τ(t_k) at every node, ends included, and the miss reported "
  "is that of the first-order hold (τ linear between the nodes), which keeps order 2. "
  "`fourth_order`: its τ_k are O(h⁴) samples, and the hold is the local cubic through the four "
  "nearest node torques (`cubicHoldCoefficients`), O(h⁴) too; the tracker and `simulate_torques` "
  "integrate it with RKMK4 (`replayPlan`), the study here with the order-16 integrator. The "
  "step-start column holds τ_k over [t_k, t_{k+1}) as for the other schemes.")
w("")
w("`paper` and `variational` apply τ_k as a momentum impulse hτ_k at the node t_k (discrete_scheme.hpp: the "
  "momentum of step k is that of step k−1 plus hτ_k), so τ_k samples τ(t_k) (torque error "
  "column) and the matching hold is **node-centred**: τ_k over [t_k − h/2, t_k + h/2] (τ_0 = 0 "
  "over [0, h/2], τ_N = 0 over [T − h/2, T]). That is the miss reported. Holding τ_k over the step "
  "[t_k, t_{k+1}) instead (a naive controller, column *step-start hold*) delays the whole torque "
  "history by h/2. Starting and ending at rest that costs almost nothing (the delayed body ends "
  "where the undelayed one was h/2 earlier, and it is at rest then: rest-to-rest keeps its order), "
  "but with Ω_T ≠ 0 the body falls h/2·Ω_T short: order 1 on slew-up for both schemes (variational "
  "at N = %d: %s rad instead of %s)." % (
      by[("slew_up", "variational")]["sweep"][-1]["N"],
      sci(by[("slew_up", "variational")]["sweep"][-1]["attitude_miss_step_start"]),
      sci(by[("slew_up", "variational")]["sweep"][-1]["attitude_miss"])))
w("")
w("## The continuous reference")
w("")
w("Minimize ½∫₀ᵀ|τ|²dt subject to Ṙ = RΩ^, JΩ̇ = (JΩ)×Ω + τ and R, Ω given at 0 and T (seed 000, "
  "Problem 2.2). Pontryagin with the costate of R trivialized on the left (π ∈ ℝ³, so that "
  "⟨p_R, RΩ^⟩ = π·Ω) and the costate of Ω written λ = Jν:")
w("")
w("    H = ½|τ|² + π·Ω + ν·((JΩ)×Ω + τ)        ∂H/∂τ = 0  ⇒  τ = −ν")
w("    π̇ = π × Ω                                (H does not depend on R: Rπ is constant)")
w("    Jν̇ = −π − J(Ω × ν) + (JΩ) × ν             (λ̇ = −∂H/∂Ω, ∂/∂Ω[(JΩ)×Ω] = (JΩ)^ − Ω^J)")
w("")
w("and H = −½|ν|² + π·Ω + ν·((JΩ)×Ω) is conserved. This is the first-order (Hamiltonian) form of "
  "the seed's Theorem 2.1; we did not use the printed fourth-order equation. The flow "
  "(quaternion of R, Ω, π, ν and the running cost) is integrated by Gragg–Bulirsch–Stoer "
  "extrapolation of order 16 (`extrapolation_integrator.hpp`); π(0), ν(0) are found by multiple "
  "shooting (8 intervals, Newton on the 6 + 12·7 node defects, exact sensitivities by dual numbers "
  "through the same integrator, backtracking), started from the `paper` plan at N = 256 "
  "(ν ≈ −τ_k, π from the ν equation with ν̇ by differences).")
w("")
w("Checks: the isotropic closed form (J = jI, θ(t) = θ(3s² − 2s³), cost 6j²θ²/T³) to 1e-12 "
  "(`ContinuousReference.MatchesIsotropicClosedForm`); on the seed's J the Hamiltonian is conserved, "
  "another shooting grid and step give the same cost, and the discrete plans converge to it "
  "(`AnisotropicExtremalIsConsistent`, `DiscretePlansConvergeToIt`).")
w("")
w("| case | continuous cost ½∫\\|τ\\|²dt [N² m² s] | Newton iterations | max defect | integration error (H vs H/2) | H drift | \\|cost − cost(16 intervals)\\| | attitude vs 16 intervals at 0.37 T | solve time |")
w("|---|---|---|---|---|---|---|---|---|")
for c in cases:
    if c["scheme"] != "paper":
        continue
    r = c["reference"]
    w("| %s | %.13f | %d | %.1e | %.1e | %.1e | %.1e | %.1e rad | %s |" % (
        c["scene"], r["cost"], r["iterations"], r["max_defect"], r["integration_error"],
        r["hamiltonian_drift"], r["cost_vs_finer"], r["attitude_vs_finer"], ms(r["solve_time_s"])))
w("")
w("## Plans to a requested accuracy: is the estimate honest?")
w("")
w("`planManeuver` with `PlanningProblem::accuracy` (CLI `--target-miss RAD` / "
  "`--target-cost-error E` [`--scheme auto`], service/action fields `accuracy_measure`, "
  "`accuracy_target`) solves N = 64 (and 32) of each candidate scheme, predicts "
  "N = 1.15·64·(e₆₄/target)^{1/p} from the documented order p, solves there and checks; if the "
  "check fails it refines (at most 4 times). The estimate returned with the plan is, for "
  "`terminal_miss`, the zero-order-hold replay of the plan itself (a measurement, accurate to "
  "~1e-13) and, for `cost_error`, the Richardson estimate |hC(N) − h′C(N/2)|/(2^p − 1) (needs the "
  "plan at N/2 too). *Predicted* is what the coarse resolutions promised before solving at N; "
  "*actual* is measured against the continuous reference. Time: the whole request (coarse "
  "resolutions included) and a plain solve at the chosen N.")
w("")
w("For `terminal_miss` the returned estimate *is* a measurement of the plan (the same replay the "
  "study uses), so actual/estimated = 1 by construction; the honest test there is the prediction "
  "made from N = 64 alone (column actual/predicted). For `cost_error` both columns are genuine "
  "estimates against the continuous reference.")
w("")
w("| case | scheme | measure | target | N chosen | predicted | estimated (returned) | actual | actual/predicted | actual/estimated | time (request) | time (plain solve at N) | N tried |")
w("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
for c in cases:
    for t in c["targets"]:
        if not t["converged"]:
            w("| %s | %s | %s | %.0e | — | | | | | | %s | | refused: %s |" % (
                c["scene"], c["scheme"], t["measure"], t["target"], ms(t["solve_time_s"]),
                "needs N > max_steps (order-1 miss)" if t["tried"].count(",") == 0 else t["tried"]))
            continue
        w("| %s | %s | %s | %.0e | %d | %s | %s | %s | %.3f | %.3f | %s | %s | %s |" % (
            c["scene"], c["scheme"], t["measure"], t["target"], t["N"], sci(t["predicted"]),
            sci(t["estimated"]), sci(t["actual"]), t["actual"] / t["predicted"],
            t["actual"] / t["estimated"],
            ms(t["solve_time_s"]), ms(t["plain_solve_time_s"]), t["tried"]))
w("")
ratios = [t["actual"] / t["estimated"] for c in cases for t in c["targets"]
          if t["converged"] and t["measure"] == "cost_error" and c["scheme"] != "fourth_order"]
pred = [t["actual"] / t["predicted"] for c in cases for t in c["targets"] if t["converged"]
        and c["scheme"] != "fourth_order"]
w("Every plan that was returned meets its target in the actual error (%d of %d requests; the "
  "others were refused). Without `fourth_order` (below), the cost estimates are within %.1f %% of the actual error, the "
  "predictions from N = 64 within %.0f %% (actual/predicted %.2f … %.2f), so no refinement round "
  "was needed." % (sum(1 for c in cases for t in c["targets"] if t["converged"]),
                   sum(len(c["targets"]) for c in cases),
                   100 * max(abs(r - 1) for r in ratios), 100 * max(abs(r - 1) for r in pred),
                   min(pred), max(pred)) + " "
  "The margin of 15 % in the predicted N is why the returned errors sit at 0.7–0.9 of the target. Requests the "
  "`paper` scheme cannot meet within `max_steps` (2^18 in the core, `~max_steps` in the node) are "
  "refused after the coarse resolution, with the N they would need in the message.")
w("")
w("`fourth_order` meets the cost targets of this table already at the smallest N the planner "
  "chooses (16 … 24). There its Richardson estimate |hC(N) − h′C(N/2)|/15 is rough (actual/estimated %s: "
  "conservative on rest-to-rest, up to 1.7× low on slew-up, where N/2 = 8 … 12 is not yet in the "
  "asymptotic range); the targets are met by a wide margin all the same. Its miss "
  "predictions: actual/predicted %s." % (
      ", ".join("%.2f" % (t["actual"] / t["estimated"]) for c in cases for t in c["targets"]
                if t["converged"] and c["scheme"] == "fourth_order" and t["measure"] == "cost_error"),
      ", ".join("%.2f" % (t["actual"] / t["predicted"]) for c in cases for t in c["targets"]
                if t["converged"] and c["scheme"] == "fourth_order"
                and t["measure"] == "terminal_miss")))
w("")
w("## Measured data")
w("")
for c in cases:
    w("### %s, %s" % (c["scene"], c["scheme"]))
    w("")
    w("| N | solve time | h·Σ½\\|τ_k\\|² | cost error | trajectory error [rad] | torque error [N m] | attitude miss [rad] | velocity miss [rad/s] | attitude miss, step-start hold |")
    w("|---|---|---|---|---|---|---|---|---|")
    for r in c["sweep"]:
        w("| %d | %s | %.10f | %s | %s | %s | %s | %s | %s |" % (
            r["N"], ms(r["solve_time_s"]), r["cost_integral"], sci(r["cost_error"]),
            sci(r["trajectory_error"]), sci(r["torque_error"]), sci(r["attitude_miss"]),
            sci(r["velocity_miss"]), sci(r["attitude_miss_step_start"])))
    w("")
open(docs + "/accuracy.md", "w").write("\n".join(out) + "\n")
print("wrote %s/accuracy.md, accuracy_vs_steps.png, accuracy_vs_time.png" % docs)
