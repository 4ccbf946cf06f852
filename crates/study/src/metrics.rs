//! Case metrics for summary.json, computed from the timeseries and events
//! (PHYSICS.md section 4: "late" = the last simulated second).

use crate::timeseries::Timeseries;
use monitor::{Event, EventKind};
use serde_json::{json, Value};

/// Martin & Moyce (1952), a = 2.25 in, n^2 = 2: (T, Z) pairs (source in the file).
const MARTIN_MOYCE: &str = include_str!("../../../data/martin_moyce_1952_a2.25in.csv");

pub fn martin_moyce() -> Vec<(f64, f64)> {
    MARTIN_MOYCE
        .lines()
        .filter(|l| !l.starts_with('#') && !l.starts_with('T'))
        .filter_map(|l| {
            let (t, z) = l.split_once(',')?;
            Some((t.trim().parse().ok()?, z.trim().parse().ok()?))
        })
        .collect()
}

fn mean(v: impl Iterator<Item = f64>) -> Option<f64> {
    let (mut s, mut n) = (0.0, 0usize);
    for x in v.filter(|x| x.is_finite()) {
        s += x;
        n += 1;
    }
    (n > 0).then(|| s / n as f64)
}

/// RMS of Z_sim - Z_data over the data points the run covers, while the
/// measured front is short of the far wall (Z < z_wall).
pub fn front_rms_error(ts: &Timeseries, z_wall: f64) -> Option<f64> {
    let (tt, zz) = (ts.column("front_t"), ts.column("front_z"));
    let pts: Vec<(f64, f64)> = tt
        .iter()
        .zip(zz)
        .filter(|(t, z)| t.is_finite() && z.is_finite())
        .map(|(t, z)| (*t, *z))
        .collect();
    let mut sum = 0.0;
    let mut n = 0;
    for (t, z) in martin_moyce() {
        if z >= z_wall {
            continue;
        }
        let Some(k) = pts.windows(2).position(|w| w[0].0 <= t && t <= w[1].0) else {
            continue;
        };
        let (a, b) = (pts[k], pts[k + 1]);
        let s = if b.0 > a.0 {
            (t - a.0) / (b.0 - a.0)
        } else {
            0.0
        };
        let z_sim = a.1 + s * (b.1 - a.1);
        sum += (z_sim - z) * (z_sim - z);
        n += 1;
    }
    (n > 0).then(|| (sum / n as f64).sqrt())
}

/// The summary.json metrics block.
pub fn summarise(ts: &Timeseries, events: &[Event], z_wall: Option<f64>) -> Value {
    let t = ts.column("t");
    let t_last = t.last().copied().unwrap_or(0.0);
    let late = |name: &str| {
        let col = ts.column(name);
        mean(
            t.iter()
                .zip(col)
                .filter(|(ti, _)| **ti >= t_last - 1.0)
                .map(|(_, v)| *v),
        )
    };
    let peak = |name: &str| {
        ts.column(name)
            .iter()
            .copied()
            .filter(|v| v.is_finite())
            .fold(None, |m: Option<f64>, v| Some(m.map_or(v, |m| m.max(v))))
    };
    let first_kick = events
        .iter()
        .filter(|e| e.kind == EventKind::Kick)
        .map(|e| e.t)
        .fold(None, |m: Option<f64>, t| Some(m.map_or(t, |m| m.min(t))));
    let count = |k: EventKind| events.iter().filter(|e| e.kind == k).count();
    json!({
        "hydro_rel_rms_late": late("hydro_rel_rms"),
        "hydro_max_late": late("hydro_max"),
        "checkerboard_late": late("checkerboard"),
        "checkerboard_peak": peak("checkerboard"),
        "energy_injected_max": peak("energy_injected"),
        "t_first_kick": first_kick,
        "n_kicks": count(EventKind::Kick),
        "n_energy_injections": count(EventKind::EnergyInjection),
        "courant_max": peak("courant"),
        "max_accel_g": peak("max_accel_g"),
        "front_rms_error": z_wall.and_then(|z| front_rms_error(ts, z)),
    })
}
