#!/usr/bin/env python3
"""Plot of seed 001, Remark 3.1: extremal costates p(t) of the drift + two-input system lie on
the intersection of the sphere C = |p|^2 = const (Casimir) with the paraboloid
H = (p1^2/c1 + p2^2/c2)/2 + p3 = const (reduced Hamiltonian).

Reads the CSV written by `drift_two_input_example` (columns orbit,c1,c2,t,p1,p2,p3,H,C; orbit 0 is
the worked example's extremal) and writes docs/results/drift_two_input_sphere.png.
Run with /usr/bin/python3 (numpy, matplotlib):
  /usr/bin/python3 scripts/plot_drift_two_input.py [docs/results/drift_two_input_orbits.csv] [out.png]
"""
import csv
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402


def main():
    src = sys.argv[1] if len(sys.argv) > 1 else "docs/results/drift_two_input_orbits.csv"
    out = sys.argv[2] if len(sys.argv) > 2 else "docs/results/drift_two_input_sphere.png"
    orbits = {}
    with open(src) as f:
        for row in csv.DictReader(f):
            orbits.setdefault(int(row["orbit"]), []).append(row)
    c1, c2 = float(orbits[0][0]["c1"]), float(orbits[0][0]["c2"])
    arrays = {i: np.array([[float(r[k]) for k in ("p1", "p2", "p3", "H", "C")] for r in rows])
              for i, rows in orbits.items()}
    ex = arrays[0]
    radius = np.sqrt(ex[0, 4])
    h0 = ex[0, 3]

    fig = plt.figure(figsize=(8, 7.5))
    ax = fig.add_subplot(111, projection="3d")
    # sphere C = C0
    u, v = np.mgrid[0:2 * np.pi:60j, 0:np.pi:30j]
    ax.plot_wireframe(radius * np.cos(u) * np.sin(v), radius * np.sin(u) * np.sin(v),
                      radius * np.cos(v), color="0.8", linewidth=0.4)
    # paraboloid H = H0 of the example: p3 = H0 - (p1^2/c1 + p2^2/c2)/2, inside the sphere's box
    a, b = np.mgrid[-radius:radius:40j, -radius:radius:40j]
    z = h0 - 0.5 * (a ** 2 / c1 + b ** 2 / c2)
    z = np.where(np.abs(z) <= 1.05 * radius, z, np.nan)
    ax.plot_surface(a, b, z, color="tab:orange", alpha=0.25, linewidth=0)
    hs = [arr[0, 3] for i, arr in arrays.items() if i != 0]
    cmap = plt.get_cmap("viridis")
    for i, arr in arrays.items():
        if i == 0:
            continue
        t = (arr[0, 3] - min(hs)) / (max(hs) - min(hs) + 1e-300)
        ax.plot(arr[:, 0], arr[:, 1], arr[:, 2], color=cmap(t), linewidth=1.0)
    ax.plot(ex[:, 0], ex[:, 1], ex[:, 2], color="tab:red", linewidth=3.0,
            label="worked example: sphere C = %.3f \u2229 paraboloid H = %.3f" % (ex[0, 4], h0))
    ax.scatter([ex[0, 0]], [ex[0, 1]], [ex[0, 2]], color="k", s=30, label="p(0)")
    ax.set_xlabel("p1")
    ax.set_ylabel("p2")
    ax.set_zlabel("p3")
    ax.set_box_aspect((1, 1, 1))
    ax.set_title("Extremal costates on C = |p|\u00b2 = const (seed 001, Remark 3.1)\n"
                 "c1 = %g, c2 = %g; thin lines: other orbits on the same sphere, colored by H" % (c1, c2))
    ax.legend(loc="lower left", fontsize=8)
    fig.tight_layout()
    fig.savefig(out, dpi=120)
    print("wrote", out)


if __name__ == "__main__":
    main()
