#!/usr/bin/env python3
"""The viscous-decay yardstick of a matrix folder (docs/physics.md section 7).

Usage: scripts/viscous_decay.py MATRIX_DIR [NU]

Reads every CASE/summary.json of a `kick matrix studies/viscous_decay.toml`
folder and prints, per method, cell size and K (markdown):
- the fitted decay rates of each mode, inviscid and viscous (1/s);
- nu_phys per mode = (viscous rate - inviscid rate) / (2 k^2), against NU
  (default 5e-4 m^2/s, the 0.5 Pa s water);
- nu_num and beta from the inviscid rates of two modes:
  rate / (2 k^2) = nu_num + beta k^2 (two modes: solved exactly);
- the observed order in h of nu_num and beta per method and K (least-squares
  slope of ln |value| against ln h), where three cell sizes are there.
Standard library only.
"""
import json
import math
import sys
from collections import defaultdict
from pathlib import Path


def method_label(params):
    keys = ["method.shape", "method.transfer", "method.scheme", "method.dt"]
    base = " ".join(str(params.get(k, "?")) for k in keys)
    extra = sorted(k for k in params if k.startswith("method.") and k not in keys
                   and k.count(".") > 1 and params[k] not in (None, False))
    return base + ("" if not extra else " +" + ",".join(e.split(".")[1] for e in extra))


def mode_of(params):
    body = params.get("scene.body")
    if isinstance(body, list) and body and isinstance(body[0], dict):
        return body[0].get("flow", {}).get("mode")
    return None


def slope(points):
    pts = [(math.log(x), math.log(abs(y))) for x, y in points if x > 0 and y and y != 0]
    if len(pts) < 2:
        return None
    mx = sum(p[0] for p in pts) / len(pts)
    my = sum(p[1] for p in pts) / len(pts)
    sxx = sum((p[0] - mx) ** 2 for p in pts)
    return None if sxx == 0 else sum((p[0] - mx) * (p[1] - my) for p in pts) / sxx


def main(folder, nu):
    runs = defaultdict(dict)  # (method, h, K) -> {(mode, mu): (rate, k, status)}
    for s_path in sorted(Path(folder).glob("*/summary.json")):
        s = json.loads(s_path.read_text())
        p = s["params"]
        check = s["metrics"].get("checks", {}).get("mode_decay")
        if check is not None and check.get("later_max_ratio", 0.0) > 0.5:
            check = dict(check, rate=None)  # the mode swings back: no decay rate
        if check is None:
            continue
        key = (method_label(p), p.get("scene.cell"), p.get("materials.water.K"))
        mu = p.get("materials.water.viscosity", 0.0)
        runs[key][(mode_of(p), mu)] = (check.get("rate"), check["k"], s["status"], s["wall_s"])
    print(f"| method | h (m) | K (Pa) | mode | rate inviscid (1/s) | rate viscous (1/s) "
          f"| nu_phys (m²/s) | nu_phys / nu | wall (s) |")
    print("|---|---|---|---|---|---|---|---|---|")
    fits = {}
    for key in sorted(runs, key=lambda k: (k[0], -k[1], k[2])):
        r = runs[key]
        modes = sorted({m for m, _ in r})
        inviscid = {}
        for m in modes:
            a = r.get((m, 0.0))
            b = next((v for (mm, mu), v in r.items() if mm == m and mu > 0), None)
            k = (a or b)[1]
            phys = (b[0] - a[0]) / (2 * k * k) if a and b and a[0] is not None and b[0] is not None else None
            if a and a[0] is not None:
                inviscid[m] = (a[0], k)
            fmt = lambda x: "-" if x is None else f"{x:.4g}"
            wall = sum(v[3] for (mm, _), v in r.items() if mm == m)
            print(f"| {key[0]} | {key[1]} | {key[2]:.3g} | {m} | {fmt(a and a[0])} | {fmt(b and b[0])} "
                  f"| {fmt(phys)} | {fmt(phys / nu if phys is not None else None)} | {wall:.0f} |")
        if len(inviscid) >= 2:
            (r1, k1), (r2, k2) = [inviscid[m] for m in sorted(inviscid)[:2]]
            y1, y2 = r1 / (2 * k1 * k1), r2 / (2 * k2 * k2)
            beta = (y2 - y1) / (k2 * k2 - k1 * k1)
            fits[key] = (y1 - beta * k1 * k1, beta)
    print()
    print("| method | h (m) | K (Pa) | nu_num (m²/s) | nu_num / nu | beta (m⁴/s) |")
    print("|---|---|---|---|---|---|")
    for key in sorted(fits, key=lambda k: (k[0], -k[1], k[2])):
        n, b = fits[key]
        print(f"| {key[0]} | {key[1]} | {key[2]:.3g} | {n:.4g} | {n / nu:.3g} | {b:.4g} |")
    print()
    by = defaultdict(list)
    for (m, h, K), (n, b) in fits.items():
        by[(m, K)].append((h, n, b))
    for (m, K), rows in sorted(by.items()):
        if len(rows) >= 3:
            on = slope([(h, n) for h, n, _ in rows])
            ob = slope([(h, b) for h, _, b in rows])
            print(f"observed order in h, {m}, K = {K:.3g}: nu_num {on and round(on, 2)}, "
                  f"beta {ob and round(ob, 2)}")


if __name__ == "__main__":
    if len(sys.argv) not in (2, 3):
        sys.exit(__doc__)
    main(sys.argv[1], float(sys.argv[2]) if len(sys.argv) == 3 else 5e-4)
