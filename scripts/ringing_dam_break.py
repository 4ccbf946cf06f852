#!/usr/bin/env python3
"""Ringing-map regime against the dam-break kicks (the bug-report baseline,
power gamma 7, 0 Pa s, fixed dt; docs/findings/ringing.md). Standard
library only.

Usage: python3 scripts/ringing_dam_break.py DIR [--json out.json]
Reads DIR/K{15kPa,150kPa,1.5MPa,15MPa}/K*_power-g7_mu0_fixed_e0/{timeseries.csv,summary.json},
written by (for each K)
  kick run studies/bug_report.toml --case K<K>_power-g7_mu0_fixed_e0 --out DIR/K<K>
      --threads 1 --csv --set scene.t_end=2.0 --set output.timeseries_rows=20000
Prints, per run, U dt/h (largest particle speed) and c dt/h (sqrt(7 K / rho0),
the power law's tangent at rest), the map's rate there, and the growth of
the monitor's ringing_energy before each of the first kicks against quiet
stretches.
"""
import csv
import json
import math
import statistics as st
import sys

BASE = sys.argv[1] if len(sys.argv) > 1 and not sys.argv[1].startswith("--") else "."
CASES = [("15kPa", 1.5e4), ("150kPa", 1.5e5), ("1.5MPa", 1.5e6), ("15MPa", 1.5e7)]
H = 0.01
RHO0 = 1000.0
GAMMA = 7.0
M = 1000.0 * 0.2 * 0.4  # kg/m
KICK_CAUSES = ("injection", "inversion")

# Measured map (studies/ringing.toml, linear FLIP USF): rate per 1000 steps.
U_GRID = [0.001, 0.003, 0.01, 0.03, 0.1, 0.3]
MAP = {
    0.2: [0.06, -0.02, 0.07, 4.59, 5.19, 3.28],
    0.4: [-0.07, 0.00, 0.33, 12.0, 17.3, 22.7],
}


def map_rate(u, row):
    """Map rate per 1000 steps at U dt/h = u, row c dt/h = row, linear in
    log10(u) between grid points (clamped at the ends)."""
    vals = MAP[row]
    if u <= U_GRID[0]:
        return vals[0]
    if u >= U_GRID[-1]:
        return vals[-1]
    for i in range(len(U_GRID) - 1):
        a, b = U_GRID[i], U_GRID[i + 1]
        if a <= u <= b:
            w = (math.log10(u) - math.log10(a)) / (math.log10(b) - math.log10(a))
            return vals[i] + w * (vals[i + 1] - vals[i])


def fnum(s):
    try:
        return float(s)
    except ValueError:
        return float("nan")


def load(tag):
    d = f"{BASE}/K{tag}/K{tag}_power-g7_mu0_fixed_e0"
    rows = {}
    with open(f"{d}/timeseries.csv") as f:
        for r in csv.DictReader(f):
            step = int(r["step"])
            rec = {k: fnum(r[k]) for k in
                   ("t", "dt", "e_kin", "ringing_energy", "max_speed", "courant")}
            rec["step"] = step
            # keep the regular row when an event row shares its step
            if step not in rows or r["event_row"] == "false":
                rows[step] = rec
    summ = json.load(open(f"{d}/summary.json"))
    return [rows[s] for s in sorted(rows)], summ


def linfit(xs, ys):
    n = len(xs)
    mx, my = sum(xs) / n, sum(ys) / n
    sxx = sum((x - mx) ** 2 for x in xs)
    sxy = sum((x - mx) * (y - my) for x, y in zip(xs, ys))
    syy = sum((y - my) ** 2 for y in ys)
    b = sxy / sxx
    r2 = (sxy * sxy / (sxx * syy)) if syy > 0 else float("nan")
    return b, r2


def growth(rows, s0, s1, ratio=False):
    """Fit ln(R) (or ln(R/e_kin)) against step over rows with s0 <= step < s1.
    Returns (rate per 1000 steps, r2, n used, n rows, n R<=0)."""
    w = [r for r in rows if s0 <= r["step"] < s1]
    pos = [r for r in w if r["ringing_energy"] > 0 and r["e_kin"] > 0]
    if len(pos) < 4:
        return None
    xs = [r["step"] for r in pos]
    ys = [math.log(r["ringing_energy"] / (r["e_kin"] if ratio else 1.0)) for r in pos]
    b, r2 = linfit(xs, ys)
    return 1000.0 * b, r2, len(pos), len(w), len(w) - len(pos)


def pct(v, q):
    v = sorted(v)
    return v[min(len(v) - 1, int(q * (len(v) - 1) + 0.5))]


def analyse(tag, K):
    rows, summ = load(tag)
    ev = sorted(summ["events"], key=lambda e: e["first_step"])
    dt = st.median(r["dt"] for r in rows)
    c_brief = math.sqrt(K / RHO0)
    c_eos = math.sqrt(GAMMA * K / RHO0)  # power law p = K (J^-g - 1): K_t(1) = g K
    out = {
        "case": tag, "status": summ["status"], "steps": summ["steps"],
        "t_stop": rows[-1]["t"], "dt": dt, "n_rows": len(rows),
        "c_dt_h_brief": c_brief * dt / H, "c_dt_h_eos": c_eos * dt / H,
        "n_events": len(ev),
    }
    first_blow = min((e["first_step"] for e in ev if e["outcome"] == "blow_out"),
                     default=rows[-1]["step"] + 1)
    out["t_first_blowout_event"] = next(r["t"] for r in rows if r["step"] >= first_blow) \
        if any(r["step"] >= first_blow for r in rows) else None
    for r in rows:
        r["u_max"] = r["max_speed"] * dt / H
        r["u_rms"] = math.sqrt(max(0.0, 2 * r["e_kin"] / M)) * dt / H
    body = [r for r in rows if r["step"] > 0]
    pre = [r for r in body if r["step"] < first_blow]
    out["u_max_range_run"] = (min(r["u_max"] for r in body), st.median(r["u_max"] for r in body),
                              max(r["u_max"] for r in body))
    out["u_max_range_pre_blowout"] = (min(r["u_max"] for r in pre), st.median(r["u_max"] for r in pre),
                                      max(r["u_max"] for r in pre))
    out["u_rms_range_pre_blowout"] = (min(r["u_rms"] for r in pre), st.median(r["u_rms"] for r in pre),
                                      max(r["u_rms"] for r in pre))
    out["courant_range_pre_blowout"] = (min(r["courant"] for r in pre), max(r["courant"] for r in pre))

    # quiet rows: no event open, t > 0.01 s, before the first blow-out event
    def open_at(s):
        return any(e["first_step"] <= s <= e["last_step"] for e in ev)

    quiet = [r for r in pre if r["t"] > 0.01 and not open_at(r["step"])]
    out["quiet_rows"] = len(quiet)
    if quiet:
        ratio = [r["ringing_energy"] / r["e_kin"] for r in quiet if r["e_kin"] > 0]
        out["quiet_R_median"] = st.median(r["ringing_energy"] for r in quiet)
        out["quiet_ratio_median"] = st.median(ratio)
        out["quiet_ratio_p10_p90"] = (pct(ratio, 0.1), pct(ratio, 0.9))
        out["quiet_frac_negative"] = sum(r["ringing_energy"] < 0 for r in quiet) / len(quiet)
        # control: growth fits on 0.05 s quiet windows (no event open in them)
        nwin = max(1, int(round(0.05 / dt)))
        ctrl = []
        ctrl_r = []
        s = quiet[0]["step"]
        while s + nwin < first_blow:
            if not any(e["first_step"] < s + nwin and e["last_step"] >= s for e in ev):
                g = growth(rows, s, s + nwin)
                if g:
                    ctrl.append(g[0])
                gr = growth(rows, s, s + nwin, ratio=True)
                if gr:
                    ctrl_r.append(gr[0])
            s += nwin
        if ctrl:
            out["control_rate_per1000"] = (len(ctrl), min(ctrl), st.median(ctrl), max(ctrl))
            out["control_ratio_rate_per1000"] = (len(ctrl_r), min(ctrl_r), st.median(ctrl_r), max(ctrl_r))
    # R / e_kin by 0.1 s bins (all rows with e_kin > 0, before the first blow-out event)
    bins = {}
    for r in pre:
        if r["e_kin"] > 0:
            bins.setdefault(int(r["t"] / 0.1), []).append(r["ringing_energy"] / r["e_kin"])
    out["ratio_by_0.1s"] = {f"{b/10:.1f}": st.median(v) for b, v in sorted(bins.items())}

    kicks = [e for e in ev if e["cause"] in KICK_CAUSES][:5]
    kk = []
    n02 = max(1, int(round(0.02 / dt)))
    n05 = max(1, int(round(0.05 / dt)))
    for e in kicks:
        s = e["first_step"]
        before = [r for r in rows if r["step"] < s]
        last = before[-1]
        win = [r for r in before if r["step"] >= s - n02]
        rat = [r["ringing_energy"] / r["e_kin"] for r in win if r["e_kin"] > 0]
        other_open = [o["id"] for o in ev if o is not e and o["first_step"] < s
                      and o["last_step"] >= s - n05]
        k = {
            "id": e["id"], "kind": e["kind"], "cause": e["cause"], "outcome": e["outcome"],
            "step": s, "t": e["t"], "region": e["region"],
            "u_max_before": last["u_max"],
            "u_max_max_0.02s": max(r["u_max"] for r in win),
            "u_rms_before": last["u_rms"],
            "speed_before_evidence": e["evidence"].get("speed_before"),
            "u_local": (e["evidence"].get("speed_before") or 0.0) * dt / H,
            "map_rate_c0.2": map_rate(last["u_max"], 0.2),
            "R_before": last["ringing_energy"],
            "ratio_0.02s_median": st.median(rat) if rat else None,
            "ratio_0.02s_max": max(rat) if rat else None,
            "frac_neg_0.02s": sum(r["ringing_energy"] < 0 for r in win) / max(1, len(win)),
            "fit_0.02s": growth(rows, s - n02, s),
            "fit_0.05s": growth(rows, s - n05, s),
            "fit_ratio_0.05s": growth(rows, s - n05, s, ratio=True),
            "events_open_in_0.05s": other_open,
        }
        kk.append(k)
    out["kicks"] = kk
    # secondary: first 5 events of kind "kick" whatever their cause
    out["first_kind_kick"] = [
        {"id": e["id"], "cause": e["cause"], "t": e["t"],
         "u_max_before": [r for r in rows if r["step"] < e["first_step"]][-1]["u_max"],
         "fit_0.05s": growth(rows, e["first_step"] - n05, e["first_step"])}
        for e in ev if e["kind"] == "kick"][:5]
    return out


def fmt(x, p=3):
    if x is None:
        return "-"
    if isinstance(x, float):
        return f"{x:.{p}g}"
    if isinstance(x, tuple):
        return "(" + ", ".join(fmt(v, p) for v in x) + ")"
    return str(x)


def main():
    res = [analyse(tag, K) for tag, K in CASES]
    for o in res:
        print(f"== K {o['case']}: {o['status']} at t={o['t_stop']:.4f} s, {o['steps']} steps, "
              f"{o['n_rows']} rows, {o['n_events']} events; first blow_out-outcome event at t={fmt(o['t_first_blowout_event'], 4)}")
        print(f"   dt={o['dt']:.4g}  c dt/h: brief sqrt(K/rho0) -> {o['c_dt_h_brief']:.4f}; "
              f"EOS sqrt(7K/rho0) -> {o['c_dt_h_eos']:.4f}")
        print(f"   U dt/h (max_speed) min/med/max whole run {fmt(o['u_max_range_run'])}; "
              f"before first blow-out event {fmt(o['u_max_range_pre_blowout'])}")
        print(f"   U dt/h (RMS) pre-blowout {fmt(o['u_rms_range_pre_blowout'])}; courant {fmt(o['courant_range_pre_blowout'])}")
        print(f"   quiet rows {o['quiet_rows']}: R median {fmt(o.get('quiet_R_median'))} J/m, "
              f"R/e_kin median {fmt(o.get('quiet_ratio_median'))} p10-p90 {fmt(o.get('quiet_ratio_p10_p90'))}, "
              f"frac R<0 {fmt(o.get('quiet_frac_negative'))}")
        print(f"   control fits (0.05 s quiet windows, ln R per 1000 steps) n/min/med/max {fmt(o.get('control_rate_per1000'))}"
              f"; ln(R/Ek) {fmt(o.get('control_ratio_rate_per1000'))}; per second = per-1000 / (1000 dt), 1000 dt = {1000*o['dt']:.4g} s")
        print(f"   R/e_kin median by 0.1 s bin: " + " ".join(f"{k}:{v:.3g}" for k, v in o['ratio_by_0.1s'].items()))
        for k in o["kicks"]:
            print(f"   kick id {k['id']} {k['kind']}/{k['cause']}/{k['outcome']} step {k['step']} t={k['t']:.4f} "
                  f"region {k['region']['x_min']:.2f},{k['region']['y_min']:.2f}")
            print(f"      local U dt/h (event speed_before) {k['u_local']:.4f}; U dt/h before {k['u_max_before']:.4f} (max in 0.02 s {k['u_max_max_0.02s']:.4f}; rms {k['u_rms_before']:.4f}); "
                  f"map@c0.2 {k['map_rate_c0.2']:.2f}/1000")
            print(f"      R before {fmt(k['R_before'])}; R/e_kin 0.02 s median {fmt(k['ratio_0.02s_median'])} max {fmt(k['ratio_0.02s_max'])} "
                  f"fracneg {fmt(k['frac_neg_0.02s'])}")
            print(f"      fit lnR 0.02 s {fmt(k['fit_0.02s'])}; 0.05 s {fmt(k['fit_0.05s'])}; ln(R/Ek) 0.05 s {fmt(k['fit_ratio_0.05s'])}; "
                  f"other events open in 0.05 s: {k['events_open_in_0.05s'][:8]}{'...' if len(k['events_open_in_0.05s']) > 8 else ''}")
        print("   first 5 kind=kick events:")
        for k in o["first_kind_kick"]:
            print(f"      id {k['id']} {k['cause']} t={k['t']:.4f} U dt/h {k['u_max_before']:.4f} fit0.05 {fmt(k['fit_0.05s'])}")
    if "--json" in sys.argv:
        json.dump(res, open(sys.argv[sys.argv.index("--json") + 1], "w"), indent=1, default=str)


if __name__ == "__main__":
    main()
