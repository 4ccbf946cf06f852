#!/usr/bin/env python3
"""Each remedy's energy booked (docs/physics.md section 4): does the budget close?

Usage: scripts/energy_booking.py DIR... [--factor 1.5]

DIR: `kick matrix` folders of studies/energy_booking.toml (or any matrix
whose summaries carry `budget_closure_max`). Reads every CASE/summary.json
and prints markdown:

- per scene (dam break, quiescent column, or other), one row per method:
  the largest |drift| of the budget with every remedy booked
  (`budget_closure_max`) and without the remedies' bookings
  (`budget_closure_unbooked_max`), the same of its remedy-free method (the
  same case with every `method.<remedy>` key removed), their ratio, the
  energy the remedies removed and added, and whether the booked closure
  is within FACTOR (1.5) times the remedy-free method's;
- the three checkerboards of each case, late (the last simulated second)
  and peak: the cell means of particle pressure (the old index) beside
  the nodal and cell measures;
- the events of each case whose cause is `injection`, with their kind
  (`energy_injection`: budget only, no flagged particle) and time.

A method's remedy-free method is only in the table if that case ran;
otherwise its row says so. Standard library only.
"""
import argparse
import json
import re
from pathlib import Path

# solver::remedies::REMEDY_KEYS.
REMEDIES = ["pic_damping", "min_node_mass", "f_reset", "bulk_damping", "cell_dilatation",
            "j_bar", "volume_relaxation", "pressure_smoothing", "null_space_filter", "shifting"]


def summaries(folders):
    for folder in folders:
        for path in sorted(Path(folder).glob("*/summary.json")):
            yield json.loads(path.read_text())


def is_remedy(key):
    parts = key.split(".")
    return len(parts) >= 2 and parts[0] == "method" and parts[1] in REMEDIES


def scene_of(p):
    box = p.get("scene.box")
    if box and box[0] < 0.5:
        at_rest = p.get("scene.initial") == "hydrostatic"
        return "column at rest" if at_rest else "column from zero stress"
    return "dam break"


def physics_of(p):
    """The case's physics: every parameter but the method's."""
    return tuple(sorted((k, json.dumps(v, sort_keys=True)) for k, v in p.items()
                        if not k.startswith("method") and k != "scene.ppc"))


def method_of(p, without_remedies=False):
    return tuple(sorted((k, json.dumps(v, sort_keys=True)) for k, v in p.items()
                        if (k.startswith("method") or k == "scene.ppc")
                        and not (without_remedies and is_remedy(k))))


def label(s):
    """The method part of the case name (after the viscosity), else the case."""
    m = re.search(r"_mu[0-9.]+_(.*)$", s["case"])
    return m.group(1) if m else s["case"]


def fmt(x, spec=".3g"):
    return "-" if x is None else format(x, spec)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("dirs", nargs="+")
    ap.add_argument("--factor", type=float, default=1.5)
    a = ap.parse_args()
    cases = list(summaries(a.dirs))
    by_key = {}
    for s in cases:
        p = s["params"]
        by_key[(physics_of(p), method_of(p))] = s
    rows = []
    for s in cases:
        p, f = s["params"], s["metrics"].get("figures", {})
        base = by_key.get((physics_of(p), method_of(p, True)))
        closure, unbooked = f.get("budget_closure_max"), f.get("budget_closure_unbooked_max")
        ref = base and base["metrics"]["figures"].get("budget_closure_max")
        ratio = closure / ref if closure is not None and ref else None
        rows.append((scene_of(p), p.get("materials.water.K"), p.get("materials.water.viscosity"),
                     label(s), s, closure, unbooked, ref, ratio, f))
    rows.sort(key=lambda r: (r[0], r[1] or 0, r[2] or 0, r[3]))
    print(f"| scene | K (Pa) | mu (Pa s) | method | status | closure, booked (J/m) | unbooked | "
          f"remedy-free method's | ratio | within {a.factor} | remedies removed | remedies added |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    for scene, k, mu, name, s, closure, unbooked, ref, ratio, f in rows:
        within = "-" if ratio is None else ("yes" if ratio <= a.factor else "**no**")
        print(f"| {scene} | {fmt(k)} | {fmt(mu)} | {name} | {s['status']} | {fmt(closure)} | {fmt(unbooked)} "
              f"| {fmt(ref)} | {fmt(ratio, '.2f')} | {within} | {fmt(f.get('remedy_dissipated_total'))} "
              f"| {fmt(f.get('remedy_injected_total'))} |")
    print("\n### Checkerboards: the cell means (old index) beside the nodal and cell measures\n")
    print("| scene | K (Pa) | mu (Pa s) | method | cell means, late | nodal, late | cell, late "
          "| cell means, peak | nodal, peak | cell, peak |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    for scene, k, mu, name, s, *_rest in rows:
        f = s["metrics"].get("figures", {})
        cols = [f.get(f"checkerboard_{m}_{w}") for w in ("late", "peak") for m in ("means", "nodal", "cell")]
        print(f"| {scene} | {fmt(k)} | {fmt(mu)} | {name} | " + " | ".join(fmt(c) for c in cols) + " |")
    print("\n### Injection events\n")
    print("| case | events with cause injection | of them energy_injection (budget only) | times (s) |")
    print("|---|---|---|---|")
    for s in sorted(cases, key=lambda s: s["case"]):
        inj = [e for e in s["events"] if e.get("cause") == "injection"]
        if not inj:
            continue
        budget = [e for e in inj if e.get("kind") == "energy_injection"]
        times = ", ".join(f"{e['t']:.3f}" for e in inj[:12])
        print(f"| {s['case']} | {len(inj)} | {len(budget)} | {times}{' ...' if len(inj) > 12 else ''} |")


if __name__ == "__main__":
    main()
