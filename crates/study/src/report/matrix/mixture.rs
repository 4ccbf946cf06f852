//! The multiphase section of a matrix report (docs/physics.md section 6):
//! for mixture cases, the drag's figures per case (decay errors, dt/tau,
//! dissipation, energy growth, momentum drift, each phase's events) and the
//! decay error against dt/tau, one line per drag update.

use crate::report::data::{Matrix, Row};
use crate::report::html::{escape, Cell, Page};
use crate::report::plot::matrix::LinesFigure;
use crate::report::plot::{render, short, Res};
use std::collections::BTreeMap;
use std::path::Path;
use study::run::probes::darcy::DarcyFigures;
use study::run::probes::drag_decay::DragDecayFigures;
use study::run::probes::drag_layer::DragLayerFigures;
use study::run::probes::mixture_conservation::MixtureFigures;
use study::run::probes::surface::SurfaceFigures;

/// The multiphase section (a matrix section: `matrix::MATRIX_SECTIONS`):
/// nothing unless some case is a mixture.
pub fn mixture_section(m: &Matrix, out: &Path, page: &mut Page) -> Res {
    let rows: Vec<_> = m
        .rows
        .iter()
        .filter(|r| !r.summary.phases.is_empty())
        .collect();
    if rows.is_empty() {
        return Ok(());
    }
    page.h2("Multiphase: drag between the phases");
    page.p(
        "Each mixture case: the largest error of the relative velocity against the exact \
         decay dv0 exp(-t/tau) and against its update's own discrete law (both relative to \
         |dv0|, over the whole run; uniform periodic scenes only), the first step's dt/tau, \
         the kinetic energy the drag dissipated, the largest rise of the total energy above \
         its start (drag dissipation counted) and of the momentum (relative to sum m|v| at \
         t = 0; periodic scenes without gravity); in the Darcy column (a fixed layer in a \
         box periodic along gravity, at t_end) the error of the layer's pressure drop against \
         mu q L / k from the fitted gradients, the largest departure of its row-averaged \
         pressure from a line (over the drop), the measured flux q and its error against the \
         flux that carries the column's weight; under gravity in a closed box, the mean over \
         the last second of the fluid's free-surface spread and of its lowest particles' \
         spread across the columns (levelling and evenness of penetration), the largest \
         cell saturation at the end (above 1: water crowding into the grains' room) and the \
         fluid's late hydrostatic departure; and each phase's events.",
    );
    mixture_table(&rows, page);
    convergence_figure(&rows, out, page)?;
    decay_figure(&rows, out, page)
}

/// A param of the case as text ("-" when it lacks it).
fn param(r: &Row, key: &str) -> String {
    r.summary
        .params
        .get(key)
        .map(|v| match v {
            serde_json::Value::String(s) => s.clone(),
            other => other.to_string(),
        })
        .unwrap_or_else(|| "-".into())
}

/// One row per mixture case: its drag figures and each phase's events.
fn mixture_table(rows: &[&Row], page: &mut Page) {
    let opt = |v: Option<f64>| Cell::Num(v.map_or("-".into(), short));
    let headers: Vec<String> = [
        "case",
        "status",
        "drag update",
        "dt/tau",
        "decay error (exact)",
        "decay error (own law)",
        "dissipated (J/m)",
        "energy growth (J/m)",
        "momentum drift",
        "Darcy drop error",
        "Darcy p linearity",
        "Darcy flux q (m/s)",
        "q error",
        "surface spread late (m)",
        "penetration spread late (m)",
        "saturation max",
        "fluid hydro late (rel. RMS)",
        "events solid / fluid",
    ]
    .map(String::from)
    .to_vec();
    let table: Vec<(String, Vec<Cell>)> = rows
        .iter()
        .map(|r| {
            let s = &r.summary;
            let mx = &s.metrics;
            let events = s
                .phases
                .iter()
                .map(|p| p.n_events.to_string())
                .collect::<Vec<_>>()
                .join(" / ");
            (
                String::new(),
                vec![
                    Cell::Text(escape(&s.case)),
                    Cell::Text(s.status.as_str().into()),
                    Cell::Text(escape(&param(r, "drag.update"))),
                    opt(mx.check::<DragDecayFigures>().and_then(|c| c.dt_over_tau)),
                    opt(mx.check::<DragDecayFigures>().map(|c| c.rel_error)),
                    opt(mx.check::<DragDecayFigures>().map(|c| c.discrete_rel_error)),
                    opt(mx.check::<MixtureFigures>().map(|c| c.drag_dissipated)),
                    opt(mx.check::<MixtureFigures>().and_then(|c| c.energy_growth)),
                    opt(mx
                        .check::<MixtureFigures>()
                        .and_then(|c| c.momentum_drift_rel)),
                    opt(mx.check::<DarcyFigures>().map(|c| c.dp_rel_error)),
                    opt(mx.check::<DarcyFigures>().and_then(|c| c.linearity)),
                    opt(mx.check::<DarcyFigures>().map(|c| c.flux)),
                    opt(mx.check::<DarcyFigures>().map(|c| c.flux_rel_error)),
                    opt(mx
                        .check::<SurfaceFigures>()
                        .and_then(|c| c.surface_spread_late)),
                    opt(mx
                        .check::<SurfaceFigures>()
                        .and_then(|c| c.penetration_spread_late)),
                    opt(mx.check::<MixtureFigures>().map(|c| c.saturation_max)),
                    opt(s
                        .phases
                        .get(1)
                        .and_then(|p| p.metrics.figure("hydro_rel_rms_late"))),
                    Cell::Num(events),
                ],
            )
        })
        .collect();
    page.table("mixture", &headers, &table);
}

/// Decay error against dt/tau, a line per update (drawn from two points on).
fn decay_figure(rows: &[&Row], out: &Path, page: &mut Page) -> Res {
    let mut lines: BTreeMap<String, Vec<(f64, f64)>> = BTreeMap::new();
    for r in rows {
        let mx = &r.summary.metrics;
        if let (Some(x), Some(y)) = (
            mx.check::<DragDecayFigures>().and_then(|c| c.dt_over_tau),
            mx.check::<DragDecayFigures>().map(|c| c.rel_error),
        ) {
            lines
                .entry(param(r, "drag.update"))
                .or_default()
                .push((x, y));
        }
    }
    if lines.values().map(Vec::len).sum::<usize>() < 2 {
        return Ok(());
    }
    for pts in lines.values_mut() {
        pts.sort_by(|a, b| a.0.total_cmp(&b.0));
    }
    let y_max = lines
        .values()
        .flatten()
        .map(|p| p.1)
        .fold(0.0_f64, f64::max)
        .max(1e-3);
    let fig = LinesFigure {
        title: "Relative-velocity decay: largest error against exp(-t/tau)".into(),
        x_label: "dt / tau (first step)".into(),
        y_label: "max |dv - dv0 exp(-t/tau)| / |dv0|".into(),
        lines: lines.into_iter().collect(),
        spread: vec![],
        x_log: true,
        y_max,
    };
    page.figure(
        &render(&fig, out, "drag_decay")?,
        "Decay error against dt/tau, one line per drag update (the explicit update's step is \
         held below 0.4 tau)",
    );
    Ok(())
}

/// The fixed layer's error against h, a line per interaction model, with
/// each model's observed order in its legend.
fn convergence_figure(rows: &[&Row], out: &Path, page: &mut Page) -> Res {
    let mut lines: BTreeMap<String, Vec<(f64, f64)>> = BTreeMap::new();
    for r in rows {
        let s = &r.summary;
        let h = s.params.get("scene.cell").and_then(|v| v.as_f64());
        if let (Some(h), Some(e)) = (h, s.metrics.check::<DragLayerFigures>().map(|c| c.error)) {
            let model = s
                .params
                .get("drag.model")
                .and_then(|v| v.as_str())
                .unwrap_or("bang_bang_node");
            let update = s
                .params
                .get("drag.update")
                .and_then(|v| v.as_str())
                .unwrap_or("implicit");
            lines
                .entry(format!("{model} ({update})"))
                .or_default()
                .push((h, e));
        }
    }
    lines.retain(|_, pts| pts.len() >= 2);
    if lines.is_empty() {
        return Ok(());
    }
    let mut named = vec![];
    for (name, mut pts) in lines {
        pts.sort_by(|a, b| a.0.total_cmp(&b.0));
        let (h, e): (Vec<f64>, Vec<f64>) = pts.iter().copied().unzip();
        let order = study::output::metrics::observed_order(&h, &e)
            .map_or("-".into(), |p| format!("{p:.2}"));
        named.push((format!("{name}: order {order}"), pts));
    }
    let y_max = named
        .iter()
        .flat_map(|(_, p)| p.iter().map(|q| q.1))
        .fold(0.0_f64, f64::max);
    let fig = LinesFigure {
        title: "Interaction models under refinement: fixed layer in moving fluid".into(),
        x_label: "cell size h (m)".into(),
        y_label: "max fluid velocity error / (|u0| L / H)".into(),
        lines: named,
        spread: vec![],
        x_log: true,
        y_max,
    };
    page.figure(
        &render(&fig, out, "drag_convergence")?,
        "Each interaction model's error against h and its observed order (least-squares slope of ln error against ln h)",
    );
    Ok(())
}
