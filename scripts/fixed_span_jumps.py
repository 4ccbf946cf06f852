#!/usr/bin/env python3
"""Usage: scripts/fixed_span_jumps.py CASE/particles [CASE/particles ...] [--cell H] [--stride K]

The velocity-jump rule over a fixed span, the same at every time step:
between consecutive VTK files of a run (its `output.vtk_times`, K files
apart), each particle's velocity change (followed by id) against its
local flow's, the component-wise median of the mean changes of the cells
2 to 4 cells away (in the box only: no wall images), with 1.4826 times
the median distance from it as the spread. A particle jumps when it
departs by at least max(0.02 m/s, 5 spreads), its speed grew and the
ring's median change is below 0.5 m/s (calm); jumping particles in
8-adjacent cells of at least 4 make a cluster. The monitor's rule judges
moving particles per step, so its sensitivity to a sustained acceleration
grows with the step; this judges every method over the same span
(docs/findings/projection_mac.md, "The dam break's kicks against the
step"). Prints the clusters and their count. Standard library only (the
VTK reader of scripts/check_vtu.py)."""
import argparse, glob, os, sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from check_vtu import read_vtu  # noqa: E402

JUMP_SPEED, JUMP_Z, CALM_CHANGE, CLUSTER = 0.02, 5.0, 0.5, 4


def median(values):
    values = sorted(values)
    n = len(values)
    return 0.5 * (values[(n - 1) // 2] + values[n // 2])


def particles(path):
    """id -> (x, y, vx, vy), and the file's time."""
    t, _, n, a = read_vtu(path)
    pts, vel, ids = a["Points"][1], a["velocity"][1], a["id"][1]
    return t, {ids[i]: (pts[3 * i], pts[3 * i + 1], vel[3 * i], vel[3 * i + 1]) for i in range(n)}


def ring_flow(mean, c):
    """The local flow's change around cell c: median, spread, calm; None
    with fewer than 4 ring cells."""
    ring = [mean[(c[0] + di, c[1] + dj)] for di in range(-4, 5) for dj in range(-4, 5)
            if max(abs(di), abs(dj)) >= 2 and (c[0] + di, c[1] + dj) in mean]
    if len(ring) < 4:
        return None
    mx, my = median([r[0] for r in ring]), median([r[1] for r in ring])
    spread = 1.4826 * median([((r[0] - mx) ** 2 + (r[1] - my) ** 2) ** 0.5 for r in ring])
    calm = median([(r[0] ** 2 + r[1] ** 2) ** 0.5 for r in ring]) < CALM_CHANGE
    return mx, my, spread, calm


def jumps(before, after, h):
    """The jumping particles between two files: (cell, departure) each."""
    change, cells = {}, {}
    for i, (x, y, vx, vy) in after.items():
        if i not in before:
            continue
        _, _, ux, uy = before[i]
        c = (int(x // h), int(y // h))
        change[i] = (c, vx - ux, vy - uy, vx * vx + vy * vy > ux * ux + uy * uy)
        cells.setdefault(c, []).append((vx - ux, vy - uy))
    mean = {c: (sum(d[0] for d in ds) / len(ds), sum(d[1] for d in ds) / len(ds)) for c, ds in cells.items()}
    flows, out = {}, []
    for c, dx, dy, grew in change.values():
        if not grew:
            continue
        if c not in flows:
            flows[c] = ring_flow(mean, c)
        flow = flows[c]
        if flow is None or not flow[3]:
            continue
        departure = ((dx - flow[0]) ** 2 + (dy - flow[1]) ** 2) ** 0.5
        if departure >= max(JUMP_SPEED, JUMP_Z * flow[2]):
            out.append((c, departure))
    return out


def clusters(jumping):
    """Groups of 8-adjacent cells' jumping particles: (count, largest departure, a cell)."""
    by_cell = {}
    for c, d in jumping:
        by_cell.setdefault(c, []).append(d)
    seen, out = set(), []
    for start in by_cell:
        if start in seen:
            continue
        seen.add(start)
        stack, group = [start], []
        while stack:
            c = stack.pop()
            group.append(c)
            for di in (-1, 0, 1):
                for dj in (-1, 0, 1):
                    o = (c[0] + di, c[1] + dj)
                    if o in by_cell and o not in seen:
                        seen.add(o)
                        stack.append(o)
        count = sum(len(by_cell[c]) for c in group)
        if count >= CLUSTER:
            out.append((count, max(d for c in group for d in by_cell[c]), start))
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("folders", nargs="+")
    ap.add_argument("--cell", type=float, default=0.01)
    ap.add_argument("--stride", type=int, default=1)
    args = ap.parse_args()
    for folder in args.folders:
        files = sorted(glob.glob(os.path.join(folder, "*.vtu")))
        if len(files) <= args.stride:
            sys.exit(f"{folder}: fewer than {args.stride + 1} .vtu files")
        frames = [particles(f) for f in files]
        found = []
        for k in range(len(frames) - args.stride):
            (t0, before), (t1, after) = frames[k], frames[k + args.stride]
            for count, largest, cell in clusters(jumps(before, after, args.cell)):
                found.append((t0, t1, count, largest, cell))
        print(f"{folder}: {len(found)} clusters over {len(frames) - args.stride} spans")
        for t0, t1, count, largest, cell in found:
            print(f"  t {t0:.4f}-{t1:.4f} s  {count:3d} particles  largest {largest:.3f} m/s  cell {cell}")


if __name__ == "__main__":
    main()
