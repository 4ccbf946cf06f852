#!/usr/bin/env python3
"""The yardsticks that see compression, the grid scale and energy gained
(docs/physics.md section 7), per method, as markdown tables.

Usage: scripts/yardsticks_energy.py [--sound DIR] [--grid DIR] [--energy DIR...] [--rest DIR] [--nu NU]

--sound DIR: a `kick matrix` folder of studies/acoustic.toml: per method
  and K, the inviscid sound wave's frequency error and excess viscosity
  over NU at mode 1 and at k h = pi/4, and what it keeps after a period.
--grid DIR: a folder of studies/viscous_decay.toml (`--only h1cm` is
  enough): per method, the inviscid Taylor-Green decay rates (1/s) at
  k h = pi/4 and pi/2, at 1.5 and 15 MPa.
--energy DIR...: any yardstick folders: per inviscid case, the motion's
  energy growth over its window and over any 1 s (shares of the wave's
  energy), the energy its booked terms cycled (the smaller of what they
  added and removed, over the wave's), and each term that moved energy.
--rest DIR: the same cases run without their flow (the water at rest,
  `--set scene.body=...` and `--csv`): each method's drift of the water's
  energy at rest, the mean over the last energy period less the first's
  (J/m), beside the energy table's case of the same name.

NU defaults to 5e-4 m^2/s (the 0.5 Pa s water). Reads every
CASE/summary.json. Standard library only.
"""
import argparse
import json
import math
from pathlib import Path


def cases(folder):
    for path in sorted(Path(folder).glob("*/summary.json")):
        s = json.loads(path.read_text())
        yield path.parent.name, s


def inviscid_checks(folder, check):
    """(case name, summary, the check's figures) of the inviscid cases that carry `check`."""
    for name, s in cases(folder):
        c = s["metrics"].get("checks", {}).get(check)
        if c and not (param(s, ".viscosity") or 0.0) > 0.0:
            yield name, s, c


def param(s, suffix):
    for k, v in s.get("params", {}).items():
        if k.endswith(suffix):
            return v
    return None


def method_of(name):
    """The method part of a case name: everything before the first axis."""
    for marker in ("_h1cm", "_h2cm", "_h0.5cm", "_K1.5MPa", "_K15MPa", "_inf", "_mu"):
        if marker in name:
            name = name.split(marker)[0]
    return name


def fmt(v, spec):
    return "-" if v is None or (isinstance(v, float) and not math.isfinite(v)) else format(v, spec)


def mode_of(s):
    bodies = param(s, "scene.body") or []
    flow = (bodies[0] if bodies else {}).get("flow") or {}
    return flow.get("mode")


def sound_table(folder, nu):
    rows = {}
    for name, s, c in inviscid_checks(folder, "sound_wave"):
        k = param(s, ".K")
        key = (method_of(name), k)
        slot = 0 if mode_of(s) == 1 else 1
        rows.setdefault(key, [None, None])[slot] = c
    print("| method | K (MPa) | frequency error, mode 1 | excess nu / nu, mode 1 | excess nu / nu, k h = pi/4 | mode 1 kept after a period |")
    print("|---|---|---|---|---|---|")
    for (method, k), (m1, m5) in sorted(rows.items(), key=lambda r: (str(r[0][1]), r[0][0])):
        fe = m1 and m1.get("frequency_error")
        x1 = m1 and m1.get("excess_viscosity")
        x5 = m5 and m5.get("excess_viscosity")
        kept = m1 and m1.get("kept_after_period")
        print(
            f"| {method} | {fmt(k / 1e6 if isinstance(k, float) else None, 'g')} "
            f"| {fmt(fe * 100 if fe is not None else None, '+.2f')} % "
            f"| {fmt(x1 / nu if x1 is not None else None, '.3g')} "
            f"| {fmt(x5 / nu if x5 is not None else None, '.3g')} | {fmt(kept, '.3f')} |"
        )


def grid_table(folder):
    rows = {}
    for name, s, c in inviscid_checks(folder, "mode_decay"):
        if param(s, "scene.cell") != 0.01:
            continue
        kh = c["k"] * 0.01
        slot = 0 if abs(kh / (math.pi / 4) - 1) < 0.1 else 1 if abs(kh / (math.pi / 2) - 1) < 0.1 else None
        k = param(s, ".K")
        if slot is None or k not in (1.5e6, 1.5e7):
            continue
        col = slot + (2 if k == 1.5e7 else 0)
        rows.setdefault(method_of(name), [None] * 4)[col] = c.get("rate")
    print("| method | rate k h = pi/4, 1.5 MPa | k h = pi/2, 1.5 MPa | k h = pi/4, 15 MPa | k h = pi/2, 15 MPa |")
    print("|---|---|---|---|---|")
    for method, r in sorted(rows.items()):
        print(f"| {method} | " + " | ".join(fmt(x, ".4g") for x in r) + " |")


def rest_drift(folder, period):
    """Per case: the energy at rest's last-period mean less its first's (J/m)."""
    import csv

    drift = {}
    for path in sorted(Path(folder).glob("*/timeseries.csv")):
        rows = list(csv.DictReader(path.open()))
        e = [
            (float(r["t"]), sum(float(r[k]) for k in ("e_kin", "e_affine", "e_grav", "e_int")))
            for r in rows
        ]
        if len(e) < 2:
            continue
        t0, t1 = e[0][0], e[-1][0]
        first = [v for t, v in e if t <= t0 + period]
        last = [v for t, v in e if t >= t1 - period]
        drift[path.parent.name] = sum(last) / len(last) - sum(first) / len(first)
    return drift


def energy_table(folders, rest=None):
    print("| case | status | wave energy (J/m) | growth | window (s) | largest 1 s growth | booked cycled / wave | at rest: drift / wave | terms: added / removed (J/m) |")
    print("|---|---|---|---|---|---|---|---|---|")
    drifts = {}
    for folder in folders:
        for name, s, g in inviscid_checks(folder, "energy_gain"):
            if rest and not drifts:
                drifts.update(rest_drift(rest, g["energy_period_s"]))
            added = sum(t["added"] for t in g["booked"])
            removed = sum(t["removed"] for t in g["booked"])
            e0 = abs(g["wave_energy"]) or float("nan")
            terms = "; ".join(
                f"{t['term']} {t['added']:.3g} / {t['removed']:.3g}"
                for t in g["booked"]
                if t["added"] + t["removed"] > 1e-3 * e0
            )
            window = f"{fmt(g.get('growth_from_s'), '.2f')}-{fmt(g.get('growth_to_s'), '.2f')}"
            growth = g.get("growth")
            largest = g.get("largest_growth_1s")
            print(
                f"| {name} | {s['status']} | {g['wave_energy']:.4g} | {fmt(growth * 100 if growth is not None else None, '+.1f')} % "
                f"| {window} | {fmt(largest * 100 if largest is not None else None, '+.1f')} % "
                f"| {min(added, removed) / e0:.3g} "
                f"| {fmt(drifts[name] / e0 * 100 if name in drifts else None, '+.1f')} % | {terms} |"
            )


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--sound")
    ap.add_argument("--grid")
    ap.add_argument("--energy", nargs="*", default=[])
    ap.add_argument("--rest")
    ap.add_argument("--nu", type=float, default=5e-4)
    a = ap.parse_args()
    if a.sound:
        sound_table(a.sound, a.nu)
        print()
    if a.grid:
        grid_table(a.grid)
        print()
    if a.energy:
        energy_table(a.energy, a.rest)


if __name__ == "__main__":
    main()
