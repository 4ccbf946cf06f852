#!/usr/bin/env python3
"""Growth of Brackbill's ringing perturbation at the slowest flows.

Reads a matrix folder of studies/slow_ringing.toml run with --csv (each
case's ringing.csv: t, E', the drift's energy at the timeseries rows) and
prints, per method, U dt / h and c dt / h, the growth rate of E' per 1000
steps (least-squares slope of ln E') over three windows of the run, E' at
the end over E' at the start, and the time E' needs to grow one e-fold.

    kick matrix studies/slow_ringing.toml --out DIR --jobs 2 --threads 1 --csv
    python3 scripts/slow_ringing.py DIR
"""
import csv
import json
import math
import os
import sys

WINDOWS = [(0.0, 0.2), (0.2, 1.0), (1.0, 2.0)]  # seconds (2000 steps each 0.2 s at dt = 1e-4 s)


def slope_per_1000_steps(rows, t0, t1, dt):
    pts = [(t, math.log(e)) for t, e, _ in rows if t0 <= t <= t1 and e > 0]
    if len(pts) < 3:
        return float("nan")
    n = len(pts)
    mt = sum(p[0] for p in pts) / n
    my = sum(p[1] for p in pts) / n
    sxx = sum((p[0] - mt) ** 2 for p in pts)
    sxy = sum((p[0] - mt) * (p[1] - my) for p in pts)
    return sxy / sxx * dt * 1000.0


def read_case(case_dir):
    with open(os.path.join(case_dir, "summary.json")) as f:
        s = json.load(f)
    rows = []
    with open(os.path.join(case_dir, "ringing.csv")) as f:
        for r in csv.DictReader(f):
            rows.append((float(r["t"]), float(r["e_perturbation"]), float(r["e_drift"])))
    return s, rows


def main():
    if len(sys.argv) != 2:
        sys.exit(__doc__)
    root = sys.argv[1]
    out = []
    for name in sorted(os.listdir(root)):
        case_dir = os.path.join(root, name)
        if not os.path.exists(os.path.join(case_dir, "ringing.csv")):
            continue
        s, rows = read_case(case_dir)
        check = s["metrics"]["checks"]["ringing"]
        dt = s["params"]["method.dt_value"]
        method = f'{s["params"]["method.shape"]} {s["params"]["method.transfer"]}'
        rates = [slope_per_1000_steps(rows, a, b, dt) for a, b in WINDOWS]
        e0, e1 = rows[0][1], rows[-1][1]
        whole = slope_per_1000_steps(rows, 0.0, rows[-1][0], dt)
        efold = 1000.0 * dt / whole if whole > 0 else float("inf")
        out.append((method, check["flow_courant"], check["sound_courant"], rates,
                    check.get("rate_per_step", float("nan")) * 1000.0, e1 / e0, efold, s["status"]))
    print("| method | U dt / h | c dt / h | map's fit (per 1000 steps) | "
          + " | ".join(f"{a:g}-{b:g} s" for a, b in WINDOWS)
          + " | E'(2 s) / E'(0) | e-fold time (s) | status |")
    print("|---|---|---|---|" + "---|" * len(WINDOWS) + "---|---|---|")
    for m, u, c, rates, fit, ratio, efold, status in sorted(out):
        cells = " | ".join(f"{r:+.2f}" for r in rates)
        print(f"| {m} | {u:.0e} | {c:.2f} | {fit:+.2f} | {cells} | {ratio:.3g} | "
              f"{'-' if math.isinf(efold) else f'{efold:.2f}'} | {status} |")


if __name__ == "__main__":
    main()
