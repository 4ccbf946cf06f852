#!/usr/bin/env python3
"""The calibration's planted kicks judged by another kick build's detector.

`kick calibrate` places each patch at the plant time and records where
and when it went (detection.json: region, step). This script plants the
same patches, at the same step, in the same regions, with an older build
(one that knows `[[perturb]]` only as step, region and dv), runs each case
from t = 0 to the end of the window, and bisects each placement's smallest
speed found the same way: the bracket's top, its bottom, then geometric
means to the calibration's ratio. A patch is found when an event whose
cause is not `impact` opens within merge_cells of its cells in the window,
and the older build's clean twin has no event of that kind there then.

    python3 scripts/detector_then_and_now.py CAL_DIR --kick OLD_KICK \
        --case K1.5MPa_cfl0.2 [--case ...] --out OUT.csv

Prints the smallest speed found per case, placement and size by both
builds, and their ratio (the older over the newer: above 1 the newer
finds smaller kicks).
"""

import argparse
import csv
import json
import math
import subprocess
import sys
import tempfile
from pathlib import Path


def run(kick, case_toml, perturbs, t_end, work, name):
    """Runs the case with these [[perturb]] entries; its events."""
    text = Path(case_toml).read_text()
    text += "\n"
    for step, region, dv in perturbs:
        text += "\n[[perturb]]\nstep = %d\nregion = [%r, %r, %r, %r]\ndv = [0.0, %r]\n" % (
            step, *region, dv)
    study = Path(work) / f"{name}.toml"
    study.write_text(text)
    out = Path(work) / name
    subprocess.run(
        [kick, "run", str(study), "--out", str(out), "--threads", "1",
         "--set", f"scene.t_end={t_end!r}", "--set", "output.checkpoint_every=0"],
        check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    [case_dir] = [p for p in out.iterdir() if p.is_dir()]
    return json.loads((case_dir / "summary.json").read_text())["events"]


def cells_of(region, cell):
    i0 = math.floor(region[0] / cell)
    j0 = math.floor(region[1] / cell)
    i1 = max(math.ceil(region[2] / cell) - 1, i0)
    j1 = max(math.ceil(region[3] / cell) - 1, j0)
    return (i0, j0, i1, j1)


def near(a, b, margin):
    return (a[0] <= b[2] + margin and b[0] <= a[2] + margin
            and a[1] <= b[3] + margin and b[1] <= a[3] + margin)


def event_cells(e):
    c = e["cells"]
    return (c["i_min"], c["j_min"], c["i_max"], c["j_max"])


def found(events, twin, cells, reach, window):
    for e in events:
        if e["cause"] == "impact" or not (window[0] <= e["t"] <= window[1] + 1e-12):
            continue
        if not near(event_cells(e), cells, reach):
            continue
        masked = any(
            t["kind"] == e["kind"] and near(event_cells(t), event_cells(e), reach)
            and t["last_t"] >= window[0] and t["t"] <= window[1] for t in twin)
        if not masked:
            return True
    return False


def bisect_case(kick, cal, case, rows, spec, work):
    case_toml = Path(cal) / case / "case.toml"
    cell = float(json.loads((Path(cal) / case / "summary.json").read_text())
                 ["params"]["scene.cell"])
    reach = json.loads((Path(cal) / case / "summary.json").read_text())["params"].get(
        "monitor.merge_cells", 3)
    t_plant = rows[0]["t_plant_s"]
    window = (t_plant, t_plant + spec["window"])
    twin = run(kick, case_toml, [], window[1], work, f"{case}_twin")
    lo, hi = spec["bisect"]
    result = {}
    for size in sorted({r["cells"] for r in rows}):
        patches = [r for r in rows if r["cells"] == size and r["placed"]]
        brackets = {r["place"]: [None, None] for r in patches}  # found, missed
        k = 0
        while True:
            speeds = {}
            for r in patches:
                f, m = brackets[r["place"]]
                if f is None and m is None:
                    speeds[r["place"]] = hi
                elif f is not None and m is None and f > lo:
                    speeds[r["place"]] = lo
                elif f is not None and m is not None and f / m > spec["ratio"]:
                    speeds[r["place"]] = math.sqrt(f * m)
            if not speeds:
                break
            plan = [(r["step"], r["region"], speeds[r["place"]]) for r in patches
                    if r["place"] in speeds]
            events = run(kick, case_toml, plan, window[1], work, f"{case}_{size}_{k}")
            k += 1
            for r in patches:
                if r["place"] not in speeds:
                    continue
                dv = speeds[r["place"]]
                ok = found(events, twin, cells_of(r["region"], cell), reach, window)
                f, m = brackets[r["place"]]
                if ok:
                    brackets[r["place"]][0] = dv if f is None else min(f, dv)
                else:
                    brackets[r["place"]][1] = dv if m is None else max(m, dv)
        for place, (f, _) in brackets.items():
            result[(place, size)] = f
    return result


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("cal_dir")
    ap.add_argument("--kick", required=True, help="the other build's kick binary")
    ap.add_argument("--case", action="append", required=True)
    ap.add_argument("--out", required=True)
    a = ap.parse_args()
    d = json.loads((Path(a.cal_dir) / "detection.json").read_text())
    spec = d["spec"]
    if spec.get("bisect") is None:
        sys.exit("the calibration must bisect (calibration.bisect)")
    out_rows = []
    with tempfile.TemporaryDirectory() as work:
        for case in a.case:
            rows = [r for r in d["rows"] if r["case"] == case]
            if not rows:
                sys.exit(f"{a.cal_dir}: no rows of case {case}")
            then = bisect_case(a.kick, a.cal_dir, case, rows, spec, work)
            for r in rows:
                old = then.get((r["place"], r["cells"]))
                new = r["dv_found"]
                ratio = old / new if old and new else float("nan")
                out_rows.append([case, r["place"], r["cells"], new, old, ratio])
                print(f"{case:32} {r['place']:8} {r['cells']}x{r['cells']}  "
                      f"now {new}  then {old}  then/now {ratio:.2f}")
    with open(a.out, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["case", "place", "cells", "dv_found_now", "dv_found_then", "then_over_now"])
        w.writerows(out_rows)


if __name__ == "__main__":
    main()
