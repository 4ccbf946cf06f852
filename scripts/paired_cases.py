#!/usr/bin/env python3
"""Two arms of one study, case by case (summary.json only).

Arm A is matrix folder A; arm B is folder B (the same case names, for a
`--set` change of the whole study) or, with `--pair OLD=NEW`, the cases of
A whose name has NEW in place of OLD (two arms in one folder, e.g. a
`method.scheme` axis). Per group (the case name with the ensemble member
and the arm's text removed) and in all, for each arm: runs, completed,
survival (simulated time reached, t_end for a completed run) as median
[min, max], kicks (injection, inversion or jump) per simulated second,
first-kick time and cause, kicks in a region (`--region x0,x1,y0,y1`, m)
among the first kicks, and anomaly-proper events; then the pairs (same
member): B survives longer / shorter / the same, and B's first kick later /
earlier, with the median ratio of B's first-kick time to A's.

    python3 scripts/paired_cases.py A B --group '^K[^_]+_[^_]+'     # by K and EOS
    python3 scripts/paired_cases.py A A --pair _usl_ppc2=_musl_ppc2 --region 0.17,0.22,0,0.05
"""
import argparse
import json
import math
import os
import re
import statistics

KICK = ("injection", "inversion", "jump")


def load(folder):
    out = {}
    for name in sorted(os.listdir(folder)):
        path = os.path.join(folder, name, "summary.json")
        if os.path.exists(path):
            with open(path) as f:
                out[name] = json.load(f)
    return out


def survival(s):
    return s["params"]["scene.t_end"] if s["status"] == "completed" else s["t_end"]


def kicks(s):
    return sorted((e for e in s["events"] if e.get("cause") in KICK), key=lambda e: (e["t"], e["id"]))


def in_region(e, box):
    r = e["region"]
    x, y = 0.5 * (r["x_min"] + r["x_max"]), 0.5 * (r["y_min"] + r["y_max"])
    return box[0] <= x <= box[1] and box[2] <= y <= box[3]


def spread(v):
    if not v:
        return "-"
    return f"{statistics.median(v):.3g} [{min(v):.3g}, {max(v):.3g}]"


def arm_row(runs, box):
    first = [kicks(s)[0] for s in runs if kicks(s)]
    causes = {}
    for e in first:
        causes[e["cause"]] = causes.get(e["cause"], 0) + 1
    rate = [len(kicks(s)) / max(survival(s), 1e-9) for s in runs]
    cells = [
        f"{len(runs)}",
        f"{sum(s['status'] == 'completed' for s in runs)}",
        spread([survival(s) for s in runs]),
        spread(rate),
        spread([e["t"] for e in first]) + (" (" + ", ".join(f"{c} {n}" for c, n in sorted(causes.items())) + ")" if causes else ""),
    ]
    if box:
        cells.append(f"{sum(in_region(e, box) for e in first)} of {len(first)}")
    cells.append(f"{sum(1 for s in runs for e in s['events'] if e.get('cause') in KICK and is_anomaly(e))}")
    return cells


def is_anomaly(e):
    return e.get("quiescent_before") and "strain_rate" in (e.get("deformed_by") or [])


def group_of(name, drop, pattern):
    if pattern:
        m = re.match(pattern, name)
        return m.group(0) if m else name
    g = re.sub(r"_e\d+$", "", name)
    return g.replace(drop, "_") if drop else g


def sign_test(wins, losses):
    """Two-sided exact sign test: P(a split at least this uneven | no effect)."""
    n, k = wins + losses, min(wins, losses)
    if n == 0:
        return 1.0
    tail = sum(math.comb(n, i) for i in range(k + 1)) / 2.0 ** n
    return min(1.0, 2.0 * tail)


def compare(pairs):
    longer = sum(survival(b) > survival(a) + 1e-9 for a, b in pairs)
    shorter = sum(survival(b) < survival(a) - 1e-9 for a, b in pairs)
    ratios, later, earlier = [], 0, 0
    for a, b in pairs:
        ka, kb = kicks(a), kicks(b)
        if ka and kb:
            ratios.append(kb[0]["t"] / ka[0]["t"])
            later += kb[0]["t"] > ka[0]["t"]
            earlier += kb[0]["t"] < ka[0]["t"]
    rate = lambda s: len(kicks(s)) / max(survival(s), 1e-9)
    more = sum(rate(b) > rate(a) for a, b in pairs)
    fewer = sum(rate(b) < rate(a) for a, b in pairs)
    ratio = f"{statistics.median(ratios):.3g} [{min(ratios):.3g}, {max(ratios):.3g}]" if ratios else "-"
    return (f"B longer {longer}, shorter {shorter}, same {len(pairs) - longer - shorter} (sign test p = {sign_test(longer, shorter):.2g}); "
            f"first kick later {later}, earlier {earlier} (p = {sign_test(later, earlier):.2g}), t_B / t_A {ratio}; "
            f"kicks per s more {more}, fewer {fewer} (p = {sign_test(more, fewer):.2g})")


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("a")
    ap.add_argument("b")
    ap.add_argument("--pair", help="OLD=NEW: arm B is A's case with NEW for OLD in its name")
    ap.add_argument("--region", help="x0,x1,y0,y1 (m): count first kicks there")
    ap.add_argument("--group", help="regex: a group is its match at the name's start (default: the name without member)")
    args = ap.parse_args()
    box = [float(v) for v in args.region.split(",")] if args.region else None
    a_all, b_all = load(args.a), load(args.b)
    old, new = args.pair.split("=") if args.pair else ("", "")
    pairs = {}
    for name, sa in a_all.items():
        if old and old not in name:
            continue
        other = name.replace(old, new) if old else name
        if other in b_all:
            pairs.setdefault(group_of(name, old, args.group), []).append((sa, b_all[other]))
    head = ["group", "arm", "runs", "completed", "survival (s)", "kicks per s", "first kick (s)"]
    if box:
        head.append("first kicks in region")
    head.append("anomaly proper")
    print("| " + " | ".join(head) + " |")
    print("|" + "---|" * len(head))
    everything = []
    for g, ps in sorted(pairs.items()):
        everything += ps
        for arm, runs in (("A", [p[0] for p in ps]), ("B", [p[1] for p in ps])):
            print(f"| {g} | {arm} | " + " | ".join(arm_row(runs, box)) + " |")
    for arm, runs in (("A", [p[0] for p in everything]), ("B", [p[1] for p in everything])):
        print(f"| all | {arm} | " + " | ".join(arm_row(runs, box)) + " |")
    print()
    for g, ps in sorted(pairs.items()):
        print(f"- {g}: {compare(ps)}")
    print(f"- all {len(everything)} pairs: {compare(everything)}")


if __name__ == "__main__":
    main()
