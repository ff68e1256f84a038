#!/usr/bin/python3
"""Plots the long-run energy behaviour written by integrator_study (docs/results/energy_*.csv)."""
import csv
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

out = sys.argv[1] if len(sys.argv) > 1 else "docs/results"
fig, axes = plt.subplots(1, 2, figsize=(11, 4))
for scheme, ax in zip(["paper", "variational"], axes):
    t, e, p = [], [], []
    with open(f"{out}/energy_{scheme}.csv") as f:
        for row in csv.DictReader(f):
            t.append(float(row["t"]))
            e.append(float(row["relative_energy_error"]))
            p.append(float(row["relative_momentum_error"]))
    ax.plot(t, e, label="(E - E0)/E0")
    ax.plot(t, p, label="|pi - pi0|/|pi0|")
    ax.set_title(f"{scheme}: free rigid body, h = 0.01 s")
    ax.set_xlabel("t [s]")
    ax.grid(True, alpha=0.3)
    ax.legend()
fig.tight_layout()
fig.savefig(f"{out}/integrators_energy.png", dpi=110)
