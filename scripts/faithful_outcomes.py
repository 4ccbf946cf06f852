#!/usr/bin/env python3
"""The faithful replica's grid from its record:

    python3 scripts/faithful_outcomes.py [docs/findings/data/faithful.csv]

One row per configuration of studies/faithful.toml (shape, CFL, artificial
viscosity) and K, over its 6 runs (2 viscosities x 3 members): how many
completed the 5 s, how many blew up and how (the stop reason's first
words), the first kick's time (min-max over the runs that kicked), the end
time of those that stopped, and the kicks and anomalies proper in all.
Then the same per shape and K, and the inviscid-against-viscous survival
pairs (behaviour 4's raw counts: a pair is one member index).
"""
import csv
import re
import sys
from collections import defaultdict

NAME = re.compile(
    r"K(?P<k>[\d.]+[kM]?Pa)_mu(?P<mu>[\d.]+)_(?P<shape>linear|gimp)_cfl(?P<cfl>[\d.]+)_(?P<method>.+)_e(?P<e>\d+)$"
)


def k_value(s):
    v = float(re.match(r"[\d.]+", s).group())
    return v * (1e3 if "kPa" in s else 1e6 if "MPa" in s else 1.0)


def reason_kind(r):
    if r["status"] == "completed":
        return "completed"
    text = r["reason"]
    for key, label in [("time step collapsed", "dt collapsed"), ("non-finite", "non-finite"),
                       ("mass", "mass lost"), ("blow", "blow-out")]:
        if key in text:
            return label
    return text.split(":")[0][:30]


def span(values, fmt="{:.4g}"):
    v = sorted(x for x in values if x is not None)
    if not v:
        return "-"
    return fmt.format(v[0]) if v[0] == v[-1] else (fmt + "-" + fmt).format(v[0], v[-1])


def main():
    path = sys.argv[1] if len(sys.argv) > 1 else "docs/findings/data/faithful.csv"
    rows = list(csv.DictReader(open(path)))
    groups = defaultdict(list)
    for r in rows:
        m = NAME.match(r["case"])
        if not m:
            continue
        r["_"] = m.groupdict()
        key = (m["shape"], float(m["cfl"]), m["method"], k_value(m["k"]))
        groups[key].append(r)
    print(f"{len(rows)} runs recorded")
    print("| shape | CFL | method | K | runs | completed | stopped (how) | first kick (s) | stopped at (s) | kicks | anomalies proper |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for key in sorted(groups):
        g = groups[key]
        kinds = defaultdict(int)
        for r in g:
            kinds[reason_kind(r)] += 1
        done = kinds.pop("completed", 0)
        stopped = ", ".join(f"{n} {k}" for k, n in sorted(kinds.items())) or "-"
        first = [float(r["t_first_kick"]) for r in g if r["t_first_kick"]]
        ends = [float(r["t_end"]) for r in g if r["status"] != "completed"]
        kicks = sum(int(r["n_kicks"]) for r in g)
        anomalies = sum(int(r["n_anomalies"]) for r in g)
        shape, cfl, method, k = key
        print(f"| {shape} | {cfl} | {method.replace('_', ' ')} | {k:g} | {len(g)} | {done} | {stopped} | "
              f"{span(first)} ({len(first)} kicked) | {span(ends)} | {kicks} | {anomalies} |")
    # Behaviour 4's raw pairs: inviscid against viscous, same member.
    print()
    print("| shape | CFL | method | K | pairs | inviscid ends first | viscous first | tie |")
    print("|---|---|---|---|---|---|---|---|")
    for key in sorted(groups):
        by = {(r["_"]["mu"], r["_"]["e"]): r for r in groups[key]}
        counts = [0, 0, 0]
        for e in sorted({r["_"]["e"] for r in groups[key]}):
            a, b = by.get(("0", e)), by.get(("0.5", e))
            if not a or not b:
                continue
            ta, tb = float(a["t_end"]), float(b["t_end"])
            counts[0 if ta < tb else 1 if tb < ta else 2] += 1
        shape, cfl, method, k = key
        print(f"| {shape} | {cfl} | {method.replace('_', ' ')} | {k:g} | {sum(counts)} | {counts[0]} | {counts[1]} | {counts[2]} |")


if __name__ == "__main__":
    main()
