//! Case metrics for summary.json, computed from the timeseries and events
//! (docs/physics.md section 4: "late" = the last simulated second of a run
//! that reached t_end, without event rows).

use crate::output::summary::{CauseCount, Metrics};
use crate::output::timeseries::{Rule, Timeseries};
use monitor::{Event, EventKind};
use std::collections::BTreeMap;

/// Martin & Moyce (1952), a = 2.25 in, n^2 = 2: (T, Z) pairs (source in the file).
const MARTIN_MOYCE: &str = include_str!("../../../../data/martin_moyce_1952_a2.25in.csv");

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

/// The simulated front as (T, Z) rows of the timeseries (finite ones).
pub fn front_track(ts: &Timeseries) -> Vec<(f64, f64)> {
    ts.column("front_t")
        .iter()
        .zip(ts.column("front_z"))
        .filter(|(t, z)| t.is_finite() && z.is_finite())
        .map(|(t, z)| (*t, *z))
        .collect()
}

/// RMS of Z_sim - Z_data over the data points the run covers, while the
/// measured front is short of the far wall (Z < z_wall).
pub fn front_rms_error(ts: &Timeseries, z_wall: f64) -> Option<f64> {
    let sim = front_track(ts);
    rms(martin_moyce()
        .into_iter()
        .filter(|p| p.1 < z_wall)
        .filter_map(|(t, z)| interpolate(&sim, t).map(|zs| zs - z)))
}

/// Early regime (inertia-driven collapse) ends here, in T = t sqrt(2 g / a).
pub const T_EARLY_END: f64 = 3.5;
/// The experiment's gate-opening lag is looked for within this many T units.
pub const MAX_TIME_SHIFT: f64 = 0.3;

/// The surge front against Martin & Moyce in two regimes (docs/physics.md
/// section 4): RMS of Z_sim - Z_data at the data's T values while the data
/// front is short of the far wall; early (T <= 3.5) raw, and after the best
/// time shift s in [-0.3, 0.3] (Z_sim(T - s) against Z_data(T): s > 0 when
/// the experiment lags the model); late (T > 3.5) the RMS and the simulated
/// front speed dZ/dT (least squares over the late data's T range), which
/// Ritter's endless-reservoir solution puts at 2 and the data at about 1.7.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct FrontErrors {
    pub early_rms: Option<f64>,
    pub early_shifted_rms: Option<f64>,
    pub time_shift: Option<f64>,
    pub late_speed: Option<f64>,
    pub late_rms: Option<f64>,
}

/// Z of a trajectory sorted by T, linearly interpolated (None outside it).
fn interpolate(sim: &[(f64, f64)], t: f64) -> Option<f64> {
    let k = sim.windows(2).position(|w| w[0].0 <= t && t <= w[1].0)?;
    let (a, b) = (sim[k], sim[k + 1]);
    let s = if b.0 > a.0 {
        (t - a.0) / (b.0 - a.0)
    } else {
        0.0
    };
    Some(a.1 + s * (b.1 - a.1))
}

fn rms(errors: impl Iterator<Item = f64>) -> Option<f64> {
    let (mut sum, mut n) = (0.0, 0usize);
    for e in errors {
        sum += e * e;
        n += 1;
    }
    (n > 0).then(|| (sum / n as f64).sqrt())
}

/// Least-squares slope of y against x (None below two distinct x).
pub fn slope(points: impl Iterator<Item = (f64, f64)>) -> Option<f64> {
    let pts: Vec<(f64, f64)> = points.collect();
    line_fit(&pts).map(|(slope, _)| slope)
}

/// Least-squares line of y against x: (slope, intercept); None below two distinct x.
pub fn line_fit(pts: &[(f64, f64)]) -> Option<(f64, f64)> {
    let n = pts.len() as f64;
    if pts.len() < 2 {
        return None;
    }
    let (mx, my) = (
        pts.iter().map(|p| p.0).sum::<f64>() / n,
        pts.iter().map(|p| p.1).sum::<f64>() / n,
    );
    let sxx: f64 = pts.iter().map(|p| (p.0 - mx) * (p.0 - mx)).sum();
    let sxy: f64 = pts.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    (sxx > 0.0).then(|| (sxy / sxx, my - sxy / sxx * mx))
}

/// `sim`: the simulated (T, Z), sorted by T; `data`: Martin & Moyce's.
pub fn front_errors(sim: &[(f64, f64)], data: &[(f64, f64)], z_wall: f64) -> FrontErrors {
    let before_wall = |&&(_, z): &&(f64, f64)| z < z_wall;
    let early: Vec<(f64, f64)> = data
        .iter()
        .filter(before_wall)
        .filter(|p| p.0 <= T_EARLY_END)
        .copied()
        .collect();
    let late: Vec<(f64, f64)> = data
        .iter()
        .filter(before_wall)
        .filter(|p| p.0 > T_EARLY_END)
        .copied()
        .collect();
    let error_at = |shift: f64| {
        rms(early
            .iter()
            .filter_map(|&(t, z)| interpolate(sim, t - shift).map(|zs| zs - z)))
    };
    // Grid search at 0.001 in T; only shifts at which every early point is covered.
    let covered = |shift: f64| {
        early
            .iter()
            .all(|&(t, _)| interpolate(sim, t - shift).is_some())
    };
    let best = (-300..=300)
        .map(|k| k as f64 * MAX_TIME_SHIFT / 300.0)
        .filter(|&s| covered(s))
        .filter_map(|s| error_at(s).map(|e| (s, e)))
        .min_by(|a, b| a.1.total_cmp(&b.1));
    // Over the late data's T range only: the same window as the data.
    let t_last = late.iter().map(|p| p.0).fold(f64::NEG_INFINITY, f64::max);
    let sim_late = sim
        .iter()
        .filter(|p| p.0 > T_EARLY_END && p.0 <= t_last && p.1 < z_wall)
        .copied();
    FrontErrors {
        early_rms: error_at(0.0),
        early_shifted_rms: best.map(|b| b.1),
        time_shift: best.map(|b| b.0),
        late_speed: slope(sim_late),
        late_rms: rms(late
            .iter()
            .filter_map(|&(t, z)| interpolate(sim, t).map(|zs| zs - z))),
    }
}

/// Observed order of convergence: the least-squares slope of ln(error)
/// against ln(h) (None with fewer than two positive errors).
pub fn observed_order(h: &[f64], error: &[f64]) -> Option<f64> {
    slope(
        h.iter()
            .zip(error)
            .filter(|(h, e)| **h > 0.0 && **e > 0.0 && e.is_finite())
            .map(|(h, e)| (h.ln(), e.ln())),
    )
}

/// Mean of a column's `values` over the rows of the simulated second
/// before `end` (up to and including it when `inclusive`), without event
/// rows and the t = 0 row.
fn second_before_mean(ts: &Timeseries, values: &[f64], end: f64, inclusive: bool) -> Option<f64> {
    mean(
        ts.column("t")
            .iter()
            .zip(values)
            .zip(&ts.event_row)
            .filter(|((ti, _), event)| {
                let before = if inclusive { **ti <= end } else { **ti < end };
                **ti >= end - 1.0 && **ti > 0.0 && before && !**event
            })
            .map(|((_, v), _)| *v),
    )
}

/// When a failed run's state was last whole: the first row that counts a
/// lost particle, else the last row (the failure itself).
fn failure_onset(ts: &Timeseries) -> f64 {
    let t = ts.column("t");
    ts.column("particles_lost")
        .iter()
        .position(|&n| n > 0.0)
        .map_or(t.last().copied().unwrap_or(0.0), |row| t[row])
}

/// The summary.json metrics block from one phase's timeseries and events:
/// each declared column's figures, and the event counts (losses and
/// checks are filled by the run loop and the probes). "Late" figures (the
/// last simulated second) only for a run that reached t_end. A run that
/// stopped gets its `PreFailure` figures instead, over the second before
/// its state stopped being whole: before the first particle was deleted,
/// or before the failing row when none was, so that neither the collapse
/// nor the blow-up row is averaged in.
pub fn summarise(ts: &Timeseries, events: &[Event], completed: bool) -> Metrics {
    Metrics {
        figures: column_figures(ts, completed),
        t_first_kick: first_time(events, |e| e.is_kick()),
        n_kicks: events.iter().filter(|e| e.is_kick()).count(),
        n_anomalies: events.iter().filter(|e| e.is_anomaly()).count(),
        t_first_anomaly: first_time(events, |e| e.is_anomaly()),
        causes: monitor::Cause::ALL
            .iter()
            .map(|&c| {
                let of = |e: &Event| e.cause == c;
                let count = events.iter().filter(|e| of(e)).count();
                let t_first = first_time(events, of);
                (c, CauseCount { count, t_first })
            })
            .collect(),
        n_energy_injections: events
            .iter()
            .filter(|e| e.kind == EventKind::EnergyInjection)
            .count(),
        ..Metrics::default()
    }
}

/// The earliest time of the events that `keep` selects.
fn first_time(events: &[Event], keep: impl Fn(&Event) -> bool) -> Option<f64> {
    events
        .iter()
        .filter(|e| keep(e))
        .map(|e| e.t)
        .fold(None, |m: Option<f64>, t| Some(m.map_or(t, |m| m.min(t))))
}

/// Every figure the columns declare, by name (null where undefined).
fn column_figures(ts: &Timeseries, completed: bool) -> BTreeMap<String, Option<f64>> {
    let t_last = ts.column("t").last().copied().unwrap_or(0.0);
    let onset = failure_onset(ts);
    let mut figures = BTreeMap::new();
    for (c, values) in ts.defs.iter().zip(&ts.columns) {
        for figure in c.figures {
            let value = match figure.rule {
                Rule::Peak => peak(values),
                Rule::Late => completed
                    .then(|| second_before_mean(ts, values, t_last, true))
                    .flatten(),
                Rule::PreFailure => (!completed)
                    .then(|| second_before_mean(ts, values, onset, false))
                    .flatten(),
            };
            figures.insert(figure.name.to_string(), value);
        }
    }
    figures
}

/// The largest finite value.
fn peak(values: &[f64]) -> Option<f64> {
    values
        .iter()
        .copied()
        .filter(|v| v.is_finite())
        .fold(None, |m: Option<f64>, v| Some(m.map_or(v, |m| m.max(v))))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::output::timeseries::Peaks;

    /// A front that accelerates to T = 3.5, then runs at dZ/dT = 1.7.
    fn reference(t: f64) -> f64 {
        if t <= 3.5 {
            1.0 + 0.3 * t * t
        } else {
            1.0 + 0.3 * 3.5 * 3.5 + 1.7 * (t - 3.5)
        }
    }

    /// A model that runs 0.1 T ahead of the data: the shift is found and
    /// removes the early error; the late speed is the built 1.7. A model
    /// 0.02 above the data has early RMS 0.02.
    #[test]
    fn front_errors_find_a_known_shift_offset_and_speed() {
        let data: Vec<(f64, f64)> = (1..=18)
            .map(|k| 0.5 * k as f64)
            .map(|t| (t, reference(t)))
            .collect();
        let track = |f: &dyn Fn(f64) -> f64| -> Vec<(f64, f64)> {
            (0..=1000)
                .map(|k| 0.01 * k as f64)
                .map(|t| (t, f(t)))
                .collect()
        };
        let ahead = front_errors(&track(&|t| reference(t + 0.1)), &data, 100.0);
        assert!(
            (ahead.time_shift.unwrap() - 0.1).abs() < 1.5e-3,
            "{ahead:?}"
        );
        assert!(ahead.early_shifted_rms.unwrap() < 1e-3, "{ahead:?}");
        assert!(ahead.early_rms.unwrap() > 0.1, "{ahead:?}");
        assert!((ahead.late_speed.unwrap() - 1.7).abs() < 1e-9, "{ahead:?}");
        assert!((ahead.late_rms.unwrap() - 0.17).abs() < 1e-9, "{ahead:?}");
        let above = front_errors(&track(&|t| reference(t) + 0.02), &data, 100.0);
        assert!((above.early_rms.unwrap() - 0.02).abs() < 1e-4, "{above:?}");
        assert!(above.early_shifted_rms.unwrap() <= above.early_rms.unwrap());
        // Data past the wall are left out: with the wall at Z = 3 no late point remains.
        let walled = front_errors(&track(&reference), &data, 3.0);
        assert_eq!(walled.late_rms, None);
    }

    #[test]
    fn observed_order_of_synthetic_errors() {
        let h = [0.02, 0.01, 0.005];
        let first: Vec<f64> = h.iter().map(|h| 3.0 * h).collect();
        let second: Vec<f64> = h.iter().map(|h| 0.5 * h * h).collect();
        assert!((observed_order(&h, &first).unwrap() - 1.0).abs() < 1e-12);
        assert!((observed_order(&h, &second).unwrap() - 2.0).abs() < 1e-12);
        assert_eq!(observed_order(&h[..1], &first[..1]), None);
    }
    use monitor::{FieldMetrics, StepReport};

    /// A timeseries whose only content is the front trajectory (T, Z).
    fn front(points: &[(f64, f64)]) -> Timeseries {
        let mut ts = Timeseries::new();
        for (k, &(t, z)) in points.iter().enumerate() {
            let fields = FieldMetrics {
                front_t: t,
                front_z: Some(z),
                ..Default::default()
            };
            let report = StepReport {
                step: k as u64,
                ..Default::default()
            };
            ts.push(&report, &Peaks::default(), &fields, false);
        }
        ts
    }

    #[test]
    fn front_error_is_the_rms_over_the_data_short_of_the_wall() {
        let data = martin_moyce();
        assert_eq!(data.len(), 15);
        // Z_sim = Z_data + e_k at each data time (exact: the interpolation is linear
        // between the rows). Below the wall at Z = 4 are the first four data points.
        let offsets = [0.1, 0.2, 0.3, 0.4];
        let mut pts = vec![(0.0, 1.0)];
        for (k, &(t, z)) in data.iter().enumerate() {
            pts.push((t, z + offsets.get(k).copied().unwrap_or(5.0)));
        }
        let want = ((0.01 + 0.04 + 0.09 + 0.16) / 4.0f64).sqrt();
        let got = front_rms_error(&front(&pts), 4.0).unwrap();
        assert!((got - want).abs() < 1e-12, "{got} vs {want}");
        // A constant offset gives exactly that offset.
        let shifted: Vec<(f64, f64)> = data.iter().map(|&(t, z)| (t, z - 0.25)).collect();
        let got = front_rms_error(&front(&shifted), 100.0).unwrap();
        assert!((got - 0.25).abs() < 1e-12, "{got}");
        // Data times outside the run are skipped; no overlap gives no figure.
        let early = front(&[(0.0, 1.0), (1.0, 1.5)]);
        let got = front_rms_error(&early, 100.0).unwrap();
        let z_at = 1.0 + 0.5 * 0.832;
        assert!((got - (z_at - 1.217f64).abs()).abs() < 1e-12, "{got}");
        assert_eq!(
            front_rms_error(&front(&[(0.0, 1.0), (0.5, 1.1)]), 100.0),
            None
        );
    }

    #[test]
    fn late_figures_leave_out_event_rows_and_exist_only_for_completed_runs() {
        // Regular rows every 0.25 s hold 1.0; an event row at 1.6 s and the
        // t = 0 row hold outliers that must not count.
        let mut ts = Timeseries::new();
        let mut row = |t: f64, value: f64, event: bool| {
            let fields = FieldMetrics {
                hydro_rel_rms: value,
                checkerboard_means: Some(value),
                ..Default::default()
            };
            let report = StepReport {
                t,
                ..Default::default()
            };
            ts.push(&report, &Peaks::default(), &fields, event);
        };
        row(0.0, 100.0, false);
        for k in 1..=8 {
            row(0.25 * k as f64, 1.0, false);
            if k == 6 {
                row(1.6, 50.0, true);
            }
        }
        let done = summarise(&ts, &[], true);
        assert_eq!(done.figure("hydro_rel_rms_late"), Some(1.0));
        assert_eq!(done.figure("checkerboard_means_late"), Some(1.0));
        assert_eq!(done.figure("hydro_rel_rms_pre_failure"), None);
        assert_eq!(
            done.figure("checkerboard_means_peak"),
            Some(100.0),
            "peaks see every row"
        );
        let failed = summarise(&ts, &[], false);
        assert_eq!(failed.figure("hydro_rel_rms_late"), None);
        assert_eq!(failed.figure("hydro_rel_rms_pre_failure"), Some(1.0));
        assert_eq!(failed.figure("checkerboard_means_pre_failure"), Some(1.0));
        // A failing run: rows of 1.0 until a particle is lost at 1.5 s, then
        // the collapse (1e6). Its pre-failure window ends before the loss.
        let mut failing = Timeseries::new();
        for k in 1..=12 {
            let t = 0.25 * k as f64;
            let lost = t >= 1.5;
            let value = if lost { 1e6 } else { 1.0 };
            let fields = FieldMetrics {
                hydro_rel_rms: value,
                checkerboard_means: Some(value),
                ..Default::default()
            };
            let report = StepReport {
                t,
                particles_lost: if lost { 3 } else { 0 },
                ..Default::default()
            };
            failing.push(&report, &Peaks::default(), &fields, false);
        }
        let failed = summarise(&failing, &[], false);
        assert_eq!(failed.figure("hydro_rel_rms_pre_failure"), Some(1.0));
        assert_eq!(failed.figure("checkerboard_means_pre_failure"), Some(1.0));
        // Without a loss, the failing (last) row itself is left out.
        let mut blown = Timeseries::new();
        for (t, value) in [(0.5, 2.0), (1.0, 2.0), (1.25, 1e9)] {
            let fields = FieldMetrics {
                hydro_rel_rms: value,
                ..Default::default()
            };
            let report = StepReport {
                t,
                ..Default::default()
            };
            blown.push(&report, &Peaks::default(), &fields, false);
        }
        let blown = summarise(&blown, &[], false);
        assert_eq!(blown.figure("hydro_rel_rms_pre_failure"), Some(2.0));
        // A run shorter than a second: the t = 0 row still never counts.
        let mut short = Timeseries::new();
        for (t, v) in [(0.0, 100.0), (0.1, 2.0), (0.2, 4.0)] {
            let fields = FieldMetrics {
                hydro_rel_rms: v,
                ..Default::default()
            };
            let report = StepReport {
                t,
                ..Default::default()
            };
            short.push(&report, &Peaks::default(), &fields, false);
        }
        assert_eq!(
            summarise(&short, &[], true).figure("hydro_rel_rms_late"),
            Some(3.0)
        );
    }
}
