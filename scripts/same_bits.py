#!/usr/bin/env python3
"""Record and compare "same bits" evidence for a refactor.

A refactor that must not change results is checked by running a fixed set of
cases with one solver thread before and after it, and comparing the final
state hash, step count, status and event list of each, plus the exact
`kick list` output of every shipped study (case names must not drift).

Usage:
  scripts/same_bits.py record --kick BIN --studies DIR --work WORKDIR \\
      --out RESULT.json [--jobs N]
  scripts/same_bits.py compare A.json B.json

`record` runs the cases into WORKDIR/<study>__t<t_end>/<case>/ (with
--csv) and writes RESULT.json, with a digest of every column of each CSV
table the case wrote (timeseries per phase, mixture, terzaghi) and the
summary's metrics flattened to dotted keys. A case that fails to run is recorded with its exit code and
stderr instead of aborting the script. `compare` prints one row per case and
a unified diff of the `list` output of each study, and exits 1 on any
difference (including a case that failed or is missing on either side).
Standard library only (Python >= 3.11 for tomllib).
"""
import argparse
import concurrent.futures
import csv
import hashlib
import datetime
import difflib
import json
import os
import shutil
import subprocess
import sys
import time
import tomllib
from pathlib import Path

SCHEMA = 2

# Bug-report cases run to 0.6 s (names are checked against `kick list`).
BUG_REPORT_CASES = [
    "K15kPa_power-g7_mu0_fixed_e0",
    "K1.5MPa_tait_mu0.5_fixed_e0",
    "K150kPa_power-g1_mu0_dyn_e0",
    "K15MPa_power-g4_mu0.5_dyn_e0",
]
REMEDIES_FULL_CASE = (
    "K1.5MPa_tait_mu0.5_flip-pic_damping_time0.00005-j_bar1.0-linear-"
    "volume_relaxation_time0.16-shift_time0.02-shift_surface_share0.25-ppc3"
)
# Multiphase studies: first case in list order; None = the study's own t_end.
MULTIPHASE = [
    ("drag_decay.toml", None),
    ("darcy.toml", None),
    ("terzaghi.toml", 0.05),
    ("filter_stone.toml", 0.2),
]
# Cap on a multiphase study's own t_end (simulated seconds).
OWN_T_END_CAP = 1.0


def log(msg):
    print(msg, file=sys.stderr, flush=True)


def run_list(kick, study):
    """Exact stdout of `kick list STUDY` (bytes decoded as UTF-8), exit code, stderr."""
    p = subprocess.run([kick, "list", str(study)], capture_output=True)
    return (p.stdout.decode("utf-8", "surrogateescape"), p.returncode,
            p.stderr.decode("utf-8", "replace"))


def case_names(list_stdout):
    """Case names: the first tab-separated column of each non-empty line."""
    return [line.split("\t", 1)[0] for line in list_stdout.splitlines() if line.strip()]


def own_t_end(study):
    with open(study, "rb") as f:
        return float(tomllib.load(f)["scene"]["t_end"])


def fmt_t(t):
    return repr(float(t))


class Plan:
    """The fixed case list, resolved against `kick list` output."""

    def __init__(self, kick, studies):
        self.kick, self.studies = kick, Path(studies)
        self.lists = {}   # study file name -> {"stdout", "returncode", "stderr"}
        self.cases = []   # dicts: id, study, case, t_end, set_t_end, group
        self.notes = []
        self.errors = []

    def names(self, study_file):
        if study_file not in self.lists:
            out, rc, err = run_list(self.kick, self.studies / study_file)
            self.lists[study_file] = {"stdout": out, "returncode": rc, "stderr": err}
        entry = self.lists[study_file]
        if entry["returncode"] != 0:
            raise SystemExit(f"`kick list {study_file}` failed ({entry['returncode']}):\n{entry['stderr']}")
        return case_names(entry["stdout"])

    def add(self, group, study_file, case, t_end=None):
        """t_end None: run with the study's own t_end (no --set)."""
        if case not in self.names(study_file):
            self.errors.append(f"{study_file}: case {case!r} is not in `kick list` output")
            return
        set_t = t_end is not None
        if t_end is None:
            t_end = own_t_end(self.studies / study_file)
        cid = f"{study_file}::{case}::t_end={fmt_t(t_end)}"
        if any(c["id"] == cid for c in self.cases):
            self.notes.append(f"{cid} listed twice, run once")
            return
        self.cases.append({"id": cid, "group": group, "study": study_file, "case": case,
                           "t_end": float(t_end), "set_t_end": set_t})

    def build(self):
        for f in sorted(self.studies.glob("*.toml")):
            self.names(f.name)
        # 1. quick: every case, own t_end.
        for c in self.names("quick.toml"):
            self.add("1 quick", "quick.toml", c)
        # 2. dam_break: first case, own t_end.
        self.add("2 dam_break", "dam_break.toml", self.first("dam_break.toml"))
        # 3. bug_report: four cases at 0.6 s.
        listed = self.names("bug_report.toml")
        for c in BUG_REPORT_CASES:
            if c not in listed and c.removesuffix("_e0") in listed:
                self.notes.append(f"bug_report.toml: {c} is listed without the _e0 suffix")
                c = c.removesuffix("_e0")
            self.add("3 bug_report", "bug_report.toml", c, 0.6)
        # 4. remedies: the full-stack remedy at 0.5 s.
        self.add("4 remedies", "remedies.toml", REMEDIES_FULL_CASE, 0.5)
        # 5. multiphase: first case of each.
        for study, t in MULTIPHASE:
            if t is None:
                own = own_t_end(self.studies / study)
                if own > OWN_T_END_CAP:
                    self.notes.append(f"{study}: own t_end {own} s cut to {OWN_T_END_CAP} s")
                    t = OWN_T_END_CAP
            self.add("5 multiphase", study, self.first(study), t)
        # 6. remedies: every method at K = 1.5 MPa Tait, viscosity 0.5.
        sel = [c for c in self.names("remedies.toml") if c.startswith("K1.5MPa_tait_mu0.5_")]
        self.require(sel, "remedies.toml", "K1.5MPa_tait_mu0.5_*")
        for c in sel:
            self.add("6 remedies", "remedies.toml", c, 0.2)
        # 7. ablation: every method at K = 1.5 MPa Tait, inviscid, member e0.
        sel = [c for c in self.names("ablation.toml")
               if c.startswith("K1.5MPa_tait_mu0_") and c.endswith("_e0")]
        self.require(sel, "ablation.toml", "K1.5MPa_tait_mu0_*_e0")
        for c in sel:
            self.add("7 ablation", "ablation.toml", c, 0.2)
        # 8. pressure-implicit dam break at h = 1 cm, 1.5 MPa Tait, to 1 s.
        sel = [c for c in self.names("pressure_implicit.toml")
               if c.startswith("h1cm_tait-K1.5MPa_")]
        self.require(sel, "pressure_implicit.toml", "h1cm_tait-K1.5MPa_*")
        for c in sel:
            self.add("8 pressure_implicit", "pressure_implicit.toml", c, 1.0)
        if self.errors:
            raise SystemExit("case list does not match `kick list`:\n  " + "\n  ".join(self.errors))
        return self

    def first(self, study_file):
        names = self.names(study_file)
        if not names:
            raise SystemExit(f"`kick list {study_file}` printed no cases")
        return names[0]

    def require(self, sel, study_file, pattern):
        if not sel:
            self.errors.append(f"{study_file}: no case matches {pattern}")


def run_case(kick, studies, work, c):
    out = Path(work) / f"{Path(c['study']).stem}__t{fmt_t(c['t_end'])}"
    case_dir = out / c["case"]
    if case_dir.exists():
        shutil.rmtree(case_dir)  # never read a stale summary.json
    out.mkdir(parents=True, exist_ok=True)
    cmd = [kick, "run", str(Path(studies) / c["study"]), "--case", c["case"],
           "--out", str(out), "--threads", "1", "--csv"]
    if c["set_t_end"]:
        cmd += ["--set", f"scene.t_end={fmt_t(c['t_end'])}"]
    t0 = time.monotonic()
    try:
        p = subprocess.run(cmd, capture_output=True)
        rc, stderr = p.returncode, p.stderr.decode("utf-8", "replace")
    except OSError as e:
        rc, stderr = None, f"could not start: {e}"
    wall = time.monotonic() - t0
    rec = {"study": c["study"], "case": c["case"], "t_end_requested": c["t_end"],
           "group": c["group"], "command": cmd, "returncode": rc, "wall_s": round(wall, 3)}
    summary = case_dir / "summary.json"
    if rc != 0 or not summary.is_file():
        rec["error"] = stderr[-20000:] or f"exit code {rc}, no {summary}"
        return rec
    try:
        s = json.loads(summary.read_text())
        rec.update({
            "final_state_hash": s["final_state_hash"],
            "steps": s["steps"],
            "status": s["status"],
            "reason": s.get("reason", ""),
            "t_end": s.get("t_end"),
            "n_events": len(s["events"]),
            "events": [[e["first_step"], e["t"], e["cause"]] for e in s["events"]],
            "metrics": flatten(s.get("metrics", {})),
            "tables": {f.name: column_digests(f) for f in sorted(case_dir.glob("*.csv"))},
        })
    except (ValueError, KeyError, TypeError) as e:
        rec["error"] = f"unreadable {summary}: {e!r}\n{stderr[-5000:]}"
    return rec


def flatten(obj, prefix=""):
    """Nested JSON objects as one dict of dotted keys (leaves as they are)."""
    out = {}
    for k, v in obj.items():
        key = f"{prefix}{k}"
        if isinstance(v, dict):
            out.update(flatten(v, key + "."))
        else:
            out[key] = v
    return out


def column_digests(path):
    """sha256 of each CSV column's cells (by header name) and the row count."""
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    if not rows:
        return {}
    header, body = rows[0], rows[1:]
    digests = {"#rows": len(body)}
    for k, name in enumerate(header):
        h = hashlib.sha256()
        for r in body:
            h.update((r[k] if k < len(r) else "").encode() + b"\n")
        digests[name] = h.hexdigest()[:16]
    return digests


def kick_version(kick):
    try:
        p = subprocess.run([kick, "--version"], capture_output=True, text=True)
        return p.stdout.strip()
    except OSError as e:
        return f"unavailable: {e}"


def record(args):
    kick = str(Path(args.kick).resolve()) if os.sep in args.kick else args.kick
    plan = Plan(kick, args.studies).build()
    for n in plan.notes:
        log(f"note: {n}")
    n = len(plan.cases)
    log(f"{n} cases, {args.jobs} job(s), work in {args.work}")
    t0 = time.monotonic()
    results, done = {}, 0
    with concurrent.futures.ThreadPoolExecutor(max_workers=args.jobs) as pool:
        futs = {pool.submit(run_case, kick, args.studies, args.work, c): c for c in plan.cases}
        for fut in concurrent.futures.as_completed(futs):
            c, rec = futs[fut], fut.result()
            results[c["id"]] = rec
            done += 1
            state = "FAILED" if "error" in rec else f"{rec['status']} {rec['steps']} steps {rec['n_events']} events"
            log(f"[{done}/{n}] {c['id']}: {state} ({rec['wall_s']:.1f} s)")
    doc = {
        "schema": SCHEMA,
        "kick": kick,
        "kick_version": kick_version(kick),
        "studies": str(Path(args.studies).resolve()),
        "recorded_at": datetime.datetime.now(datetime.timezone.utc).isoformat(timespec="seconds"),
        "wall_s": round(time.monotonic() - t0, 1),
        "notes": plan.notes,
        "cases": {c["id"]: results[c["id"]] for c in plan.cases},
        "lists": plan.lists,
    }
    out = Path(args.out)
    tmp = out.with_name(out.name + ".tmp")
    tmp.write_text(json.dumps(doc, indent=1) + "\n")
    tmp.replace(out)
    failed = [k for k, r in doc["cases"].items() if "error" in r]
    log(f"wrote {out}: {n} cases, {len(failed)} failed, {doc['wall_s']} s")
    for k in failed:
        log(f"  failed: {k}")
    return 0


FIELDS = [("hash", "final_state_hash"), ("steps", "steps"),
          ("status", ("status", "reason")), ("events", "events")]


def table_differences(ra, rb):
    """Columns (table:column) whose cells differ, and those on one side only."""
    ta, tb = ra.get("tables", {}), rb.get("tables", {})
    differ, one_side = [], []
    for table in sorted(set(ta) | set(tb)):
        ca, cb = ta.get(table), tb.get(table)
        if ca is None or cb is None:
            one_side.append(f"{table} (only in {'B' if ca is None else 'A'})")
            continue
        for col in sorted(set(ca) | set(cb)):
            if col not in ca or col not in cb:
                one_side.append(f"{table}:{col} (only in {'B' if col not in ca else 'A'})")
            elif ca[col] != cb[col]:
                differ.append(f"{table}:{col}")
    return differ, one_side


def metric_differences(ra, rb):
    """Metrics (dotted keys) whose values differ, and those on one side only."""
    ma, mb = ra.get("metrics", {}), rb.get("metrics", {})
    differ = [k for k in sorted(set(ma) & set(mb)) if ma[k] != mb[k]]
    one_side = sorted(set(ma) ^ set(mb))
    return differ, one_side


def field(rec, key):
    if isinstance(key, tuple):
        return tuple(rec.get(k) for k in key)
    return rec.get(key)


def compare(args):
    a, b = (json.loads(Path(p).read_text()) for p in (args.a, args.b))
    ids = list(a["cases"]) + [k for k in b["cases"] if k not in a["cases"]]
    width = max([len(i) for i in ids] + [4])
    print(f"A: {args.a} ({a.get('kick')}, {a.get('kick_version')})")
    print(f"B: {args.b} ({b.get('kick')}, {b.get('kick_version')})")
    print()
    print(f"{'case':<{width}}  " + "  ".join(f"{name:<9}" for name, _ in FIELDS)
          + "  tables     metrics")
    n_diff = 0
    for cid in ids:
        ra, rb = a["cases"].get(cid), b["cases"].get(cid)
        if ra is None or rb is None:
            cells = ["missing " + ("A" if ra is None else "B")] * len(FIELDS)
        elif "error" in ra or "error" in rb:
            who = "A+B" if "error" in ra and "error" in rb else ("A" if "error" in ra else "B")
            cells = [f"failed {who}"] * len(FIELDS)
        else:
            cells = ["same" if field(ra, k) == field(rb, k) else "DIFFERENT" for _, k in FIELDS]
        details = []
        if ra is not None and rb is not None and "error" not in ra and "error" not in rb:
            t_diff, t_one = table_differences(ra, rb)
            m_diff, m_one = metric_differences(ra, rb)
            if "tables" in ra and "tables" in rb:
                n_cols = sum(len(c) - 1 for c in ra["tables"].values())
                cells.append("DIFFERENT" if t_diff else f"same({n_cols})")
                details += [f"    column differs: {c}" for c in t_diff]
                details += [f"    column on one side: {c}" for c in t_one]
            if "metrics" in ra and "metrics" in rb:
                cells.append("DIFFERENT" if m_diff else "same")
                details += [f"    metric differs: {k}: {ra['metrics'][k]!r} vs {rb['metrics'][k]!r}"
                            for k in m_diff]
                details += [f"    metric on one side: {k}" for k in m_one]
        if any(not c.startswith("same") for c in cells):
            n_diff += 1
        print(f"{cid:<{width}}  " + "  ".join(f"{c:<9}" for c in cells))
        for d in details:
            print(d)
    print()
    n_list_diff = 0
    studies = sorted(set(a.get("lists", {})) | set(b.get("lists", {})))
    for study in studies:
        la = a.get("lists", {}).get(study, {}).get("stdout")
        lb = b.get("lists", {}).get(study, {}).get("stdout")
        diff = list(difflib.unified_diff(
            (la or "").splitlines(keepends=True), (lb or "").splitlines(keepends=True),
            fromfile=f"A/{study}", tofile=f"B/{study}"))
        differs = la != lb
        n_list_diff += differs
        state = ("missing in " + ("A" if la is None else "B")) if la is None or lb is None else (
            "DIFFERENT" if differs else "identical")
        print(f"== kick list {study}: {state}")
        sys.stdout.writelines(d if d.endswith("\n") else d + "\n\\ No newline at end of file\n"
                              for d in diff)
    print()
    print(f"{len(ids)} cases, {n_diff} with a difference; "
          f"{len(studies)} study lists, {n_list_diff} differing")
    return 1 if n_diff or n_list_diff else 0


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    sub = ap.add_subparsers(dest="cmd", required=True)
    r = sub.add_parser("record", help="run the fixed case list and write RESULT.json")
    r.add_argument("--kick", required=True, help="kick binary")
    r.add_argument("--studies", required=True, help="folder of study files (*.toml)")
    r.add_argument("--work", required=True, help="folder for the case outputs")
    r.add_argument("--out", required=True, help="RESULT.json to write")
    r.add_argument("--jobs", type=int, default=1, help="cases run in parallel (default 1)")
    c = sub.add_parser("compare", help="compare two RESULT.json files; exit 1 on any difference")
    c.add_argument("a")
    c.add_argument("b")
    args = ap.parse_args()
    if args.cmd == "record":
        if args.jobs < 1:
            ap.error("--jobs must be >= 1")
        return record(args)
    return compare(args)


if __name__ == "__main__":
    sys.exit(main())
