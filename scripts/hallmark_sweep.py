#!/usr/bin/env python3
"""Count the anomaly proper (a kick with the hallmark) under other hallmark
thresholds, offline, from runs made with `[monitor] hallmark_log = true`
(docs/physics.md section 4b; `kick matrix STUDY --set monitor.hallmark_log=true`).

    python3 scripts/hallmark_sweep.py MATRIX_DIR [MATRIX_DIR ...] [--csv OUT.csv]

For every case folder with a hallmark.csv, each kick (cause injection,
inversion or jump) is re-judged at every combination of quiet speed (the
logged multiples of `quiet_speed`), `quiet_seconds` and `deformed_rate`
(1/3, 1/sqrt 3, 1, sqrt 3 and 3 times the case's own), under both readings
of "highly deformed earlier": a past peak of the strain rate before the
quiet window (`rate`, the monitor's) or a distorted F now (`distortion`).
The rule is the monitor's (`monitor::hallmark_log::reapply`): each part
holds when at least half the opening cluster's particles meet it. At the
case's own thresholds the re-judged hallmark must equal the monitor's own
for every event; the script stops if it does not.
"""
import argparse
import csv
import glob
import json
import math
import os
import sys
import tomllib

FACTORS = [1 / 3, 1 / math.sqrt(3), 1.0, math.sqrt(3), 3.0]
DEFAULTS = {"quiet_seconds": 0.05, "quiet_speed": 0.1, "deformed_rate": 50.0, "distortion_ratio": 4.0}
KICKS = ("injection", "inversion", "jump")


def monitor_config(case_dir):
    with open(os.path.join(case_dir, "case.toml"), "rb") as f:
        cfg = tomllib.load(f).get("monitor", {})
    return {k: float(cfg.get(k, v)) for k, v in DEFAULTS.items()}


# The tables write a non-finite figure as an empty cell: a particle never
# active has been quiet for ever, one never deformed peaked at -inf.
# A distortion of F with no smallest stretch (an inverted F) is infinite.
EMPTY = {"quiet_for": math.inf, "peak_rate_t": -math.inf, "distortion": math.inf}


def number(key, text):
    return float(text) if text != "" else EMPTY.get(key, math.nan)


def rows_by_event(case_dir):
    rows = {}
    with open(os.path.join(case_dir, "hallmark.csv")) as f:
        for r in csv.DictReader(f):
            e = int(float(r["event"]))
            rows.setdefault(e, []).append({k: number(k, v) for k, v in r.items()})
    return rows


def reapply(rows, speed_factor, quiet_seconds, deformed_rate, distortion_ratio):
    """(quiescent, deformed by rate, distorted) shares of the rows at one quiet speed."""
    sel = [r for r in rows if abs(r["speed_factor"] - speed_factor) < 1e-9 * speed_factor]
    if not sel:
        return 0.0, 0.0, 0.0
    n = len(sel)
    quiet = sum(r["quiet_for"] >= quiet_seconds for r in sel) / n
    rate = sum(r["peak_rate"] >= deformed_rate and r["peak_rate_t"] < r["t"] - quiet_seconds for r in sel) / n
    dist = sum(r["distortion"] >= distortion_ratio for r in sel) / n
    return quiet, rate, dist


def loosest(rows, cfg):
    """(quiet share, rate share, distortion share, median quiet spell) at the
    loosest setting: 3 times the quiet speed, 1/3 of the quiet window and of
    the deformed rate."""
    q, r, d = reapply(rows, FACTORS[-1], FACTORS[0] * cfg["quiet_seconds"],
                      FACTORS[0] * cfg["deformed_rate"], cfg["distortion_ratio"])
    spells = sorted(x["quiet_for"] for x in rows
                    if abs(x["speed_factor"] - FACTORS[-1]) < 1e-9 and not math.isnan(x["quiet_for"]))
    return q, r, d, spells[len(spells) // 2] if spells else math.nan


def print_loosest(near):
    """Why a count is 0: how close the kicks came at the loosest setting."""
    if not near:
        return
    quiet = [n for n in near if n[0] >= 0.5]
    spells = sorted(n[3] for n in near if not math.isnan(n[3])) or [math.nan]
    print()
    print(f"At the loosest setting (quiet speed x 3, quiet seconds x 1/3, deformed rate x 1/3): "
          f"{len(quiet)} of {len(near)} kicks had half their particles quiet; of those, "
          f"{sum(n[1] >= 0.5 for n in quiet)} deformed by rate and {sum(n[2] >= 0.5 for n in quiet)} distorted. "
          f"Median over kicks of the median particle's quiet spell at 3 x the quiet speed: {spells[len(spells) // 2]:.3g} s.")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("matrices", nargs="+")
    ap.add_argument("--csv", help="write every setting's counts here")
    a = ap.parse_args()
    counts = {}
    near = []
    kicks = 0
    cases = 0
    for matrix in a.matrices:
        for summary in sorted(glob.glob(os.path.join(matrix, "*", "summary.json"))):
            case = os.path.dirname(summary)
            if not os.path.exists(os.path.join(case, "hallmark.csv")):
                continue
            cases += 1
            cfg = monitor_config(case)
            rows = rows_by_event(case)
            for e in json.load(open(summary))["events"]:
                if e["kind"] != "kick" or e["cause"] not in KICKS or e["id"] not in rows:
                    continue
                kicks += 1
                near.append(loosest(rows[e["id"]], cfg))
                own = reapply(rows[e["id"]], 1.0, cfg["quiet_seconds"], cfg["deformed_rate"], cfg["distortion_ratio"])
                online = e["quiescent_before"] and "strain_rate" in e["deformed_by"]
                if (own[0] >= 0.5 and own[1] >= 0.5) != online:
                    sys.exit(f"{case} event {e['id']}: re-judged {own} but the monitor said hallmark={online}")
                for fs in FACTORS:
                    for fq in FACTORS:
                        for fd in FACTORS:
                            q, r, d = reapply(rows[e["id"]], fs, fq * cfg["quiet_seconds"],
                                              fd * cfg["deformed_rate"], cfg["distortion_ratio"])
                            key = (round(fs, 3), round(fq, 3), round(fd, 3))
                            c = counts.setdefault(key, [0, 0])
                            c[0] += q >= 0.5 and r >= 0.5
                            c[1] += q >= 0.5 and d >= 0.5
    print(f"{cases} cases with a hallmark log, {kicks} kicks")
    if kicks == 0:
        return
    print()
    print("One threshold at a time (the others at the case's own):")
    print()
    print("| threshold | x 1/3 | x 1/sqrt 3 | x 1 | x sqrt 3 | x 3 |")
    print("|---|---|---|---|---|---|")
    one = lambda f: round(f, 3)
    for name, at in (("quiet_speed", lambda f: (one(f), 1.0, 1.0)),
                     ("quiet_seconds", lambda f: (1.0, one(f), 1.0)),
                     ("deformed_rate", lambda f: (1.0, 1.0, one(f)))):
        cells = [f"{counts[at(f)][0]} ({counts[at(f)][1]})" for f in FACTORS]
        print(f"| {name} | " + " | ".join(cells) + " |")
    print_loosest(near)
    print()
    print("Anomaly proper by the strain-rate reading (by the distortion reading in brackets). Every setting:")
    print()
    print("| quiet speed x | quiet seconds x | deformed rate x | anomaly (rate) | anomaly (distortion) |")
    print("|---|---|---|---|---|")
    for key in sorted(counts):
        print(f"| {key[0]:g} | {key[1]:g} | {key[2]:g} | {counts[key][0]} | {counts[key][1]} |")
    if a.csv:
        with open(a.csv, "w", newline="") as f:
            w = csv.writer(f)
            w.writerow(["quiet_speed_factor", "quiet_seconds_factor", "deformed_rate_factor",
                        "anomaly_rate", "anomaly_distortion", "kicks"])
            for key in sorted(counts):
                w.writerow([*key, *counts[key], kicks])


if __name__ == "__main__":
    main()
