//! What a report page says first: how a case ended, its kicks by cause with
//! their times and places, and the metrics that apply to its scene with
//! their units (a metric that is undefined for the scene, or a count that
//! stayed zero, is not shown).

use crate::report::html::escape;
use crate::report::plot::short;
use monitor::{Cause, Event, Region};
use solver::Scene;
use study::output::summary::{Metrics, Status, Summary};
use study::output::timeseries::COLUMNS;

/// "Completed: reached t = 1.0000 s in 1234 steps." / "Blew up at t =
/// 0.4980 s, step 5678: reason." / "Failed: reason." (HTML).
pub fn status_sentence(s: &Summary) -> String {
    match s.status {
        Status::Completed => format!(
            "<b class=\"status completed\">Completed</b>: reached t = {:.4} s in {} steps.",
            s.t_end, s.steps
        ),
        Status::BlewUp => {
            // The reason usually opens with the step the status names already.
            let step = format!("step {}: ", s.steps);
            let reason = s.reason.strip_prefix(&step).unwrap_or(&s.reason);
            format!(
                "<b class=\"status blew_up\">Blew up</b> at t = {:.4} s, step {}: {}.",
                s.t_end,
                s.steps,
                escape(reason.trim_end_matches('.'))
            )
        }
        Status::Failed => format!(
            "<b class=\"status failed\">Failed</b>: {}.",
            escape(s.reason.trim_end_matches('.'))
        ),
    }
}

/// Where a region lies in the scene's box, in words: "at the foot of the
/// right wall", "on the floor", "at the left wall", "at the top", "inside
/// the fluid". A side counts when the region comes within two cells of it.
pub fn place_words(r: &Region, scene: &Scene) -> &'static str {
    let near = 2.0 * scene.cell;
    let [x0, y0] = scene.origin;
    let (x1, y1) = (x0 + scene.size[0], y0 + scene.size[1]);
    let left = r.x_min - x0 <= near;
    let right = x1 - r.x_max <= near;
    let floor = r.y_min - y0 <= near;
    let top = y1 - r.y_max <= near;
    match (left, right, floor, top) {
        (true, true, _, _) => "across the box",
        (_, _, true, true) => "from floor to top",
        (true, false, true, false) => "at the foot of the left wall",
        (false, true, true, false) => "at the foot of the right wall",
        (true, false, false, true) => "at the top of the left wall",
        (false, true, false, true) => "at the top of the right wall",
        (true, false, false, false) => "at the left wall",
        (false, true, false, false) => "at the right wall",
        (false, false, true, false) => "on the floor",
        (false, false, false, true) => "at the top",
        (false, false, false, false) => "away from the walls",
    }
}

/// "x 0.580–0.600 m, y 0.000–0.020 m (at the foot of the right wall)".
pub fn place(r: &Region, scene: &Scene) -> String {
    format!(
        "x {:.3}–{:.3} m, y {:.3}–{:.3} m ({})",
        r.x_min,
        r.x_max,
        r.y_min,
        r.y_max,
        place_words(r, scene)
    )
}

/// Causes in the order a reader wants them: the kicks, then the rest.
pub const CAUSE_ORDER: [Cause; 4] = [
    Cause::Injection,
    Cause::Inversion,
    Cause::Cfl,
    Cause::Impact,
];

/// The kicks (injection, inversion), earliest first.
pub fn kicks(events: &[Event]) -> Vec<&Event> {
    let mut k: Vec<&Event> = events.iter().filter(|e| e.is_kick()).collect();
    k.sort_by(|a, b| a.t.total_cmp(&b.t).then(a.id.cmp(&b.id)));
    k
}

/// One sentence on the kicks: "No kick." or "2 kicks (2 injection); the
/// first, an injection, at t = 0.2440 s (step 1234), x ... (place)." (HTML).
pub fn kicks_sentence(events: &[Event], scene: &Scene) -> String {
    let k = kicks(events);
    let Some(first) = k.first() else {
        return "<b>No kick.</b>".into();
    };
    let by_cause: Vec<String> = CAUSE_ORDER
        .iter()
        .filter_map(|&c| {
            let n = k.iter().filter(|e| e.cause == c).count();
            (n > 0).then(|| format!("{n} {}", c.name()))
        })
        .collect();
    format!(
        "<b>{} kick{}</b> ({}); the first, an {}, at <b>t = {:.4} s</b> (step {}), <b>{}</b>{}.",
        k.len(),
        if k.len() == 1 { "" } else { "s" },
        by_cause.join(", "),
        first.cause.name(),
        first.t,
        first.first_step,
        escape(&place(&first.region, scene)),
        if first.hallmark() {
            ", with the hallmark (quiet before, sheared earlier)"
        } else {
            ""
        }
    )
}

/// One metric row of the case page.
#[derive(Clone, Debug, PartialEq)]
pub struct MetricRow {
    pub label: &'static str,
    pub value: String,
    pub unit: &'static str,
}

/// The metrics the verdict already states (not repeated in the table);
/// `causes.*` are all the counts by cause.
#[cfg(test)]
pub const IN_VERDICT: [&str; 3] = ["causes", "n_kicks", "t_first_kick"];

/// Each metric of summary.json that is not a timeseries figure: its key in
/// the metrics object (dotted for nested ones), label and unit, in the order
/// shown. The figures drawn from timeseries columns come after the event
/// counts, labelled and in the order their columns declare them.
/// Counts and fractions that are zero are left out, like undefined values.
pub const METRICS: &[(&str, &str, &str)] = &[
    ("t_first_anomaly", "first kick with the hallmark", "s"),
    ("n_anomalies", "kicks with the hallmark", "count"),
    ("n_energy_injections", "energy-budget events", "count"),
    (
        "events_dropped",
        "events dropped past monitor.max_events",
        "count",
    ),
    (
        "checks.surge_front.rms_error",
        "surge front against Martin & Moyce, RMS error",
        "Z = x / a",
    ),
    (
        "checks.surge_front.rms_error_early",
        "surge front, early (T ≤ 3.5) RMS error",
        "Z = x / a",
    ),
    (
        "checks.surge_front.rms_error_early_shifted",
        "surge front, early RMS error after the best time shift",
        "Z = x / a",
    ),
    (
        "checks.surge_front.time_shift",
        "surge front, best time shift",
        "T = t √(2g/a)",
    ),
    (
        "checks.surge_front.speed_late",
        "surge front, late speed dZ/dT",
        "Z per T",
    ),
    (
        "checks.surge_front.rms_error_late",
        "surge front, late (T > 3.5) RMS error",
        "Z = x / a",
    ),
    (
        "losses.particles_escaped",
        "particles deleted: escaped",
        "count",
    ),
    (
        "losses.particles_inverted",
        "particles deleted: inverted",
        "count",
    ),
    (
        "losses.mass_lost_fraction",
        "mass lost with them",
        "of the initial mass",
    ),
    ("losses.t_first_loss", "first deletion", "s"),
    ("losses.particles_drained", "particles drained", "count"),
    (
        "losses.mass_drained_fraction",
        "mass drained",
        "of the initial mass",
    ),
    (
        "losses.particles_injected",
        "particles injected by inflow",
        "count",
    ),
    (
        "losses.mass_injected_fraction",
        "mass injected",
        "of the initial mass",
    ),
    (
        "checks.surface.surface_spread_late",
        "late free-surface spread",
        "m",
    ),
    (
        "checks.surface.penetration_spread_late",
        "late penetration spread",
        "m",
    ),
    (
        "checks.mixture.saturation_max",
        "largest cell saturation",
        "volume fraction",
    ),
    (
        "checks.drag_decay.rel_error",
        "drag decay against exp(-t/tau), largest error",
        "of |dv0|",
    ),
    (
        "checks.drag_decay.discrete_rel_error",
        "drag decay against the update's own law, largest error",
        "of |dv0|",
    ),
    (
        "checks.drag_decay.dt_over_tau",
        "dt / tau at the first step",
        "ratio",
    ),
    (
        "checks.darcy.dp_rel_error",
        "Darcy pressure drop, error",
        "of mu q L / k",
    ),
    (
        "checks.darcy.linearity",
        "Darcy layer pressure, largest departure from its line",
        "of the drop",
    ),
    ("checks.darcy.flux", "Darcy flux q", "m/s"),
    (
        "checks.darcy.flux_rel_error",
        "Darcy flux against rho g H n² / (B L), error",
        "relative",
    ),
    (
        "checks.drag_layer.error",
        "drag layer velocity, largest error",
        "of |u0| L / H",
    ),
    (
        "checks.terzaghi.max_error_over_p0",
        "Terzaghi pore pressure, largest error",
        "of p0",
    ),
    (
        "checks.terzaghi.u_error",
        "Terzaghi degree of consolidation, largest error",
        "of U",
    ),
    (
        "checks.mixture.drag_dissipated",
        "kinetic energy dissipated by the drag",
        "J/m",
    ),
    (
        "checks.mixture.energy_growth",
        "largest rise of the mixture's total energy",
        "J/m",
    ),
    (
        "checks.mixture.momentum_drift_rel",
        "largest momentum drift",
        "of Σ m |v| at t = 0",
    ),
    ("checks.mode_decay.k", "initial flow's wavenumber k", "1/m"),
    ("checks.mode_decay.a0", "initial flow's amplitude", "m/s"),
    (
        "checks.mode_decay.rate",
        "initial flow's decay rate (log-linear fit)",
        "1/s",
    ),
    (
        "checks.mode_decay.nu_equivalent",
        "viscosity the decay amounts to",
        "m²/s",
    ),
    ("checks.mode_decay.fit_from_s", "decay fit from", "s"),
    ("checks.mode_decay.fit_to_s", "decay fit to", "s"),
    ("checks.mode_decay.fit_steps", "decay fit steps", "count"),
    (
        "checks.mode_decay.ratio_end",
        "initial flow left at the end",
        "of its amplitude",
    ),
    (
        "checks.mode_decay.later_max_ratio",
        "initial flow's largest return after the fit",
        "of its amplitude",
    ),
    (
        "checks.ringing.flow_courant",
        "ringing test's U dt / h",
        "1",
    ),
    (
        "checks.ringing.sound_courant",
        "ringing test's c dt / h",
        "1",
    ),
    ("checks.ringing.share", "ringing seed's speed", "of |U|"),
    (
        "checks.ringing.wavelength_cells",
        "ringing seed's wavelength",
        "cells",
    ),
    (
        "checks.ringing.e0",
        "ringing seed's kinetic energy E'",
        "J/m",
    ),
    (
        "checks.ringing.drift_energy",
        "drift's kinetic energy",
        "J/m",
    ),
    (
        "checks.ringing.rate_per_step",
        "growth rate of E' (fit over the window's second half)",
        "1/step",
    ),
    (
        "checks.ringing.rate_per_second",
        "growth rate of E' (fit over the window's second half)",
        "1/s",
    ),
    ("checks.ringing.fit_from_step", "ringing fit from", "step"),
    ("checks.ringing.fit_to_step", "ringing fit to", "step"),
    (
        "checks.ringing.window_end",
        "why the ringing fit's window ended",
        "-",
    ),
    (
        "checks.ringing.ratio_end",
        "E' at the window's end",
        "of E'(0)",
    ),
    ("checks.slosh.k", "standing wave's wavenumber k", "1/m"),
    (
        "checks.slosh.period_theory_s",
        "slosh period, linear theory",
        "s",
    ),
    ("checks.slosh.period_s", "slosh period, measured", "s"),
    (
        "checks.slosh.period_error",
        "slosh period error",
        "of linear theory's",
    ),
    (
        "checks.slosh.decay_theory",
        "slosh decay rate, linear theory (2 nu k²)",
        "1/s",
    ),
    (
        "checks.slosh.decay_rate",
        "slosh decay rate, measured",
        "1/s",
    ),
    (
        "checks.slosh.decay_ratio",
        "slosh decay rate over linear theory's",
        "ratio",
    ),
    (
        "checks.slosh.swing_theory_m",
        "swing of the centre of mass, linear theory",
        "m",
    ),
    (
        "checks.slosh.swing_m",
        "swing of the centre of mass, first",
        "m",
    ),
    ("checks.slosh.extremes", "slosh extremes fitted", "count"),
    (
        "checks.slosh.crossings",
        "slosh zero crossings fitted",
        "count",
    ),
    ("checks.slosh.followed_to_s", "slosh followed to", "s"),
];

/// A row for a value that applies: defined, and for counts and fractions
/// not zero.
fn row(label: &'static str, v: f64, unit: &'static str) -> Option<MetricRow> {
    if !v.is_finite() || (v == 0.0 && counts_or_fraction(unit)) {
        return None;
    }
    let value = if unit == "count" {
        format!("{v:.0}")
    } else {
        short(v)
    };
    Some(MetricRow { label, value, unit })
}

/// The rows of the metrics that apply: the event counts, the timeseries
/// figures (from their column declarations), then losses and checks.
pub fn metric_rows(m: &Metrics) -> Vec<MetricRow> {
    let values = m.flattened();
    let listed = |key: &str, label, unit| row(label, values.get(key)?.as_f64()?, unit);
    let nested = |key: &&(&str, &str, &str)| key.0.contains('.');
    let events = METRICS
        .iter()
        .filter(|k| !nested(k))
        .filter_map(|&(key, label, unit)| listed(key, label, unit));
    let figures = COLUMNS.iter().flat_map(|c| {
        c.figures
            .iter()
            .filter_map(move |f| row(f.label, m.figure(f.name)?, c.unit))
    });
    let rest = METRICS
        .iter()
        .filter(nested)
        .filter_map(|&(key, label, unit)| listed(key, label, unit));
    events.chain(figures).chain(rest).collect()
}

fn counts_or_fraction(unit: &str) -> bool {
    unit == "count" || unit == "of the initial mass"
}

#[cfg(test)]
mod tests {
    use super::*;

    fn scene() -> Scene {
        Scene {
            origin: [0.0, 0.0],
            size: [0.6, 0.6],
            cell: 0.01,
            ..Scene::default()
        }
    }

    fn region(x_min: f64, y_min: f64, x_max: f64, y_max: f64) -> Region {
        Region {
            x_min,
            y_min,
            x_max,
            y_max,
        }
    }

    #[test]
    fn places_name_the_walls_within_two_cells() {
        let s = scene();
        assert_eq!(
            place_words(&region(0.57, 0.0, 0.6, 0.02), &s),
            "at the foot of the right wall"
        );
        assert_eq!(
            place_words(&region(0.2, 0.01, 0.3, 0.05), &s),
            "on the floor"
        );
        assert_eq!(
            place_words(&region(0.01, 0.3, 0.05, 0.35), &s),
            "at the left wall"
        );
        assert_eq!(
            place_words(&region(0.2, 0.2, 0.3, 0.3), &s),
            "away from the walls"
        );
        assert_eq!(
            place(&region(0.57, 0.0, 0.6, 0.02), &s),
            "x 0.570–0.600 m, y 0.000–0.020 m (at the foot of the right wall)"
        );
    }

    /// Every metric of summary.json (every check run) is in the table with
    /// a label and a unit, is a declared figure, or is stated by the
    /// verdict: no raw key reaches the page.
    #[test]
    fn every_metric_has_a_label_and_a_unit_or_is_in_the_verdict() {
        use study::run::probes::{darcy, drag_decay, drag_layer, mixture_conservation, surface};
        use study::run::probes::{surge_front, terzaghi};
        let mut m = study::output::metrics::summarise(
            &study::output::timeseries::Timeseries::new(),
            &[],
            true,
        );
        m.set_check(&surge_front::SurgeFrontFigures::default());
        m.set_check(&drag_decay::DragDecayFigures::default());
        m.set_check(&drag_layer::DragLayerFigures::default());
        m.set_check(&darcy::DarcyFigures::default());
        m.set_check(&terzaghi::TerzaghiFigures::default());
        m.set_check(&surface::SurfaceFigures::default());
        m.set_check(&mixture_conservation::MixtureFigures::default());
        m.set_check(&study::run::probes::mode_decay::ModeDecayFigures::default());
        m.set_check(&study::run::probes::slosh::SloshFigures::default());
        m.set_check(&study::run::probes::ringing::RingingFigures::default());
        let all = m.flattened();
        for key in all.keys() {
            let listed = METRICS.iter().filter(|(k, _, _)| k == key).count();
            let figure = key
                .strip_prefix("figures.")
                .is_some_and(study::output::timeseries::figure_declared);
            let stated = IN_VERDICT
                .iter()
                .any(|v| key == v || key.starts_with(&format!("{v}.")));
            assert!(listed == 1 || (listed == 0 && (figure || stated)), "{key}");
        }
        for (key, label, unit) in METRICS {
            assert!(all.contains_key(*key), "{key} is a metric");
            assert!(!label.is_empty() && !unit.is_empty(), "{key}");
        }
        for c in COLUMNS {
            for f in c.figures {
                assert!(
                    all.contains_key(&format!("figures.{}", f.name)),
                    "{}",
                    f.name
                );
                assert!(!f.label.is_empty() && !c.unit.is_empty() && c.unit != "1");
            }
        }
    }

    /// A dam break's page shows its own figures and no Darcy, drag or
    /// Terzaghi row, no zero count, and no empty value.
    #[test]
    fn only_the_metrics_that_apply_are_rows() {
        let mut m = Metrics {
            n_kicks: 2,
            t_first_kick: Some(0.244),
            ..Metrics::default()
        };
        for (name, v) in [
            ("hydro_rel_rms_pre_failure", 0.12),
            ("checkerboard_means_peak", 0.3),
            ("energy_injected_max", 2.5),
            ("max_accel_g", 40.0),
        ] {
            m.figures.insert(name.into(), Some(v));
        }
        m.figures.insert("checkerboard_means_late".into(), None);
        m.set_check(&study::run::probes::surge_front::SurgeFrontFigures {
            rms_error: Some(0.2),
            ..Default::default()
        });
        let rows = metric_rows(&m);
        let labels: Vec<&str> = rows.iter().map(|r| r.label).collect();
        assert_eq!(
            labels,
            [
                "largest energy injected",
                "largest acceleration",
                "largest checkerboard of the cell means",
                "hydrostatic departure in the second before the blow-up, RMS",
                "surge front against Martin & Moyce, RMS error",
            ]
        );
        assert!(rows
            .iter()
            .all(|r| !r.value.is_empty() && !r.unit.is_empty()));
        assert!(!labels
            .iter()
            .any(|l| l.contains("Darcy") || l.contains("Terzaghi")));
        let mut with_losses = Metrics::default();
        with_losses.losses.particles_escaped = 3;
        with_losses.losses.mass_lost_fraction = 0.001;
        let rows = metric_rows(&with_losses);
        assert_eq!(rows[0].value, "3");
        assert_eq!(rows[1].unit, "of the initial mass");
    }
}
