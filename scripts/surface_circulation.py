#!/usr/bin/env python3
"""Usage: scripts/surface_circulation.py CASE [CASE ...] [--cell H] [--depth D]

The circulation a wave should not have: an inviscid standing wave started
irrotational stays irrotational (Kelvin), and its particles stay on their
orbits. Per VTK file of each CASE (its `output.vtk_times`):
- vorticity: the rms and the largest |dv/dx - du/dy| (1/s) of the cells'
  mean particle velocity by central differences, over the cells holding 3
  or more particles whose four neighbours do too, at least 3 cells below
  the top cell row holding water and 1 from the left wall (the surface's
  own cells are left out: their means are partial);
- displacement: the rms and the largest distance (mm) each particle that
  started within D (default 0.05 m) of the water's top has moved from
  where it started (linear theory's orbit: a / tanh(k H) across, a up).
Cell size H defaults to 0.01 m (the binning; give the run's own).
Standard library only (the particle reader of scripts/fixed_span_jumps.py).
"""
import argparse
import glob
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from fixed_span_jumps import particles as load  # noqa: E402


def cell_means(particles, h):
    """Cell -> mean particle velocity, over cells holding 3 or more."""
    sums = {}
    for x, y, vx, vy in particles.values():
        s = sums.setdefault((int(x // h), int(y // h)), [0, 0.0, 0.0])
        s[0] += 1
        s[1] += vx
        s[2] += vy
    return {c: (s[1] / s[0], s[2] / s[0]) for c, s in sums.items() if s[0] >= 3}


def vorticity(particles, h):
    """rms and largest vorticity (1/s) below the surface's cells."""
    u = cell_means(particles, h)
    top = max(c[1] for c in u)
    values = []
    for (i, j) in u:
        around = [(i + 1, j), (i - 1, j), (i, j + 1), (i, j - 1)]
        if j > top - 3 or i < 1 or not all(n in u for n in around):
            continue
        dv_dx = (u[(i + 1, j)][1] - u[(i - 1, j)][1]) / (2 * h)
        du_dy = (u[(i, j + 1)][0] - u[(i, j - 1)][0]) / (2 * h)
        values.append(abs(dv_dx - du_dy))
    if not values:
        return 0.0, 0.0
    return (sum(w * w for w in values) / len(values)) ** 0.5, max(values)


def displacement(start, now, near_top):
    """rms and largest distance (m) the particles near the top have moved."""
    d2 = [(now[i][0] - start[i][0]) ** 2 + (now[i][1] - start[i][1]) ** 2
          for i in near_top if i in now]
    if not d2:
        return 0.0, 0.0
    return (sum(d2) / len(d2)) ** 0.5, max(d2) ** 0.5


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("cases", nargs="+")
    ap.add_argument("--cell", type=float, default=0.01)
    ap.add_argument("--depth", type=float, default=0.05)
    args = ap.parse_args()
    for case in args.cases:
        files = sorted(glob.glob(os.path.join(case, "particles", "particles_*.vtu")))
        if not files:
            sys.exit(f"{case}: no particles/particles_*.vtu (set output.vtk_times)")
        _, start = load(files[0])
        top = max(p[1] for p in start.values())
        near_top = [i for i, p in start.items() if p[1] > top - args.depth]
        print(os.path.basename(os.path.normpath(case)))
        print("| t (s) | vorticity rms (1/s) | largest | displacement rms (mm) | largest |")
        print("|---|---|---|---|---|")
        for f in files:
            t, now = load(f)
            w_rms, w_max = vorticity(now, args.cell)
            d_rms, d_max = displacement(start, now, near_top)
            print(f"| {t:.2f} | {w_rms:.4f} | {w_max:.3f} | {1e3 * d_rms:.2f} | {1e3 * d_max:.1f} |")


if __name__ == "__main__":
    main()
