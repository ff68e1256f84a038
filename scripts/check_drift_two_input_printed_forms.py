#!/usr/bin/env python3
"""Independent check (numpy/scipy, not the C++ code) of the seed 001 printed formulas against a
high-accuracy numerical solution of the Lie-Poisson equations (3.15)-(3.17). Prints, for each
printed form and for its corrected form, max |p_formula(t) - p_numeric(t)| over t in [0, 3].
  /usr/bin/python3 scripts/check_drift_two_input_printed_forms.py
"""
import numpy as np
from scipy.integrate import solve_ivp
from scipy.special import ellipj, ellipkinc


def flow(p0, c1, c2, ts):
    f = lambda t, p: np.cross(p, [p[0] / c1, p[1] / c2, 1.0])  # noqa: E731
    return solve_ivp(f, (0, ts[-1]), p0, t_eval=ts, rtol=1e-13, atol=1e-13, method="DOP853").y.T


ts = np.linspace(0, 3, 301)

# Prop. 4.2, c1 = c2 = c
c, p0 = 2.0, np.array([0.6, -0.8, 0.5])
num = flow(p0, c, c, ts)
k1, k2 = p0[0] ** 2 + p0[1] ** 2, p0[2]
k3p = -np.arctan(p0[1] / p0[0])
printed = np.c_[np.sqrt(k1) * np.cos((1 - k2 / c) * ts + k3p), np.sqrt(k1) * np.sin((1 - k2 / c) * ts + k3p), k2 + 0 * ts]
k3 = np.arctan2(p0[1], p0[0])
fixed = np.c_[np.sqrt(k1) * np.cos((k2 / c - 1) * ts + k3), np.sqrt(k1) * np.sin((k2 / c - 1) * ts + k3), k2 + 0 * ts]
print("Prop 4.2 printed  (rate 1 - k2/c, k3 = -atan(p2/p1)): max err %.2e" % np.abs(printed - num).max())
print("Prop 4.2 corrected (rate k2/c - 1, k3 = atan2(p2, p1)): max err %.2e" % np.abs(fixed - num).max())

# Prop. 4.3 case (i), c2 < c1: a costate in case (i)
c1, c2 = 3.0, 1.0
rng = np.random.default_rng(3)
while True:
    p0 = rng.normal(size=3)
    h0 = 0.5 * (p0[0] ** 2 / c1 + p0[1] ** 2 / c2) + p0[2]
    c0 = p0 @ p0
    if h0 * h0 > c0:
        s = np.sqrt(h0 * h0 - c0)
        al, be = h0 + s, h0 - s
        if h0 - c1 < -s and s < h0 - c2:
            break
num = flow(p0, c1, c2, ts)
a2, b2 = (al - c2) / (be - c2), (al - c1) / (be - c1)
a, b = np.sqrt(a2), np.sqrt(b2)
mu1, mu2 = (be - c2) / (2 * s), (c1 - be) / (2 * s)
k = b / a
y = (p0[2] - al) / (p0[2] - be) / a  # dc(u0) = phi(0)/a
th = np.arcsin(np.sqrt(max(0.0, (y * y - 1) / (y * y - k * k))))
# the phase u0 = F(theta0, k): theta0 is one of four values (branch of arcsin, sign of cn); the
# one matching p3 best is taken, so only the rate of the argument is under test
thetas = [th, -th, np.pi - th, np.pi + th]


def p3_dc(rate):
    best = np.inf
    for t0 in thetas:
        sn, cn, dn, _ = ellipj(rate * ts + ellipkinc(t0, k * k) if abs(t0) <= np.pi / 2 else
                               rate * ts + 2 * ellipkinc(np.pi / 2, k * k) * np.sign(t0)
                               - ellipkinc(np.sign(t0) * np.pi - t0, k * k), k * k)
        phi = a * dn / cn
        best = min(best, np.abs((al - be * phi) / (1 - phi) - num[:, 2]).max())
    return best


M_stmt = mu1 * mu2            # statement: M = -(h0-c2-s)(h0-c1-s)/(4 s^2) = mu1 mu2
M_proof = np.sqrt(mu1 * mu2)  # proof: M = sqrt(mu1 mu2)
for name, rate in [("statement: M = mu1 mu2, argument Omega t", (al - be) * M_stmt / np.sqrt(c1 * c2)),
                   ("M = sqrt(mu1 mu2), argument Omega t (no factor a)", (al - be) * M_proof / np.sqrt(c1 * c2)),
                   ("corrected: M = sqrt(mu1 mu2), argument a Omega t", a * (al - be) * M_proof / np.sqrt(c1 * c2))]:
    print("Prop 4.3 (i), phi = a dc, %-52s max err of p3 %.2e" % (name + ":", p3_dc(rate)))
print("(p0 = %s, c1 = %g, c2 = %g, a = %.6f, b = %.6f, mu1 mu2 = %.6f)" % (p0, c1, c2, a, b, mu1 * mu2))
