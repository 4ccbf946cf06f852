//! The stability map of the matrix page: time survived against K, one line
//! per combination of the other axes (median over an ensemble, with its
//! range as bars).

use crate::report::data::{spread, Matrix, ParamKey, Row};
use crate::report::html::Page;
use crate::report::plot::matrix::LinesFigure;
use crate::report::plot::{render, Res};
use std::collections::BTreeSet;
use std::path::Path;

/// Survival time against K, one line per combination of the other axes.
/// (A matrix section: `matrix::MATRIX_SECTIONS`.)
pub fn stability_map(m: &Matrix, out: &Path, page: &mut Page) -> Res {
    let Some(kx) = m.axis(ParamKey::is_bulk_modulus) else {
        return Ok(());
    };
    let short_key = |k: usize| m.axes[k].field();
    let family = |r: &Row| {
        (0..m.axes.len())
            .filter(|&k| k != kx)
            .map(|k| format!("{}={}", short_key(k), r.params[k]))
            .collect::<Vec<_>>()
            .join(" ")
    };
    let families: BTreeSet<String> = m.rows.iter().map(family).collect();
    // Per family and K: the median survival, and its range over an ensemble.
    let mut lines = vec![];
    let mut spreads = vec![];
    for f in &families {
        let mut by_k: Vec<(f64, Vec<f64>)> = vec![];
        for r in m.rows.iter().filter(|r| &family(r) == f) {
            let Ok(k) = r.params[kx].parse::<f64>() else {
                continue;
            };
            match by_k.iter_mut().find(|(x, _)| *x == k) {
                Some((_, v)) => v.push(r.t_end()),
                None => by_k.push((k, vec![r.t_end()])),
            }
        }
        by_k.sort_by(|a, b| a.0.total_cmp(&b.0));
        let stats: Vec<(f64, (f64, f64, f64), usize)> = by_k
            .iter()
            .filter_map(|(k, v)| Some((*k, spread(v.iter().copied())?, v.len())))
            .collect();
        let name = if f.is_empty() {
            "all".into()
        } else {
            f.clone()
        };
        lines.push((name, stats.iter().map(|(k, s, _)| (*k, s.0)).collect()));
        spreads.push(
            stats
                .iter()
                .filter(|(_, _, n)| *n > 1)
                .map(|(k, s, _)| (*k, s.1, s.2))
                .collect(),
        );
    }
    let fig = LinesFigure {
        spread: spreads,
        title: "Stability map: time survived (median; bars: ensemble range)".into(),
        x_label: format!("{} (Pa, log)", m.axes[kx]),
        y_label: "time survived (s)".into(),
        lines,
        x_log: true,
        y_max: m.rows.iter().map(|r| r.t_end()).fold(0.1, f64::max),
    };
    page.figure(
        &render(&fig, out, "stability")?,
        "Time survived against K, one line per combination of the other axes",
    );
    Ok(())
}
