#!/usr/bin/python3
"""Plots the PMP switching functions of minimum-time plans.

usage: plot_switching.py OUT.png TITLE1 CSV1 [TITLE2 CSV2 ...]
Each CSV is switching_functions' output (k, t, tau, sigma, bounds). One column per plan, one row
per body axis: tau_i/a_i (steps) and sigma_i / max|sigma_i| (line); the torque switches where sigma
changes sign.
"""
import csv
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

out, pairs = sys.argv[1], sys.argv[2:]
plans = [(pairs[i], list(csv.DictReader(open(pairs[i + 1])))) for i in range(0, len(pairs), 2)]
fig, axes = plt.subplots(3, len(plans), figsize=(5.5 * len(plans), 7), sharex="col", squeeze=False)
for col, (title, rows) in enumerate(plans):
    t = [float(r["t"]) for r in rows]
    for i, name in enumerate("xyz"):
        ax = axes[i][col]
        tau = [float(r["t" + name]) / float(r["a" + name]) for r in rows]
        sigma = [float(r["s" + name]) for r in rows]
        scale = max(abs(s) for s in sigma) or 1.0
        ax.step(t, tau, where="mid", color="tab:blue", label="τ/a (plan)")
        ax.plot(t, [s / scale for s in sigma], color="tab:red", label="σ / max|σ| (switching fn)")
        ax.axhline(0.0, color="gray", lw=0.5)
        ax.set_ylim(-1.15, 1.15)
        ax.set_ylabel("axis " + name)
        if i == 0:
            ax.set_title(title)
        if i == 2:
            ax.set_xlabel("t [s]")
        if i == 0 and col == 0:
            ax.legend(loc="lower left", fontsize=8)
fig.tight_layout()
fig.savefig(out, dpi=110)
print("wrote", out)
