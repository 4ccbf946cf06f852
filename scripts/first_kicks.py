#!/usr/bin/env python3
"""Per K and EOS table of a bug-report matrix output (summary.json only):
cause and median time of the first kick, the hallmark, survival median
[min, max] per dt mode, and the evidence of the first kicks (energy rise over
its floor, Courant number before onset). Usage: scripts/first_kicks.py OUT
[OUT ...] (several matrix folders are read as one, e.g. the halves of the
matrix run with --only)."""
import json, statistics, sys
from collections import defaultdict
from pathlib import Path

# The kick causes: the calibrated detector adds `jump` (a velocity jump
# against a calm local flow) to the former detector's two.
KICK = ("injection", "inversion", "jump")

def first_kick(s):
    kicks = [e for e in s["events"] if e["cause"] in KICK]
    return min(kicks, key=lambda e: (e["t"], e["id"])) if kicks else None

def eos_name(p):
    if p["materials.water.eos"] == "tait":
        return "Tait"
    return f"power g{p['materials.water.gamma']:g}"

def k_name(k):
    return f"{k/1e6:g} MPa" if k >= 1e6 else f"{k/1e3:g} kPa"

def survival(s):
    return s["params"]["scene.t_end"] if s["status"] == "completed" else s["t_end"]

def spread(v):
    return f"{statistics.median(v):.2f} [{min(v):.2f}, {max(v):.2f}]"

def main(outs):
    missing = [out for out in outs if not Path(out).is_dir()]
    if missing:
        print(f"first_kicks.py: no such folder: {', '.join(missing)}", file=sys.stderr)
        sys.exit(2)
    rows, seen = [], set()
    for out in outs:
        for f in sorted(Path(out).glob("*/summary.json")):
            s = json.load(open(f))
            if s["case"] in seen:
                print(f"first_kicks.py: {s['case']} read again from {out}; the first kept", file=sys.stderr)
                continue
            seen.add(s["case"])
            rows.append(s)
    if not rows:
        print("first_kicks.py: no summary.json in the folders given", file=sys.stderr)
        sys.exit(2)
    groups = defaultdict(lambda: defaultdict(list))
    for s in rows:
        p = s["params"]
        key = (p["materials.water.K"], eos_name(p))
        groups[key][p["method.dt"]].append(s)
    print(f"{len(rows)} runs; {sum(s['status'] == 'completed' for s in rows)} completed")
    print("| K | EOS | first kick, fixed dt: cause, median t | dynamic dt | hallmark | survived, fixed dt | dynamic dt |")
    print("|---|---|---|---|---|---|---|")
    ratios, courants, first_causes, hallmarks = [], [], defaultdict(int), 0
    for (k, eos), modes in sorted(groups.items()):
        cells, surv = [], []
        n_hall = n_runs = 0
        for mode in ("fixed", "dynamic"):
            runs = modes.get(mode, [])
            causes, times = defaultdict(int), []
            for s in runs:
                e = first_kick(s)
                if e is None:
                    causes["none"] += 1
                    continue
                causes[e["cause"]] += 1
                first_causes[e["cause"]] += 1
                times.append(e["t"])
                if e["evidence"]["energy_floor"] > 0 and e["cause"] == "injection":
                    ratios.append(e["energy_injected"] / e["evidence"]["energy_floor"])
                if e["cause"] == "injection":
                    courants.append(e["evidence"]["courant_before"])
                anomaly = e["quiescent_before"] and "strain_rate" in e["deformed_by"]
                n_hall += anomaly
            n_runs += len(runs)
            c = ", ".join(f"{name} {count}/{len(runs)}" for name, count in sorted(causes.items(), key=lambda x: -x[1]))
            t = f"{statistics.median(times):.2f} s" if times else "-"
            cells.append(f"{c}; {t}")
            sv = [survival(s) for s in runs]
            done = sum(s["status"] == "completed" for s in runs)
            surv.append(spread(sv) + (f" ({done} completed)" if done else "") if sv else "-")
        hallmarks += n_hall
        print(f"| {k_name(k)} | {eos} | {cells[0]} | {cells[1]} | {n_hall}/{n_runs} | {surv[0]} | {surv[1]} |")
    print()
    print("first kicks by cause:", dict(first_causes), "; with the hallmark:", hallmarks)
    if ratios:
        r = sorted(ratios)
        print(f"injection first kicks, energy rise / floor: median {statistics.median(r):.3g}, min {r[0]:.3g}, max {r[-1]:.3g}")
    if courants:
        print(f"Courant before the first kick (injections): median {statistics.median(courants):.3g}, max {max(courants):.3g}")
    anomalies = [(s["case"], e["id"], e["t"]) for s in rows for e in s["events"]
                 if e["cause"] in KICK and e["quiescent_before"] and "strain_rate" in e["deformed_by"]]
    print("anomalies proper (kick with the hallmark):", len(anomalies), anomalies[:10])
    events = [e for s in rows for e in s["events"]]
    by = defaultdict(int)
    for e in events:
        by[e["cause"]] += 1
    print("all events by cause:", dict(by))
    # Injections within 1e-9 J/m of their floor: a label a change of the
    # floor's round-off term (1e-12 of the energies) could flip.
    near = [e for e in events if e["cause"] == "injection"
            and e["energy_injected"] - e["evidence"]["energy_floor"] < 1e-9]
    print("injection events within 1e-9 J/m of their floor:", len(near))
    walls = [s["wall_s"] for s in rows]
    print(f"run time: {sum(walls):.0f} s in all, longest {max(walls):.0f} s; steps {sum(s['steps'] for s in rows)}")

if __name__ == "__main__":
    main(sys.argv[1:] or ["reports/bug_report"])
