#!/usr/bin/env python3
"""How much a pressure step damps a sound mode, per step, against x = omega dt.

Usage: scripts/step_damping.py [--x X ...]

Prints the damping a step, -ln of the amplification's largest root, for the
theta-method (kick's `method.projection.theta`) and for the generalised-alpha
step for first-order systems (Jansen, Whiting and Hulbert, 2000; not built in
kick), applied to one undamped mode y' = i omega y. The sound rule of the
Methods table asks mode 1 of the acoustic box (x = 0.61 at 1.5 MPa and 1 ms)
to decay below 1 /s, that is below 0.001 a step at that x
(docs/findings/projection_mac.md, "The sound against the settling").
Standard library only.
"""

import argparse
import cmath
import math

THETAS = (0.5, 0.502, 0.505, 0.51, 1.0)
RHO_INFINITY = (0.95, 0.9, 0.8, 0.7, 0.6, 0.5)
DEFAULT_X = (0.07, 0.61, 1.0, 3.0, 10.0)


def theta_damping(theta, x):
    """-ln|g| with |g|^2 = (1 + (1 - theta)^2 x^2) / (1 + theta^2 x^2)."""
    g2 = (1.0 + (1.0 - theta) ** 2 * x * x) / (1.0 + theta * theta * x * x)
    return -0.5 * math.log(g2) + 0.0  # + 0.0: theta = 0.5 prints 0, not -0


def alpha_damping(rho_inf, x):
    """-ln of the generalised-alpha step's spectral radius for y' = i x y
    (dt = 1): y1 = y0 + (1 - gamma) v0 + gamma v1 and
    alpha_m v1 + (1 - alpha_m) v0 = i x (alpha_f y1 + (1 - alpha_f) y0).
    The larger root decays slowest: the principal one at small x, and
    rho_inf as x grows."""
    a_m = (3.0 - rho_inf) / (2.0 * (1.0 + rho_inf))
    a_f = 1.0 / (1.0 + rho_inf)
    gamma = 0.5 + a_m - a_f
    lam = 1j * x
    # The step as A [y1, v1] = B [y0, v0]; its amplification is A^-1 B.
    a = ((1.0, -gamma), (-lam * a_f, a_m))
    b = ((1.0, 1.0 - gamma), (lam * (1.0 - a_f), -(1.0 - a_m)))
    det = a[0][0] * a[1][1] - a[0][1] * a[1][0]
    inv = ((a[1][1] / det, -a[0][1] / det), (-a[1][0] / det, a[0][0] / det))
    m = [[sum(inv[i][k] * b[k][j] for k in range(2)) for j in range(2)] for i in range(2)]
    half_trace = (m[0][0] + m[1][1]) / 2.0
    root = cmath.sqrt(half_trace * half_trace - (m[0][0] * m[1][1] - m[0][1] * m[1][0]))
    return -math.log(max(abs(half_trace + root), abs(half_trace - root)))


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--x", type=float, nargs="+", default=list(DEFAULT_X))
    xs = ap.parse_args().x

    def row(label, cells):
        print(f"| {label} | " + " | ".join(cells) + " |")

    row("step", [f"x = {x:g}" for x in xs])
    print("|---|" + "---|" * len(xs))
    for theta in THETAS:
        row(f"theta = {theta:g}", [f"{theta_damping(theta, x):.3g}" for x in xs])
    for rho in RHO_INFINITY:
        row(f"generalised-alpha, rho_inf = {rho:g}", [f"{alpha_damping(rho, x):.3g}" for x in xs])


if __name__ == "__main__":
    main()
