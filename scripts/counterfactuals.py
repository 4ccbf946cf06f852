#!/usr/bin/env python3
"""Counterfactual ensembles of a matrix's events, and their table.

    python3 scripts/counterfactuals.py MATRIX_DIR [MATRIX_DIR ...] [--pick anomaly|kick]
        [--first-per-case] [--near CASE=T ...] [--max N] [--members 5] [--kick PATH]
        [--threads 2] [--table-only]

Picks the events of every case (cases and events in name and id order):
`anomaly` takes the kicks with the hallmark (a kick cause, quiet before and
past the strain-rate threshold earlier: docs/physics.md section 4b),
`kick` every kick (inversion, injection or jump); `--first-per-case` keeps
each case's first. `--near CASE=T` (repeatable) keeps, in each case so
named, the one kick nearest to time T (each kick once, in id order), and
no other case: it finds again an event that was logged under an earlier
detector, whose id moved; a kick more than 5 ms from T is named. Each
one with a checkpoint is explained with `kick explain CASE --event K
--counterfactual --members M --threads T` unless its explain.json already
holds counterfactual members. Then prints, in Markdown: per event, each
change's members reopened and verdict; and per change, over the events
whose control reproduced its event (at least 4 of 5 members), how many
it prevented, with the 95 % Wilson interval, and how many it delayed,
hastened, moved, blew up or let happen again.
"""
import argparse
import glob
import json
import math
import os
import subprocess
import sys
import time

KICKS = ("inversion", "injection", "jump")


def picked(matrices, pick, first_per_case, near):
    for m in matrices:
        for path in sorted(glob.glob(os.path.join(m, "*", "summary.json"))):
            case = os.path.dirname(path)
            name = os.path.basename(case)
            if near and name not in near:
                continue
            s = json.load(open(path))
            chosen = []
            for e in sorted(s["events"], key=lambda e: e["id"]):
                kick = e["cause"] in KICKS
                hallmark = e["quiescent_before"] and "strain_rate" in e.get("deformed_by", [])
                if kick and (pick == "kick" or hallmark) and e.get("checkpoint"):
                    chosen.append(e)
            if near:
                found = {}
                for t in near[name] if chosen else []:
                    e = min(chosen, key=lambda e: abs(e["t"] - t))
                    if abs(e["t"] - t) > 0.005:
                        print(f"{name}: the kick nearest {t} s is event {e['id']} at "
                              f"{e['t']:.4f} s", file=sys.stderr)
                    found[e["id"]] = e
                chosen = [found[k] for k in sorted(found)]
            for e in chosen[:1] if first_per_case else chosen:
                yield case, e


def record(case, event):
    path = os.path.join(case, "explain", f"event_{event}", "explain.json")
    try:
        rec = json.load(open(path))
    except (OSError, ValueError):
        return None
    rows = rec.get("counterfactual", [])
    return rec if rows and "members" in rows[0] else None


def explain(kick, case, event, members, threads):
    start = time.time()
    out = subprocess.run(
        [kick, "explain", case, "--event", str(event), "--counterfactual",
         "--members", str(members), "--threads", str(threads)],
        capture_output=True, text=True)
    wall = time.time() - start
    print(f"{os.path.basename(case)} event {event}: {wall:.0f} s, exit {out.returncode}",
          file=sys.stderr)
    if out.returncode not in (0, 1):
        print(out.stderr, file=sys.stderr)
    return wall


def wilson(k, n):
    if n == 0:
        return 0.0, 1.0
    z = 1.959963984540054
    p = k / n
    centre = (p + z * z / (2 * n)) / (1 + z * z / n)
    half = z / (1 + z * z / n) * math.sqrt(p * (1 - p) / n + z * z / (4 * n * n))
    return max(0.0, centre - half), min(1.0, centre + half)


# counterfactual.rs SAME_TIME: records written before that margin are
# re-judged with it (a delay or haste within it is "again").
SAME_TIME = 0.005


def median(values):
    v = sorted(values)
    n = len(v)
    return None if n == 0 else (v[n // 2] if n % 2 else 0.5 * (v[n // 2 - 1] + v[n // 2]))


def rejudged(control, row):
    if row["verdict"] not in ("delayed", "hastened"):
        return row["verdict"]
    times = lambda r: [m["next_kick_after"] if m["next_kick_after"] is not None else math.inf
                       for m in r["members"]]
    theirs, own = times(control), median(times(row))
    if own > max(theirs) + SAME_TIME:
        return "delayed"
    if own < min(theirs) - SAME_TIME:
        return "hastened"
    return "again"


def generic(change):
    """The change's name without the remedies it names (`(without ...)`)."""
    return change.split(" (without")[0]


def tables(explained):
    print("| case | event | t (s) | cause | control reopened | " +
          "change: reopened of members, verdict |")
    print("|---|---|---|---|---|---|")
    per_change = {}
    for case, e, rec in explained:
        rows = rec["counterfactual"]
        control = rows[0]
        n = len(control["members"])
        cells = []
        for r in rows[1:]:
            name = generic(r["change"])
            if r.get("refused"):
                # A panicked replay is a fault to see, not a change that
                # does not apply; either way it leaves this change's M.
                why = " (the replay panicked)" if "panicked" in r["refused"] else ""
                cells.append(f"{name}: refused{why}")
                continue
            verdict = rejudged(control, r)
            cells.append(f"{name}: {r['reopened']}/{n} {verdict}")
            if control["verdict"] == "control":
                per_change.setdefault(name, []).append(verdict)
        print(f"| {os.path.basename(case)} | {e['id']} | {e['t']:.3f} | {e['cause']} | "
              f"{control['reopened']} of {n} ({control['verdict']}) | {'; '.join(cells)} |")
    decided = sum(1 for _, _, r in explained if r["counterfactual"][0]["verdict"] == "control")
    print()
    print(f"Over the {decided} events whose control reproduced its event "
          f"(of {len(explained)} explained):")
    print()
    print("| change | prevented (95 % interval) | delayed | hastened | again | moved | "
          "blew up | injected | undecided |")
    print("|---|---|---|---|---|---|---|---|---|")
    for name, verdicts in per_change.items():
        n = len(verdicts)
        k = verdicts.count("prevented")
        lo, hi = wilson(k, n)
        counts = [verdicts.count(v) for v in
                  ("delayed", "hastened", "again", "moved", "blew up", "injected", "undecided")]
        print(f"| {name} | {k} of {n} [{lo:.2f}, {hi:.2f}] | " +
              " | ".join(str(c) for c in counts) + " |")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("matrices", nargs="+")
    ap.add_argument("--pick", choices=("anomaly", "kick"), default="anomaly")
    ap.add_argument("--first-per-case", action="store_true")
    ap.add_argument("--near", action="append", default=[], metavar="CASE=T")
    ap.add_argument("--max", type=int, default=None)
    ap.add_argument("--members", type=int, default=5)
    ap.add_argument("--kick", default="target/release/kick")
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--table-only", action="store_true")
    a = ap.parse_args()
    near = {}
    for item in a.near:
        name, _, t = item.partition("=")
        try:
            near.setdefault(name, []).append(float(t))
        except ValueError:
            print(f"counterfactuals.py: --near {item}: expected CASE=T, T a time in s",
                  file=sys.stderr)
            sys.exit(2)
    events = list(picked(a.matrices, a.pick, a.first_per_case, near))
    missing = set(near) - {os.path.basename(case) for case, _ in events}
    if missing:
        print(f"counterfactuals.py: --near: no picked kick in {', '.join(sorted(missing))} "
              f"(no such case under {', '.join(a.matrices)}, or no kick with a checkpoint)",
              file=sys.stderr)
        sys.exit(2)
    events = events[: a.max]
    explained, wall = [], 0.0
    for case, e in events:
        if record(case, e["id"]) is None and not a.table_only:
            wall += explain(a.kick, case, e["id"], a.members, a.threads)
        rec = record(case, e["id"])
        if rec is not None:
            explained.append((case, e, rec))
    print(f"{len(events)} events picked, {len(explained)} with counterfactual members; "
          f"explained now in {wall:.0f} s", file=sys.stderr)
    tables(explained)


if __name__ == "__main__":
    main()
