#!/usr/bin/env python3
"""Explain a stratified sample of a matrix's injection kicks.

    python3 scripts/explain_sample.py MATRIX_DIR [--n 30] [--kick PATH] [--jobs 2] [--table-only]
        [--causes injection,inversion] [--counterfactual] [--max-window-steps N]
    python3 scripts/explain_sample.py MATRIX_DIR --all-explained
    python3 scripts/explain_sample.py MATRIX_DIR --table-only --causes impact --precursors
    python3 scripts/explain_sample.py MATRIX_DIR --hallmark --precursors

Picks kicks of cause `injection` (or the `--causes` given) from every
case's summary.json (events open for at most `--max-window-steps` steps
when given: an event open through a whole blow-out takes as long to
explain as the blow-out took to run), stratified
by K (`materials.water.K`) and by time: collapse (t < 0.15 s), impact
(0.15-0.6 s) and late (t >= 0.6 s), taking one per stratum in turn
(deterministic: cases and events in name and id order), then runs
`kick explain CASE --event K --threads 1` for each (skipping those already
explained) and prints a table of each event's shares and the means per time
stratum. `--hallmark` takes, instead of a sample, every event of the given
causes that the monitor gave the hallmark (the anomaly proper).
"""
import argparse
import csv
import glob
import json
import math
import os
import statistics
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor


def stratum(t):
    return "collapse" if t < 0.15 else ("impact" if t < 0.6 else "late")


def events(matrix):
    """(K, case folder, event) of every case's events, cases and events in name and id order."""
    for d in sorted(glob.glob(os.path.join(matrix, "*", "summary.json"))):
        s = json.load(open(d))
        k = s["params"].get("materials.water.K")
        for e in sorted(s["events"], key=lambda e: e["id"]):
            yield k, os.path.dirname(d), e


def pick(matrix, n, causes=("injection",), max_window=None):
    strata = {}
    for k, case, e in events(matrix):
        short = max_window is None or e["last_step"] - e["first_step"] <= max_window
        if e["cause"] in causes and e.get("checkpoint") and short:
            strata.setdefault((k, stratum(e["t"])), []).append((case, e))
    keys = sorted(strata, key=lambda k: (k[0], ["collapse", "impact", "late"].index(k[1])))
    chosen, round_ = [], 0
    # Spread over each stratum rather than its first events: a stride of a
    # quarter of it, then the offsets between (a permutation: no event twice).
    order = {}
    for k in keys:
        step = max(1, len(strata[k]) // 4)
        order[k] = [i for off in range(step) for i in range(off, len(strata[k]), step)]
    while len(chosen) < n and any(round_ < len(strata[k]) for k in keys):
        for k in keys:
            if round_ < len(strata[k]) and len(chosen) < n:
                chosen.append((k, *strata[k][order[k][round_]]))
        round_ += 1
    # The same event twice (small strata wrap): keep one.
    seen, out = set(), []
    for k, case, e in chosen:
        if (case, e["id"]) not in seen:
            seen.add((case, e["id"]))
            out.append((k, case, e))
    return out, {k: len(v) for k, v in strata.items()}


def explained_events(matrix):
    """Every event of the matrix with an explain.json, as `pick` returns them."""
    return [((k, stratum(e["t"])), case, e) for k, case, e in events(matrix)
            if explain_done(case, e["id"]) is not None]


def explain(kick, case, event, counterfactual=False, quiet_window=None):
    """Explains the event unless it already is; its explain.json (None if it failed)."""
    done = explain_done(case, event)
    if done is not None and quiet_window and abs(quiet_seconds(done) - quiet_window) > 1e-9:
        done = None  # explained over another quiet window: again, over this one
    if done is None:
        extra = ["--counterfactual"] if counterfactual else []
        extra += ["--quiet-window", str(quiet_window)] if quiet_window else []
        subprocess.run([kick, "explain", case, "--event", str(event), "--threads", "1", *extra],
                       stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        done = explain_done(case, event)
    return done


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("matrix")
    ap.add_argument("--n", type=int, default=30)
    ap.add_argument("--kick", default="target/release/kick")
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--table-only", action="store_true")
    ap.add_argument("--causes", default="injection")
    ap.add_argument("--counterfactual", action="store_true")
    ap.add_argument("--max-window-steps", type=int, default=None)
    ap.add_argument("--precursors", action="store_true",
                    help="also table each event's precursors against its matched quiet boxes, and their tally")
    ap.add_argument("--all-explained", action="store_true",
                    help="table every event of the matrix already explained (picked or not); runs nothing")
    ap.add_argument("--quiet-window", type=float, default=None,
                    help="seconds of quiet window to explain (kick explain --quiet-window)")
    ap.add_argument("--hallmark", action="store_true",
                    help="every event of the causes with the monitor's hallmark, not a sample")
    a = ap.parse_args()
    if a.all_explained:
        chosen = explained_events(a.matrix)
    elif a.hallmark:
        causes = a.causes.split(",")
        chosen = [((k, stratum(e["t"])), case, e) for k, case, e in events(a.matrix)
                  if e["cause"] in causes and e.get("checkpoint") and hallmark(e) == "yes"]
        print(f"events with the hallmark: {len(chosen)}", file=sys.stderr)
    else:
        chosen, sizes = pick(a.matrix, a.n, tuple(a.causes.split(",")), a.max_window_steps)
        print(f"injection kicks per (K, time) stratum: {sizes}", file=sys.stderr)
    if a.table_only or a.all_explained:
        results = [explain_done(case, e["id"]) for _, case, e in chosen]
    else:
        with ThreadPoolExecutor(a.jobs) as ex:
            results = list(ex.map(lambda c: explain(a.kick, c[1], c[2]["id"], a.counterfactual,
                                                    a.quiet_window), chosen))
    keys = ["internal", "external", "walls", "jump", "small_mass_node", "cell_crossing", "stress_outlier"]
    print("| case | event | K (Pa) | t (s) | stratum | hallmark | matched | closure | largest part | internal | jump | M1 small-mass | M2 crossing | M3 outlier | M4 drift / speed | M4 drift / sqrt(gH) | M5 Courant | prevented by |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    prevented_by = {}
    by = {}
    for (k, case, e), j in zip(chosen, results):
        if j is None:
            print(f"| {os.path.basename(case)} | {e['id']} | {k[0]:g} | {e['t']:.3f} | {k[1]} | {hallmark(e)} | not explained | | | | | | | | | | | |")
            continue
        sh = j["shares"]
        by.setdefault(k[1], []).append(sh)
        # JSON writes NaN (no step before the onset window) as null.
        f2 = lambda x: "-" if x is None else f"{x:.2f}"
        print(f"| {os.path.basename(case)} | {e['id']} | {k[0]:g} | {e['t']:.3f} | {k[1]} | {hallmark(e)} | {j['matched']} | {j['closure_rest_max']:.1e} | "
              f"{j['largest_part']['part']} | {f2(sh['internal'])} | {f2(sh['jump'])} | {f2(sh['small_mass_node'])} | "
              f"{f2(sh['cell_crossing'])} | {f2(sh['stress_outlier'])} | {f2(j['m4_ringing']['drift_over_speed'])} | "
              f"{f2(j['m4_ringing'].get('drift_over_gravity_wave'))} | "
              f"{f2(j['m5_time_step']['courant_before'])} | {prevents(j, prevented_by)} |")
    if a.precursors:
        precursor_table(chosen, results)
    if prevented_by:
        print()
        print("single changes that prevent the event (counterfactual replays): "
              + ", ".join(f"{c} {n}" for c, n in sorted(prevented_by.items(), key=lambda x: -x[1])))
    print()
    print("| stratum | events | " + " | ".join(f"{k} (median [min, max])" for k in keys) + " |")
    print("|---|---|" + "---|" * len(keys))
    for s in ["collapse", "impact", "late"]:
        lst = by.get(s, [])
        if not lst:
            continue
        cells = []
        for k in keys:
            v = [x[k] for x in lst]
            cells.append(f"{statistics.median(v):.2f} [{min(v):.2f}, {max(v):.2f}]")
        print(f"| {s} | {len(lst)} | " + " | ".join(cells) + " |")


def precursor_table(chosen, results):
    """Each event's precursors (quiet-window shares of its particle-steps
    flagged M1, M2, M3 against its matched quiet boxes'), and the tally of
    the named precursor by the event's cause."""
    f = lambda x: "-" if x is None else f"{x:.2f}"
    print()
    print("| case | event | cause | t (s) | named | excess | M1 event / control | M2 event / control "
          "| M3 event / control | ringing event / control | quiet window (s) "
          "| ringing last 0.05 s / first half, event / control | at first step M1 / M2 / M3 | boxes "
          "| cancellation | leading |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    tally, ratios, trend_of = {}, {}, {}
    for (_, case, e), j in zip(chosen, results):
        p = (j or {}).get("precursors")
        if p is None:
            continue
        ev, ct, on = p["quiet_event"], p["quiet_control"], p["onset_event"]
        pair = lambda k: f"{f(ev[k])} / {f(ct[k])}"
        te, tc = trends(case, e, j)
        print(f"| {os.path.basename(case)} | {e['id']} | {e['cause']} | {e['t']:.3f} | {p['named']} | "
              f"{f(p['excess'])} | {pair('m1_light_node')} | {pair('m2_cell_crossing')} | "
              f"{pair('m3_stress_outlier')} | {ringing(p)} | {window_s(j)} | {f(te)} / {f(tc)} | "
              f"{f(on['m1_light_node'])} / {f(on['m2_cell_crossing'])} / {f(on['m3_stress_outlier'])} | {p['control_boxes']} | {f(j['cancellation'])} | "
              f"{j['leading']['mechanism']} |")
        cause = "impact" if e["cause"] == "impact" else "kick"
        tally.setdefault(cause, {}).setdefault(p["named"], 0)
        tally[cause][p["named"]] += 1
        if p.get("ringing_event") is not None and p.get("ringing_control"):
            ratios.setdefault(cause, []).append(p["ringing_event"] / p["ringing_control"])
        for who, t in (("event", te), ("controls", tc)):
            if t is not None:
                trend_of.setdefault((cause, who), []).append(t)
    print()
    for cause, names in sorted(tally.items()):
        n = sum(names.values())
        print(f"{cause}: {n} explained; named precursor: "
              + ", ".join(f"{k} {v} of {n}" for k, v in sorted(names.items(), key=lambda x: -x[1])))
        r = sorted(ratios.get(cause, []))
        if r:
            print(f"{cause}: quiet-window ringing above its controls' in {sum(x > 1 for x in r)} of "
                  f"{len(r)}; event / control median {statistics.median(r):.2f} [{r[0]:.2f}, {r[-1]:.2f}]")
        for who in ("event", "controls"):
            r = sorted(trend_of.get((cause, who), []))
            if r:
                print(f"{cause}, {who}: ringing of the last 0.05 s above the window's first half in "
                      f"{sum(x > 1 for x in r)} of {len(r)}; ratio median {statistics.median(r):.2f} "
                      f"[{r[0]:.2f}, {r[-1]:.2f}]")


def ringing(p):
    """The quiet window's ringing (mean drift over sqrt(g H)), event / control."""
    e, c = p.get("ringing_event"), p.get("ringing_control")
    g = lambda x: "-" if x is None else f"{x:.2g}"
    return f"{g(e)} / {g(c)}" if "ringing_event" in p else "-"


def trends(case, e, j):
    """(event, controls): the mean drift over the quiet window's last 0.05 s
    (before the onset window) over that in its first half, of the event's
    particles and of the matched quiet boxes' (None where not recorded):
    above 1 when the ringing grows towards the kick. Nones for windows
    under 0.2 s."""
    w = j["window"]
    path = os.path.join(case, "explain", f"event_{e['id']}", "explain_steps.csv")
    if w["onset_from"] - w["explain_from"] < 0.19 or not os.path.exists(path):
        return None, None
    with open(path) as f:
        rows = [r for r in csv.DictReader(f) if float(r["onset"]) == 0.0]
    mid = 0.5 * (w["explain_from"] + w["onset_from"])

    def ratio(column):
        value = lambda r: float(r[column]) if r.get(column) else math.nan
        first = [value(r) for r in rows if float(r["t"]) < mid]
        last = [value(r) for r in rows if float(r["t"]) >= w["onset_from"] - 0.05]
        first, last = [x for x in first if x == x], [x for x in last if x == x]
        if not first or not last or statistics.mean(first) == 0.0:
            return None
        return statistics.mean(last) / statistics.mean(first)
    return ratio("m4_drift_speed"), ratio("m4_drift_speed_control")


def quiet_seconds(j):
    """How far before the event its quiet window started (s)."""
    w = j["window"]
    return w["onset_from"] - w["explain_from"] + 0.01


def window_s(j):
    return f"{quiet_seconds(j):.2f}"


def hallmark(e):
    """The monitor's hallmark (monitor::Event::hallmark): quiet before, and
    most of its particles past the strain-rate threshold earlier (a large
    distortion of F alone does not count)."""
    return "yes" if e["quiescent_before"] and "strain_rate" in e["deformed_by"] else "no"


def prevents(j, tally):
    """The counterfactual changes that prevented the event (verdict
    `prevented`: it did not happen again over its cells, the replay completed
    the window, and no other non-physical event opened); none when the
    unchanged replay itself missed the event (inconclusive). Each other
    change is listed by its verdict: blew up, moved, again."""
    cf = j.get("counterfactual") or []
    if not cf:
        return "-"
    if any("verdict" not in c for c in cf):
        return "(replayed before verdicts: rerun with --counterfactual)"
    control = [c for c in cf if c["change"] == "unchanged"]
    if control and control[0]["verdict"] != "again":
        return "(control did not reproduce the event: inconclusive)"
    names = [c["change"] for c in cf if c["change"] != "unchanged" and c["verdict"] == "prevented"]
    for n in names:
        tally[n] = tally.get(n, 0) + 1
    others = [f'{c["change"]}: {c["verdict"]}' for c in cf
              if c["change"] != "unchanged" and c["verdict"] not in ("prevented", "again")]
    text = ", ".join(names) if names else "none"
    return text + (f" (not: {'; '.join(others)})" if others else "")


def explain_done(case, event):
    out = os.path.join(case, "explain", f"event_{event}", "explain.json")
    return json.load(open(out)) if os.path.exists(out) else None


if __name__ == "__main__":
    main()
