//! Refinement: for a matrix with a `scene.cell` axis, each case's error
//! against h (the early shifted surge-front error and the late hydrostatic
//! departure, median over an ensemble) and the observed order of
//! convergence, the least-squares slope of ln(error) against ln(h), as a
//! table and, per figure, a log-log plot with reference slopes 1 and 2.

use crate::report::data::{median, Matrix, ParamKey, Row};
use crate::report::html::{Cell, Page};
use crate::report::plot::matrix::RefinementFigure;
use crate::report::plot::{render, short, Res};
use std::collections::BTreeMap;
use std::path::Path;
use study::output::metrics::observed_order;
use study::run::probes::darcy::DarcyFigures;
use study::run::probes::drag_layer::DragLayerFigures;
use study::run::probes::surge_front::SurgeFrontFigures;

type Figure = fn(&Row) -> Option<f64>;
/// A case's figure at each h.
type Line = (String, Vec<(f64, f64)>);
/// A row of the table: its class and cells.
type TableRow = (String, Vec<Cell>);

const FIGURES: [(&str, Figure); 8] = [
    ("surge front, early shifted RMS (Z)", |r| {
        r.summary
            .metrics
            .check::<SurgeFrontFigures>()
            .and_then(|c| c.rms_error_early_shifted)
    }),
    ("surge front speed late (dZ/dT)", |r| {
        r.summary
            .metrics
            .check::<SurgeFrontFigures>()
            .and_then(|c| c.speed_late)
    }),
    ("late hydrostatic departure (rel. RMS)", |r| {
        r.summary.metrics.figure("hydro_rel_rms_late")
    }),
    ("Darcy flux against rho g H n^2 / (B L) (rel.)", |r| {
        r.summary
            .metrics
            .check::<DarcyFigures>()
            .map(|c| c.flux_rel_error)
    }),
    (
        "fixed layer: fluid velocity error against the update's law (rel.)",
        |r| {
            r.summary
                .metrics
                .check::<DragLayerFigures>()
                .map(|c| c.error)
        },
    ),
    ("Darcy pressure drop against mu q L / k (rel.)", |r| {
        r.summary
            .metrics
            .check::<DarcyFigures>()
            .map(|c| c.dp_rel_error)
    }),
    // Appended, so that the earlier figures keep their file names.
    (
        "late hydrostatic floor (rel. RMS of the exact rest field)",
        |r| r.summary.metrics.figure("hydro_floor_late"),
    ),
    (
        "late hydrostatic departure above its floor (rel. RMS)",
        |r| r.summary.metrics.figure("hydro_excess_late"),
    ),
];

/// A case name without its cell-size token (`h2cm`, `h0.5cm`): the name of
/// the refinement group.
fn without_cell_size(case: &str) -> String {
    let is_h = |t: &str| {
        t.strip_prefix('h')
            .and_then(|t| t.strip_suffix("cm"))
            .is_some_and(|v| v.parse::<f64>().is_ok())
    };
    let kept: Vec<&str> = case.split('_').filter(|t| !is_h(t)).collect();
    kept.join("_")
}

/// Each case's runs by cell size: grouped by every axis but `scene.cell`,
/// then by h (as its bits, ascending for positive h).
type Groups<'a> = BTreeMap<Vec<String>, BTreeMap<u64, Vec<&'a Row>>>;

/// The refinement table and figures (a matrix section:
/// `matrix::MATRIX_SECTIONS`); nothing without a `scene.cell` axis
/// or a case run at two cell sizes.
pub fn refinement_table(m: &Matrix, out: &Path, page: &mut Page) -> Res {
    let Some(h_axis) = m.axis(ParamKey::is_cell_size) else {
        return Ok(());
    };
    let mut rows: Vec<TableRow> = vec![];
    // Per figure, one (case, [(h, value)]) line per group.
    let mut plots: Vec<Vec<Line>> = vec![vec![]; FIGURES.len()];
    for (key, by_h) in &by_cell_size(m, h_axis) {
        if by_h.len() < 2 {
            continue;
        }
        for (f, figure) in FIGURES.iter().enumerate() {
            if let Some((row, line)) = figure_row(key, by_h, figure) {
                rows.push(row);
                plots[f].extend(line);
            }
        }
    }
    if rows.is_empty() {
        return Ok(());
    }
    page.h2("Refinement: observed order of convergence");
    page.p("Per case (every other axis fixed), the figure at each cell size h (median over an ensemble) and the observed order, the least-squares slope of ln(error) against ln(h) (1 and 2 are first and second order).");
    let headers = ["case", "figure", "h (m): value", "order"]
        .map(String::from)
        .to_vec();
    page.table("refinement", &headers, &rows);
    refinement_figures(plots, out, page)
}

fn by_cell_size(m: &Matrix, h_axis: usize) -> Groups<'_> {
    let h_of = |r: &Row| {
        r.summary
            .params
            .get("scene.cell")
            .and_then(|v| v.as_f64())
            .unwrap_or(f64::NAN)
    };
    let mut groups: Groups = BTreeMap::new();
    for r in &m.rows {
        let mut key = r.params.clone();
        key.remove(h_axis);
        groups
            .entry(key)
            .or_default()
            .entry(h_of(r).to_bits())
            .or_default()
            .push(r);
    }
    groups
}

/// One case's table row for one figure (None when the figure is undefined
/// at every h), and its line for the figure's plot (None for the front
/// speed, which converges to a value, not to zero: no order for it).
fn figure_row(
    key: &[String],
    by_h: &BTreeMap<u64, Vec<&Row>>,
    (name, figure): &(&str, Figure),
) -> Option<(TableRow, Option<Line>)> {
    let hs: Vec<f64> = by_h.keys().map(|b| f64::from_bits(*b)).collect();
    let values: Vec<f64> = by_h
        .values()
        .map(|runs| {
            let v: Vec<f64> = runs.iter().filter_map(|r| figure(r)).collect();
            median(&v).unwrap_or(f64::NAN)
        })
        .collect();
    if values.iter().all(|v| !v.is_finite()) {
        return None;
    }
    let label = by_h
        .values()
        .next()
        .and_then(|runs| runs.first())
        .map_or_else(|| key.join(" "), |r| without_cell_size(&r.summary.case));
    let text: Vec<String> = hs
        .iter()
        .zip(&values)
        .map(|(h, v)| format!("{}: {}", short(*h), short(*v)))
        .collect();
    let (order, line) = if name.contains("speed") {
        ("-".into(), None)
    } else {
        (
            observed_order(&hs, &values).map_or("-".into(), |p| format!("{p:.2}")),
            Some((label.clone(), hs.iter().copied().zip(values).collect())),
        )
    };
    let row = (
        format!("{label} {name}"),
        vec![
            Cell::Text(label),
            Cell::Text((*name).into()),
            Cell::Text(text.join(", ")),
            Cell::Num(order),
        ],
    );
    Some((row, line))
}

/// Per figure, its lines against h on log-log axes (a figure needs a line
/// with two positive values).
fn refinement_figures(plots: Vec<Vec<Line>>, out: &Path, page: &mut Page) -> Res {
    for (f, lines) in plots.into_iter().enumerate() {
        let drawn = |pts: &Vec<(f64, f64)>| pts.iter().filter(|(_, e)| *e > 0.0).count() >= 2;
        if !lines.iter().any(|(_, pts)| drawn(pts)) {
            continue;
        }
        let name = FIGURES[f].0;
        let fig = RefinementFigure {
            title: format!("Refinement: {name}"),
            y_label: name.into(),
            lines,
        };
        page.figure(
            &render(&fig, out, &format!("refinement_{f}"))?,
            &format!("{name} against h, one line per case, with dashed reference slopes 1 and 2"),
        );
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::without_cell_size;

    #[test]
    fn the_group_name_drops_only_the_cell_size() {
        assert_eq!(
            without_cell_size("h0.5cm_K1.5MPa_tait_base"),
            "K1.5MPa_tait_base"
        );
        assert_eq!(
            without_cell_size("svf_node_h0.6666666666666667cm"),
            "svf_node"
        );
        assert_eq!(
            without_cell_size("h2cm_mu0_noslip-floor_j_bar1.0"),
            "mu0_noslip-floor_j_bar1.0"
        );
        assert_eq!(without_cell_size("hydro_heavy"), "hydro_heavy");
    }
}
