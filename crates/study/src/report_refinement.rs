//! Refinement: for a matrix with a `scene.cell` axis, each case's error
//! against h (the early shifted surge-front error and the late hydrostatic
//! departure, median over an ensemble) and the observed order of
//! convergence, the least-squares slope of ln(error) against ln(h).

use crate::metrics::observed_order;
use crate::plot_common::short;
use crate::report_html::{Cell, Page};
use crate::report_matrix::{median, Matrix, Row};
use std::collections::BTreeMap;

type Figure = fn(&Row) -> Option<f64>;

const FIGURES: [(&str, Figure); 6] = [
    ("surge front, early shifted RMS (Z)", |r| {
        r.summary.metrics.front_rms_error_early_shifted
    }),
    ("surge front speed late (dZ/dT)", |r| {
        r.summary.metrics.front_speed_late
    }),
    ("late hydrostatic departure (rel. RMS)", |r| {
        r.summary.metrics.hydro_rel_rms_late
    }),
    ("Darcy flux against rho g H n^2 / (B L) (rel.)", |r| {
        r.summary.metrics.darcy_flux_rel_error
    }),
    (
        "fixed layer: fluid velocity error against the update's law (rel.)",
        |r| r.summary.metrics.drag_layer_error,
    ),
    ("Darcy pressure drop against mu q L / k (rel.)", |r| {
        r.summary.metrics.darcy_dp_rel_error
    }),
];

pub fn refinement_table(m: &Matrix, page: &mut Page) {
    let Some(h_axis) = m.axis("scene.cell") else {
        return;
    };
    let h_of = |r: &Row| {
        r.summary
            .params
            .get("scene.cell")
            .and_then(|v| v.as_f64())
            .unwrap_or(f64::NAN)
    };
    // Group by every other axis; within a group, by h.
    let mut groups: BTreeMap<Vec<String>, BTreeMap<u64, Vec<&Row>>> = BTreeMap::new();
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
    let mut rows: Vec<(String, Vec<Cell>)> = vec![];
    for (key, by_h) in &groups {
        if by_h.len() < 2 {
            continue;
        }
        let hs: Vec<f64> = by_h.keys().map(|b| f64::from_bits(*b)).collect();
        for (name, figure) in FIGURES {
            let values: Vec<f64> = by_h
                .values()
                .map(|runs| {
                    let v: Vec<f64> = runs.iter().filter_map(|r| figure(r)).collect();
                    median(&v).unwrap_or(f64::NAN)
                })
                .collect();
            if values.iter().all(|v| !v.is_finite()) {
                continue;
            }
            let label = key.join(" ");
            let text: Vec<String> = hs
                .iter()
                .zip(&values)
                .map(|(h, v)| format!("{}: {}", short(*h), short(*v)))
                .collect();
            // The front speed converges to a value, not to zero: no order for it.
            let order = if name.contains("speed") {
                "-".into()
            } else {
                observed_order(&hs, &values).map_or("-".into(), |p| format!("{p:.2}"))
            };
            rows.push((
                format!("{label} {name}"),
                vec![
                    Cell::Text(label),
                    Cell::Text(name.into()),
                    Cell::Text(text.join(", ")),
                    Cell::Num(order),
                ],
            ));
        }
    }
    if rows.is_empty() {
        return;
    }
    page.h2("Refinement: observed order of convergence");
    page.p("Per case (every other axis fixed), the figure at each cell size h (median over an ensemble) and the observed order, the least-squares slope of ln(error) against ln(h) (1 and 2 are first and second order).");
    let headers = ["case", "figure", "h (m): value", "order"]
        .map(String::from)
        .to_vec();
    page.table("refinement", &headers, &rows);
}
