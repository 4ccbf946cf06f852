#!/usr/bin/env python3
"""Tables of a study rerun's record (scripts/record_cases.py's CSV): per method (the case name after K, EOS and
viscosity), the runs recorded and completed, kicks, anomaly-proper events
(case and id), energy-budget events (`energy_injection`, where the record
has the column), and the late checkerboard measures side by side (median
over the method's runs): the old index (cell means of particle pressure,
`checkerboard_means_late`), the cell measure and the nodal measure.

    python3 scripts/rerun_tables.py docs/findings/data/remedies_rerun.csv [--by-k]

`--by-k` splits the energy-budget events by K and EOS instead.
"""
import argparse
import csv
import statistics
from collections import defaultdict


def num(v):
    try:
        return float(v)
    except (TypeError, ValueError):
        return None


def median(values):
    vals = [v for v in values if v is not None]
    return f"{statistics.median(vals):.3g}" if vals else "-"


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("record")
    ap.add_argument("--by-k", action="store_true")
    a = ap.parse_args()
    rows = list(csv.DictReader(open(a.record)))
    groups = defaultdict(list)
    for r in rows:
        parts = r["case"].split("_")
        key = "_".join(parts[:2]) if a.by_k else "_".join(parts[3:])
        groups[key].append(r)
    print(f"{len(rows)} runs recorded\n")
    print("| group | runs | completed | kicks | anomaly-proper events | energy-budget events (runs with the column) | checkerboard, old index | cell | nodal |")
    print("|---|---|---|---|---|---|---|---|---|")
    for key in sorted(groups):
        g = groups[key]
        anomalies = [f"{r['case']} {e}" for r in g for e in r["anomaly_events"].split()]
        budget = [num(r.get("n_energy_injections")) for r in g]
        known = [b for b in budget if b is not None]
        print(
            f"| {key} | {len(g)} | {sum(r['status'] == 'completed' for r in g)} "
            f"| {sum(int(r['n_kicks']) for r in g)} | {'; '.join(anomalies) or 'none'} "
            f"| {int(sum(known)) if known else '-'} ({len(known)}) "
            f"| {median(num(r['checkerboard_means_late']) for r in g)} "
            f"| {median(num(r['checkerboard_cell_late']) for r in g)} "
            f"| {median(num(r['checkerboard_nodal_late']) for r in g)} |"
        )


if __name__ == "__main__":
    main()
