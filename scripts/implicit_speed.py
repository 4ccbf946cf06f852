#!/usr/bin/env python3
"""Wall seconds per simulated second of the breaking dam: the explicit
J-bar method (the modern baseline, B-spline APIC USL with a dynamic CFL
step, plus J-bar) against the pressure-implicit formulation, at the same K
and cell, interleaved in one run (round by round, K by K, the two methods
one after the other), each case over the same simulated window, one
solver thread each. Prints each round's figures and ratio, and the median.

    python3 scripts/implicit_speed.py [--kick target/release/kick]
        [--t-end 1.0] [--rounds 2] [--cell 0.01] [--k 1.5e6 1.5e7]
        [--out reports/implicit_speed]
"""
import argparse
import json
import pathlib
import statistics
import subprocess

STUDY = """name = "implicit_speed"

[scene]
box = [0.8, 0.6]
cell = {cell}
ppc = 2
t_end = {t_end}
gravity = 9.81
on_escape = "delete"
on_inversion = "delete"
lost_mass_limit = 0.1

[[scene.body]]
rect = [0.0, 0.0, 0.2, 0.4]
material = "water"

[materials.water]
rho0 = 1000.0
eos = "power"
K = 1.5e6
gamma = 7.0
viscosity = 0.5

[method]
shape = "bspline2"
transfer = "apic"
scheme = "usl"
cfl = 0.2
dt = "dynamic"

[output]
timeseries_rows = 200
checkpoint_every = 0
vtk_times = []

[matrix]
"materials.water.K" = [{ks}]
"method" = [{{ j_bar = true }}, {{ formulation = "pressure_implicit" }}]
"""


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--kick", default="target/release/kick")
    ap.add_argument("--t-end", type=float, default=1.0)
    ap.add_argument("--rounds", type=int, default=2)
    ap.add_argument("--cell", type=float, default=0.01)
    ap.add_argument("--k", type=float, nargs="+", default=[1.5e6, 1.5e7])
    ap.add_argument("--out", default="reports/implicit_speed")
    a = ap.parse_args()
    out = pathlib.Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    study = out / "implicit_speed.toml"
    study.write_text(STUDY.format(cell=a.cell, t_end=a.t_end, ks=", ".join(repr(k) for k in a.k)))
    names = subprocess.run([a.kick, "list", str(study)], check=True, capture_output=True, text=True)
    cases = [line.split("\t")[0] for line in names.stdout.splitlines() if line.strip()]
    by_k = {}
    for name in cases:
        k = name.split("_")[0]
        by_k.setdefault(k, {})["implicit" if "pressure_implicit" in name else "j_bar"] = name
    rows = {}
    for r in range(a.rounds):
        for k, pair in by_k.items():
            for method in ("j_bar", "implicit"):
                name = pair[method]
                folder = out / f"round{r}"
                subprocess.run([a.kick, "run", str(study), "--case", name, "--out", str(folder),
                                "--threads", "1"], check=True, capture_output=True)
                s = json.loads((folder / name / "summary.json").read_text())
                per_second = s["wall_s"] / s["t_end"]
                rows.setdefault((k, method), []).append((per_second, s["steps"], s["status"]))
                print(f"round {r} {k:>8} {method:>8}: {per_second:8.2f} wall s per simulated s "
                      f"({s['steps']} steps, {s['status']}, t = {s['t_end']:.3f} s)", flush=True)
    print(f"\nwindow 0 .. {a.t_end} s, h = {a.cell} m, one thread each")
    for k in by_k:
        ratios = [j[0] / i[0] for j, i in zip(rows[(k, "j_bar")], rows[(k, "implicit")])]
        print(f"{k}: explicit J-bar / implicit = " + ", ".join(f"{x:.1f}" for x in ratios)
              + f" (median {statistics.median(ratios):.1f})")


if __name__ == "__main__":
    main()
