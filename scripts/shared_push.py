#!/usr/bin/env python3
"""Usage: scripts/shared_push.py PLANTED/particles CLEAN/particles [--spread T0 T1]

How much of a planted push the water keeps to the patch: two runs of the
same case to the same VTK times (output.vtk_times), one with a [[perturb]]
and one without, matched by particle id. At each time common to both it
prints the largest departure of the planted run's velocity from the clean
run's (m/s), and how many particles depart by more than 0.02 and 0.1 m/s:
a push the water shares moves many particles a little, one it keeps moves
the patch alone.

With --spread T0 T1 it also prints the moving window's threshold over the
span T0..T1 in the clean run, max(0.02, 5 s) per cell (docs/physics.md
section 4: each cell's ring, 2 to 4 cells out, holds the mean change of
the particles that started the span in it; s is 1.4826 times the median
distance from the plane fitted to them), as quantiles over the cells.
Standard library only."""
import math
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from fixed_span_jumps import particles  # noqa: E402

# The monitor's rule (crates/monitor/src/jump.rs): h, the ring's outer
# radius, jump_z, jump_speed and MIN_RING_CELLS.
H, RING, Z, FLOOR, MIN_RING_CELLS = 0.01, 4, 5.0, 0.02, 6


def load(folder):
    """{time: {id: (x, y, vx, vy)}} of every .vtu in the folder."""
    out = {}
    for name in sorted(os.listdir(folder)):
        if name.endswith(".vtu"):
            t, by_id = particles(os.path.join(folder, name))
            out[round(t, 6)] = by_id
    return out


def lower_median(values):
    s = sorted(values)
    return s[(len(s) - 1) // 2]


def cell_changes(start, end):
    """Per cell of the span's start positions, the mean change of its particles."""
    sums = {}
    for i, (x, y, u, v) in start.items():
        if i in end:
            c = (int(x / H), int(y / H))
            s = sums.setdefault(c, [0, 0.0, 0.0])
            s[0] += 1
            s[1] += end[i][2] - u
            s[2] += end[i][3] - v
    return {c: (s[1] / s[0], s[2] / s[0]) for c, s in sums.items()}


def ring_of(mean, ci, cj, nx):
    """The ring's cells as (di, dj, change), walls mirrored (normal flipped)."""
    pts = []
    for j in range(cj - RING, cj + RING + 1):
        for i in range(ci - RING, ci + RING + 1):
            if max(abs(i - ci), abs(j - cj)) < 2:
                continue
            ii, fx = (-1 - i, True) if i < 0 else ((2 * nx - 1 - i, True) if i >= nx else (i, False))
            jj, fy = (-1 - j, True) if j < 0 else (j, False)
            if (ii, jj) in mean:
                fu, fv = mean[(ii, jj)]
                pts.append((i - ci, j - cj, -fu if fx else fu, -fv if fy else fv))
    return pts


def spread_of(pts):
    """1.4826 times the median distance from the plane fitted to the ring."""
    n = len(pts)
    sx, sy = sum(p[0] for p in pts), sum(p[1] for p in pts)
    cxx = sum(p[0] ** 2 for p in pts) - sx * sx / n
    cyy = sum(p[1] ** 2 for p in pts) - sy * sy / n
    cxy = sum(p[0] * p[1] for p in pts) - sx * sy / n
    det = cxx * cyy - cxy * cxy
    grads = []
    for k in (2, 3):
        sf = sum(p[k] for p in pts)
        cxf = sum(p[0] * p[k] for p in pts) - sx * sf / n
        cyf = sum(p[1] * p[k] for p in pts) - sy * sf / n
        ok = det > 1e-9 * max(cxx * cyy, 1.0)
        grads.append(((cyy * cxf - cxy * cyf) / det, (cxx * cyf - cxy * cxf) / det) if ok else (0.0, 0.0))
    level = [(p[2] - p[0] * grads[0][0] - p[1] * grads[0][1],
              p[3] - p[0] * grads[1][0] - p[1] * grads[1][1]) for p in pts]
    cx, cy = lower_median(l[0] for l in level), lower_median(l[1] for l in level)
    return 1.4826 * lower_median(math.hypot(l[0] - cx, l[1] - cy) for l in level)


def thresholds(clean, t0, t1):
    mean = cell_changes(clean[t0], clean[t1])
    nx = 1 + max(c[0] for c in mean)
    out = []
    for (ci, cj) in mean:
        pts = ring_of(mean, ci, cj, nx)
        if len(pts) >= MIN_RING_CELLS:
            out.append(max(FLOOR, Z * spread_of(pts)))
    return sorted(out)


def main(argv):
    if len(argv) not in (3, 6) or (len(argv) == 6 and argv[3] != "--spread"):
        sys.exit(__doc__)
    planted, clean = load(argv[1]), load(argv[2])
    print("t (s)     largest departure (m/s)  particles > 0.02  > 0.1")
    for t in sorted(set(planted) & set(clean)):
        d = [math.hypot(p[2] - clean[t][i][2], p[3] - clean[t][i][3])
             for i, p in planted[t].items() if i in clean[t]]
        print("%-9.6f %-24.4f %-17d %d" % (t, max(d), sum(x > 0.02 for x in d), sum(x > 0.1 for x in d)))
    if len(argv) == 6:
        # The output times nearest those asked (a VTK is written at the
        # first step ending at or after its time).
        t0, t1 = (min(clean, key=lambda t: abs(t - float(a))) for a in argv[4:6])
        th = thresholds(clean, t0, t1)
        q = lambda f: th[int(f * (len(th) - 1))]
        print("moving window's threshold over %g..%g s, %d cells: 10 %% %.3f, median %.3f, 90 %% %.3f, "
              "largest %.3f m/s; at the floor: %d" % (t0, t1, len(th), q(0.1), q(0.5), q(0.9), th[-1],
                                                    sum(x <= FLOOR * (1 + 1e-9) for x in th)))


if __name__ == "__main__":
    main(sys.argv)
