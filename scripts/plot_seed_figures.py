#!/usr/bin/python3
"""Figures like the seed's Figs. 2-7 from the CSVs written by seed_report (docs/results/seed_*.csv)."""
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

out = sys.argv[1] if len(sys.argv) > 1 else "docs/results"
TITLES = {"rest_to_rest": "rest-to-rest, pi/3 about x", "slew_up": "slew-up, pi/6 about x"}


def load(path):
    d = np.genfromtxt(path, delimiter=",", names=True)
    q = np.column_stack([d["qw"], d["qx"], d["qy"], d["qz"]])
    q[q[:, 0] < 0] *= -1
    s = np.linalg.norm(q[:, 1:], axis=1)
    angle = 2 * np.arctan2(s, q[:, 0])
    axis = np.divide(q[:, 1:], s[:, None], out=np.zeros_like(q[:, 1:]), where=s[:, None] > 0)
    w = np.column_stack([d["wx"], d["wy"], d["wz"]])
    tau = np.column_stack([d["tx"], d["ty"], d["tz"]])
    wn = np.linalg.norm(w, axis=1)
    inst = np.divide(w, wn[:, None], out=np.full_like(w, np.nan), where=wn[:, None] > 1e-12)
    return d["t"], w, tau, axis, angle, inst


for example, title in TITLES.items():
    fig, ax = plt.subplots(2, 2, figsize=(12, 8))
    for scheme, style in (("paper", "-"), ("variational", "--")):
        t, w, tau, axis, angle, inst = load(f"{out}/seed_{example}_{scheme}.csv")
        for i, c in enumerate("xyz"):
            color = f"C{i}"
            ax[0, 0].plot(t, w[:, i], style, color=color, label=f"Omega_{c} ({scheme})")
            ax[0, 1].step(t, tau[:, i], style, where="post", color=color, label=f"tau_{c} ({scheme})")
            ax[1, 0].plot(t, axis[:, i], style, color=color, label=f"axis_{c} ({scheme})")
            ax[1, 1].plot(t, inst[:, i], style, color=color, label=f"Omega_{c}/|Omega| ({scheme})")
        ax[1, 0].plot(t, angle, style, color="k", label=f"angle [rad] ({scheme})")
    labels = [("angular velocity [rad/s]", "Fig. 2/5: angular velocity"),
              ("torque [N m]", "Fig. 2/5: control torque"),
              ("", "Fig. 3/6: principal axis and angle of R_k"),
              ("", "Fig. 4/7: instantaneous rotation axis")]
    for a, (ylabel, sub) in zip(ax.flat, labels):
        a.set_title(sub, fontsize=10)
        a.set_xlabel("t [s]")
        a.set_ylabel(ylabel)
        a.grid(True, alpha=0.3)
        a.legend(fontsize=6, ncol=2)
    fig.suptitle(f"Seed example: {title} (solid: paper, dashed: variational), N = 128")
    fig.tight_layout()
    fig.savefig(f"{out}/seed_{example}.png", dpi=100)
