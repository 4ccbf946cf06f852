#!/usr/bin/env python3
"""Run a study's cases one by one and keep a compact record of each in a CSV
that survives the run folders (the remedies study rerun with a full event
store takes about 8 core-hours, more than one sitting).

    python3 scripts/record_cases.py STUDY --record CSV --out RUNDIR [--kick PATH]
        [--jobs 2] [--set KEY=VALUE ...] [--shard I/N] [--until HH:MM]
        [--only REGEX]

Cases already in CSV are skipped; each case that finishes appends its row at
once (a run stopped half way loses only the cases under way). A row holds the
run's outcome, its kicks, its anomaly-proper events (kicks with the hallmark:
quiet before and deformed by strain rate, the ids `kick explain --event`
takes), the events the store dropped, and the late checkerboard measures
(the old particle-means index beside the cell and nodal ones) and the late
hydrostatic departure. A record written by an older version of this script
keeps its columns. `--until`
starts no case after that time of day (UTC). `--shard I/N` takes the cases
at positions I, I + N, ... of `kick list STUDY`; `--only REGEX` the cases
whose name it matches (two processes on one record must not share a case:
each reads the record once, when it starts).
"""
import argparse
import csv
import datetime
import json
import os
import re
import subprocess
import threading
from concurrent.futures import ThreadPoolExecutor

FIELDS = [
    "case", "status", "reason", "steps", "t_end", "wall_s", "n_kicks",
    "n_anomalies", "anomaly_events", "n_events_stored", "events_dropped",
    "t_first_kick", "checkerboard_means_late", "checkerboard_cell_late",
    "checkerboard_nodal_late", "hydro_rel_rms_late", "hydro_excess_late",
    "n_energy_injections", "final_state_hash", "settings",
]


def row_of(summary_path, settings):
    s = json.load(open(summary_path))
    m, f = s["metrics"], s["metrics"]["figures"]
    anomalies = [
        e["id"] for e in s["events"]
        if e["cause"] in ("injection", "inversion")
        and e["quiescent_before"] and "strain_rate" in e["deformed_by"]
    ]
    return {
        "case": s["case"], "status": s["status"], "reason": s.get("reason") or "",
        "steps": s["steps"], "t_end": s["t_end"], "wall_s": round(s["wall_s"], 1),
        "n_kicks": m["n_kicks"], "n_anomalies": m["n_anomalies"],
        "anomaly_events": " ".join(str(i) for i in anomalies),
        "n_events_stored": len(s["events"]), "events_dropped": m["events_dropped"],
        "t_first_kick": m["t_first_kick"],
        "checkerboard_means_late": f["checkerboard_means_late"],
        "checkerboard_cell_late": f["checkerboard_cell_late"],
        "checkerboard_nodal_late": f["checkerboard_nodal_late"],
        "hydro_rel_rms_late": f["hydro_rel_rms_late"],
        "hydro_excess_late": f["hydro_excess_late"],
        "n_energy_injections": m["n_energy_injections"],
        "final_state_hash": s["final_state_hash"], "settings": settings,
    }


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("study")
    ap.add_argument("--record", required=True)
    ap.add_argument("--out", required=True)
    ap.add_argument("--kick", default="target/release/kick")
    ap.add_argument("--jobs", type=int, default=2)
    ap.add_argument("--set", action="append", default=[])
    ap.add_argument("--shard")
    ap.add_argument("--until")
    ap.add_argument("--only", help="regular expression: run only the cases it matches (searched in the name)")
    a = ap.parse_args()

    listed = subprocess.run([a.kick, "list", a.study], check=True, capture_output=True, text=True)
    cases = [line.split("\t")[0] for line in listed.stdout.splitlines() if line.strip()]
    if a.shard:
        i, n = (int(v) for v in a.shard.split("/"))
        cases = cases[i::n]
    if a.only:
        cases = [c for c in cases if re.search(a.only, c)]
    done = set()
    if os.path.exists(a.record):
        done = {r["case"] for r in csv.DictReader(open(a.record))}
    todo = [c for c in cases if c not in done]
    print(f"{len(cases)} cases, {len(done & set(cases))} recorded, {len(todo)} to run")
    lock = threading.Lock()
    settings = " ".join(a.set)
    deadline = None
    if a.until:
        hh, mm = (int(v) for v in a.until.split(":"))
        now = datetime.datetime.now(datetime.timezone.utc)
        deadline = now.replace(hour=hh, minute=mm, second=0, microsecond=0)
        if deadline <= now:
            # A time of day already past means tomorrow's (a sitting across midnight).
            deadline += datetime.timedelta(days=1)

    def run(case):
        if deadline and datetime.datetime.now(datetime.timezone.utc) >= deadline:
            return
        cmd = [a.kick, "run", a.study, "--case", case, "--out", a.out, "--threads", "1"]
        for kv in a.set:
            cmd += ["--set", kv]
        log = open(os.path.join(a.out, case + ".log"), "w")
        code = subprocess.run(cmd, stdout=log, stderr=subprocess.STDOUT).returncode
        summary = os.path.join(a.out, case, "summary.json")
        if code != 0 or not os.path.exists(summary):
            print(f"{case}: exit {code}, no summary (not recorded)")
            return
        row = row_of(summary, settings)
        with lock:
            new = not os.path.exists(a.record)
            # An older record keeps its own columns.
            fields = FIELDS if new else next(csv.reader(open(a.record)))
            with open(a.record, "a", newline="") as fh:
                w = csv.DictWriter(fh, fieldnames=fields, extrasaction="ignore")
                if new:
                    w.writeheader()
                w.writerow(row)
        print(f"{case}: {row['status']}, {row['n_kicks']} kicks, anomalies [{row['anomaly_events']}], "
              f"dropped {row['events_dropped']}, {row['wall_s']} s")

    os.makedirs(a.out, exist_ok=True)
    with ThreadPoolExecutor(a.jobs) as pool:
        list(pool.map(run, todo))


if __name__ == "__main__":
    main()
