#!/usr/bin/env python3
"""The findings check: rerun a fixed sample of headline figures and compare
each with its recorded value (docs/findings/README.md, "The findings
check").

    python3 scripts/findings_check.py [--kick PATH] [--out DIR] [--only NAME ...]
    python3 scripts/findings_check.py --record      # write the recorded values

kick is deterministic, so every recorded figure must come back exactly
(floats compared bit for bit after a JSON round trip); only wall times get
a tolerance (`WALL_FACTOR` either way, reported, never failing the check:
machines differ). Each sample also names the sentence or table row of its
findings file that states the figure, rebuilt from the rerun with that
file's rounding: the check fails when the file no longer says what the code
gives.

Recorded values: docs/findings/data/findings_check.json (each sample with
the commit and date it was recorded at; `+changes` marks a tree that
differed from that commit). The sample runs from shipped study files
only; the file records each sample's wall time. Exit 0 when everything matches, 1 when a figure
or a findings sentence differs, 2 on a usage error or a failed command.
Standard library only.
"""
import argparse
import json
import math
import os
import re
import shutil
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
RECORD = ROOT / "docs" / "findings" / "data" / "findings_check.json"
WALL_FACTOR = 4.0


def summaries(folder):
    """Every case's summary.json under a matrix folder, by case name."""
    out = {}
    for s in sorted(Path(folder).glob("*/summary.json")):
        d = json.loads(s.read_text())
        out[d["case"]] = d
    return out


def spread(v):
    return f"{statistics.median(v):.2f} [{min(v):.2f}, {max(v):.2f}]"


def run_facts(d):
    """What a run's summary pins: outcome, length, final state and kicks."""
    m = d["metrics"]
    return {
        "status": d["status"],
        "steps": d["steps"],
        "t_end": d["t_end"],
        "final_state_hash": d["final_state_hash"],
        "n_kicks": m["n_kicks"],
        "t_first_kick": m["t_first_kick"],
        "causes": m["causes"],
    }


# --- the sample ------------------------------------------------------------


def bug_report_15kpa(kick, out):
    cmd = [kick, "matrix", "studies/bug_report.toml", "--out", str(out), "--only", "K15kPa",
           "--only", "_e0", "--jobs", "2", "--threads", "1"]
    return [cmd]


def bug_report_15kpa_values(out):
    runs = summaries(out)
    firsts = [d["metrics"]["t_first_kick"] for d in runs.values()]
    survived = [d["params"]["scene.t_end"] if d["status"] == "completed" else d["t_end"]
                for d in runs.values()]
    values = {name: run_facts(d) for name, d in runs.items()}
    row = f"| 15 kPa | {len(runs)} | {spread(firsts)} | {spread(survived)} |"
    return values, [("docs/findings/bug_report.md", row)]


EXPLAINED = ("K15kPa_tait_mu0.5_fixed_e0", 14)


def explained_event(kick, out):
    # The event's own run, then its replay.
    case, event = EXPLAINED
    return [[kick, "matrix", "studies/bug_report.toml", "--out", str(out), "--only", case,
             "--jobs", "1", "--threads", "1"],
            [kick, "explain", str(out / case), "--event", str(event), "--threads", "1"]]


def explained_event_values(out):
    case, event = EXPLAINED
    e = json.loads((out / case / "explain" / f"event_{event}" / "explain.json").read_text())
    shares = e["shares"]
    values = {k: e[k] for k in ("matched", "replayed_state_hash", "steps_explained", "shares",
                                "cancellation", "leading", "largest_part")}
    row = (f"| {case}, event {event} | {shares['internal']:.2f} | {shares['jump']:.2f} | "
           f"{shares['small_mass_node']:.2f} | {shares['cell_crossing']:.2f} | "
           f"{shares['stress_outlier']:.2f} | {e['leading']['mechanism']} |")
    return values, [("docs/findings/explain.md", row)]


def pressure_implicit_h2cm(kick, out):
    return [[kick, "matrix", "studies/pressure_implicit.toml", "--out", str(out), "--only", "h2cm",
             "--jobs", "2", "--threads", "1"]]


def pressure_implicit_h2cm_values(out):
    runs = summaries(out)
    values = {name: run_facts(d) for name, d in runs.items()}
    n = len(runs)
    kicks = [d["metrics"]["n_kicks"] for d in runs.values()]
    firsts = [d["metrics"]["t_first_kick"] for d in runs.values()]
    anomalous = sum(d["metrics"]["n_anomalies"] > 0 for d in runs.values())
    row = (f"| 2 | {sum(k > 0 for k in kicks)} of {n} | {statistics.median(kicks):g} "
           f"[{min(kicks)}, {max(kicks)}] | {min(firsts):.2f}-{max(firsts):.2f} | {anomalous} of {n}")
    return values, [("docs/findings/pressure_implicit.md", row)]


# The Methods table reads the viscous run (scripts/yardsticks.py).
SLOSH = "base_h1cm_mu0.5_K1.5MPa"


def slosh_baseline(kick, out):
    return [[kick, "matrix", "studies/slosh.toml", "--out", str(out), "--only", SLOSH,
             "--jobs", "1", "--threads", "1"]]


def slosh_baseline_values(out):
    d = summaries(out)[SLOSH]
    check = d["metrics"]["checks"]["slosh"]
    values = dict(run_facts(d), slosh=check)
    period = 100.0 * check["period_error"]
    pattern = r"\| baseline \| [^|]+ \| " + re.escape(f"{period:+.2f} % |")
    return values, [("docs/findings/yardsticks.md", re.compile(pattern))]


def detector_at_rest(kick, out):
    # The bound set's explicit APIC at CFL 0.2 and its three implicit members.
    return [[kick, "calibrate", "studies/calibration_rest.toml", "--out", str(out), "--jobs", "2",
             "--threads", "1", "--set", "calibration.sizes=[2]", "--set", "matrix.method=[{ cfl = 0.2 }]"]]


def detector_at_rest_values(out):
    d = json.loads((out / "detection.json").read_text())
    keys = ("case", "place", "cells", "dv_found", "dv_missed", "delay_s", "cause", "false_alarms")
    rows = [{k: r.get(k) for k in keys} for r in d["rows"]]
    found = max(r["dv_found"] for r in rows)
    missed = max(r["dv_missed"] for r in rows)
    sentence = f"finds a planted patch from {found:.3f} m/s; it missed {missed:.3f}"
    return {"rows": rows}, [("docs/findings/detector_calibration.md", sentence)]


SAMPLE = {
    "bug_report_15kPa": (bug_report_15kpa, bug_report_15kpa_values),
    "explained_event": (explained_event, explained_event_values),
    "pressure_implicit_h2cm": (pressure_implicit_h2cm, pressure_implicit_h2cm_values),
    "slosh_baseline": (slosh_baseline, slosh_baseline_values),
    "detector_at_rest": (detector_at_rest, detector_at_rest_values),
}


# --- running and comparing --------------------------------------------------


def run_sample(name, kick, out):
    commands, values_of = SAMPLE[name]
    folder = out / name
    shutil.rmtree(folder, ignore_errors=True)
    started = time.monotonic()
    for cmd in commands(kick, folder):
        r = subprocess.run(cmd, cwd=ROOT, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
        if r.returncode != 0:
            sys.stderr.write(r.stderr)
            print(f"findings_check: {name}: `{' '.join(cmd)}` exited {r.returncode}", file=sys.stderr)
            sys.exit(2)
    wall = time.monotonic() - started
    try:
        values, statements = values_of(folder)
    except (OSError, KeyError, TypeError, ValueError, statistics.StatisticsError) as e:
        print(f"findings_check: {name}: its output in {folder} cannot be read: {e!r}", file=sys.stderr)
        sys.exit(2)
    # The JSON round trip: what is recorded is what is compared.
    return json.loads(json.dumps(values)), statements, wall


def stated(path, statement):
    """Whether the findings file states it (whitespace runs as one space)."""
    text = " ".join((ROOT / path).read_text().split())
    if isinstance(statement, re.Pattern):
        return statement.search(text) is not None
    return " ".join(statement.split()) in text


def differences(want, got, where=""):
    if isinstance(want, dict) and isinstance(got, dict):
        out = []
        for k in sorted(set(want) | set(got)):
            if k not in got or k not in want:
                out.append(f"{where}{k}: {'missing' if k not in got else 'not recorded'}")
            else:
                out += differences(want[k], got[k], f"{where}{k}.")
        return out
    if isinstance(want, list) and isinstance(got, list) and len(want) == len(got):
        return [d for i, (a, b) in enumerate(zip(want, got)) for d in differences(a, b, f"{where}{i}.")]
    same_nan = isinstance(want, float) and isinstance(got, float) and math.isnan(want) and math.isnan(got)
    return [] if want == got or same_nan else [f"{where.rstrip('.')}: recorded {want!r}, now {got!r}"]


def commit():
    """HEAD, marked `+changes` when the tracked sources differ from it (the
    recorded values themselves aside)."""
    git = lambda *a: subprocess.run(["git", *a], cwd=ROOT, capture_output=True, text=True)
    head = git("rev-parse", "--short", "HEAD").stdout.strip() or "unknown"
    changed = git("diff", "--quiet", "HEAD", "--", ".", f":!{RECORD.relative_to(ROOT)}").returncode
    return head + ("+changes" if changed else "")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--kick", default=str(ROOT / "target" / "release" / "kick"))
    ap.add_argument("--out", default=str(ROOT / "reports" / "findings_check"))
    ap.add_argument("--only", action="append", choices=sorted(SAMPLE), help="run only these samples")
    ap.add_argument("--record", action="store_true", help="write the recorded values instead of comparing")
    a = ap.parse_args()
    # The commands run from the repository's root: paths are made absolute.
    kick = str(Path(a.kick).resolve())
    if not os.access(kick, os.X_OK):
        print(f"findings_check: no kick binary at {kick} (make build)", file=sys.stderr)
        sys.exit(2)
    recorded = json.loads(RECORD.read_text()) if RECORD.exists() else {"sample": {}}
    names = a.only or list(SAMPLE)
    out = Path(a.out).resolve()
    stamp = {"commit": commit(), "date": time.strftime("%Y-%m-%d")}
    failed = 0
    for name in names:
        values, statements, wall = run_sample(name, kick, out)
        problems = [f"{p} does not state `{s.pattern if isinstance(s, re.Pattern) else s}`"
                    for p, s in statements if not stated(p, s)]
        if a.record:
            recorded["sample"][name] = dict(stamp, values=values, wall_s=round(wall, 1))
        else:
            want = recorded["sample"].get(name)
            if want is None:
                problems.append("no recorded value (run with --record)")
            else:
                problems += differences(want["values"], values)
                w = want["wall_s"]
                if not (w / WALL_FACTOR <= wall <= w * WALL_FACTOR):
                    print(f"  note: {name} took {wall:.0f} s against {w:.0f} s recorded")
        print(f"{name}: {'ok' if not problems else 'DIFFERS'} ({wall:.0f} s)")
        for p in problems:
            print(f"  {p}")
        failed += bool(problems)
    if a.record:
        recorded.pop("recorded", None)
        RECORD.write_text(json.dumps(recorded, indent=1, sort_keys=True) + "\n")
        print(f"recorded {len(names)} sample(s) at {stamp['commit']} in {RECORD.relative_to(ROOT)}")
    # Recorded or compared, a findings file that does not state the figure fails.
    sys.exit(1 if failed else 0)


if __name__ == "__main__":
    main()
