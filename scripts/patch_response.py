#!/usr/bin/env python3
"""Usage: scripts/patch_response.py CASE/particles --region X0 Y0 X1 Y1 [--cell H]

The kick a planted push leaves in the flow: for each VTK file of a run
(its `output.vtk_times`), the mean velocity of the particles the region
held in the first file (followed by id), against the median velocity of
the particles 2 to 4 cells from the region (the jump rule's ring) and of
those within 1 cell of it. The excess over the ring is what the velocity-
jump rule can see; a push the flow spreads to its neighbours before it
builds up leaves less than it planted (docs/findings/detector_calibration.md).
Standard library only (the VTK reader of scripts/check_vtu.py)."""
import argparse, glob, os, sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
from check_vtu import read_vtu  # noqa: E402


def outside(box, x, y):
    """Chebyshev distance (m) of a point from the box (0 inside)."""
    return max(box[0] - x, 0.0, x - box[2], box[1] - y, 0.0, y - box[3])


def median(values):
    values = sorted(values)
    return values[len(values) // 2] if values else float("nan")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("folder")
    ap.add_argument("--region", type=float, nargs=4, required=True)
    ap.add_argument("--cell", type=float, default=0.01)
    args = ap.parse_args()
    box, h = args.region, args.cell
    files = sorted(glob.glob(os.path.join(args.folder, "*.vtu")))
    if not files:
        sys.exit(f"no .vtu files in {args.folder}")
    patch_ids = None
    print("t_s,patch_vx,patch_vy,adjacent_vy,ring_vy,excess_vy,particles")
    for f in files:
        t, _, n, a = read_vtu(f)
        pts, vel, ids = a["Points"][1], a["velocity"][1], a["id"][1]
        xs = [(pts[3 * i], pts[3 * i + 1]) for i in range(n)]
        vs = [(vel[3 * i], vel[3 * i + 1]) for i in range(n)]
        if patch_ids is None:
            patch_ids = {ids[i] for i in range(n) if outside(box, *xs[i]) == 0.0}
        patch = [vs[i] for i in range(n) if ids[i] in patch_ids]
        if not patch:
            sys.exit("the region holds no particle in the first file")
        d = [outside(box, *x) for x in xs]
        ring = median(vs[i][1] for i in range(n) if 2 * h <= d[i] < 4 * h)
        adjacent = median(vs[i][1] for i in range(n) if 0.0 < d[i] < h)
        vx = sum(v[0] for v in patch) / len(patch)
        vy = sum(v[1] for v in patch) / len(patch)
        print(f"{t:.4f},{vx:.4f},{vy:.4f},{adjacent:.4f},{ring:.4f},{vy - ring:.4f},{len(patch)}")


if __name__ == "__main__":
    main()
