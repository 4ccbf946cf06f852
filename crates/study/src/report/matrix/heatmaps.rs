//! The outcome and late-hydrostatic heatmaps of the matrix page: one cell
//! per case (x = K or the first axis, one panel per viscosity, y = the
//! other axes), coloured by the outcome class (`data::Class`) or by
//! the late hydrostatic departure.

use crate::report::data::{by_value, spread, Class, Matrix, ParamKey, Row};
use crate::report::html::Page;
use crate::report::plot::matrix::{HeatCell, HeatKey, HeatPanel, HeatmapFigure};
use crate::report::plot::{render, short, ColourScale, Res};
use plotters::style::RGBColor;
use std::collections::BTreeSet;
use std::path::Path;
use study::output::summary::Status;

/// A class's label and colour in the outcome heatmap's legend.
fn style(class: Class) -> (&'static str, RGBColor) {
    match class {
        Class::NoKickSurvived => ("no kick, survived", RGBColor(90, 170, 90)),
        Class::NoKickBlewUp => ("no kick, blew up", RGBColor(235, 175, 175)),
        Class::InjectionFirst => ("kick first (injection or jump)", RGBColor(240, 150, 50)),
        Class::InversionFirst => ("inversion first", RGBColor(190, 40, 40)),
        Class::AnomalyFirst => ("anomaly first", RGBColor(140, 60, 170)),
        Class::Failed => ("failed", RGBColor(150, 150, 150)),
    }
}

/// Heatmap layout: x = K (or the first axis), one panel per viscosity, y = the other axes.
struct HeatLayout<'a> {
    m: &'a Matrix,
    x_axis: usize,
    panel_axis: Option<usize>,
    y_axes: Vec<usize>,
    x_cats: Vec<String>,
    y_cats: Vec<String>,
    p_cats: Vec<String>,
}

impl<'a> HeatLayout<'a> {
    fn new(m: &'a Matrix) -> Self {
        let x_axis = m.axis(ParamKey::is_bulk_modulus).unwrap_or(0);
        let panel_axis = m.axis(ParamKey::is_viscosity).filter(|&p| p != x_axis);
        let y_axes: Vec<usize> = (0..m.axes.len())
            .filter(|&k| k != x_axis && Some(k) != panel_axis)
            .collect();
        let mut layout = HeatLayout {
            m,
            x_axis,
            panel_axis,
            y_axes,
            x_cats: vec![],
            y_cats: vec![],
            p_cats: vec![String::new()],
        };
        layout.x_cats = layout.cats(|r| r.params[x_axis].clone());
        layout.y_cats = layout.cats(|r| layout.y_of(r));
        if let Some(p) = panel_axis {
            layout.p_cats = layout.cats(|r| r.params[p].clone());
        }
        layout
    }

    fn y_of(&self, r: &Row) -> String {
        self.y_axes
            .iter()
            .map(|&k| r.params[k].clone())
            .collect::<Vec<_>>()
            .join(" ")
    }

    fn cats(&self, f: impl Fn(&Row) -> String) -> Vec<String> {
        let mut v: Vec<String> = self
            .m
            .rows
            .iter()
            .map(f)
            .collect::<BTreeSet<_>>()
            .into_iter()
            .collect();
        v.sort_by(by_value);
        v
    }

    fn y_label(&self) -> String {
        self.y_axes
            .iter()
            .map(|&k| self.m.axes[k].to_string())
            .collect::<Vec<_>>()
            .join(" / ")
    }

    /// One cell per case; `cell` sees every run of the case (one, or an ensemble).
    fn figure(
        &self,
        title: &str,
        key: HeatKey,
        cell: impl Fn(&[&Row]) -> (RGBColor, String),
    ) -> HeatmapFigure {
        let panels = self
            .p_cats
            .iter()
            .map(|p| {
                let mut groups: Vec<((usize, usize), Vec<&Row>)> = vec![];
                for r in self
                    .m
                    .rows
                    .iter()
                    .filter(|r| self.panel_axis.is_none_or(|a| &r.params[a] == p))
                {
                    let at = (
                        self.x_cats
                            .iter()
                            .position(|c| *c == r.params[self.x_axis])
                            .unwrap_or(0),
                        self.y_cats
                            .iter()
                            .position(|c| *c == self.y_of(r))
                            .unwrap_or(0),
                    );
                    match groups.iter_mut().find(|(g, _)| *g == at) {
                        Some((_, rows)) => rows.push(r),
                        None => groups.push((at, vec![r])),
                    }
                }
                HeatPanel {
                    title: match self.panel_axis {
                        Some(a) => format!("{} = {p}", self.m.axes[a]),
                        None => String::new(),
                    },
                    cells: groups
                        .iter()
                        .map(|((x, y), rows)| {
                            let (colour, text) = cell(rows);
                            HeatCell {
                                x: *x,
                                y: *y,
                                colour,
                                text,
                            }
                        })
                        .collect(),
                }
            })
            .collect();
        HeatmapFigure {
            title: title.into(),
            x_label: self.m.axes[self.x_axis].to_string(),
            y_label: self.y_label(),
            x_cats: self.x_cats.clone(),
            y_cats: self.y_cats.clone(),
            panels,
            key,
        }
    }
}

/// The case's outcome: the most frequent among its runs (ties: the worse),
/// with the median first-kick and survival times, and their range over an ensemble.
fn outcome_cell(runs: &[&Row]) -> (RGBColor, String) {
    // Class::ALL runs from best to worst and max_by_key keeps the last maximum.
    let class = Class::ALL
        .into_iter()
        .max_by_key(|&c| runs.iter().filter(|r| r.class() == c).count())
        .expect("six classes");
    let kick = spread(runs.iter().map(|r| r.t_first_kick()));
    let blew = runs.iter().any(|r| r.status() == Status::BlewUp);
    let end = spread(runs.iter().map(|r| r.t_end())).filter(|_| blew);
    let mut parts = vec![];
    // Median ± half range over an ensemble (the Ensembles table has min and max).
    if let Some(k) = kick {
        parts.push(format!("k {}", compact(k)));
    }
    if let Some(e) = end {
        parts.push(format!("x {}", compact(e)));
    }
    let text = if !parts.is_empty() {
        parts.join(" ")
    } else if runs.iter().all(|r| r.status() == Status::Failed) {
        "failed".into()
    } else {
        "ok".into()
    };
    (style(class).1, text)
}

/// The outcome and late-hydrostatic heatmaps (a matrix section:
/// `matrix::MATRIX_SECTIONS`).
pub fn heatmaps(m: &Matrix, out: &Path, page: &mut Page) -> Res {
    let layout = HeatLayout::new(m);
    let outcome = layout.figure(
        "Outcome by the cause of the first kick; time of first kick and blow-up (s)",
        HeatKey::Legend(
            Class::ALL
                .map(|c| (style(c).0.to_string(), style(c).1))
                .to_vec(),
        ),
        outcome_cell,
    );
    page.h2("Outcome");
    page.figure(
        &render(&outcome, out, "heatmap_outcome")?,
        "Colour: the cause of the first kick (a kick is an injection, an inversion or a jump; the anomaly is a kick with the hallmark), or how a run that never kicked ended; over an ensemble the most frequent class (ties: the worse). Text: k t = first kick at t (s), x t = blew up at t (s), the median ± half the range over an ensemble",
    );
    let hydro: Vec<f64> = m.rows.iter().map(|r| r.hydro_late()).collect();
    let scale = ColourScale::robust(&hydro, true);
    // An empty map says why: the departure is read on completed runs only.
    let key = if hydro.iter().any(|h| *h > 0.0) {
        HeatKey::Bar(scale, "rel. RMS (log)".into())
    } else {
        HeatKey::Legend(vec![("no case completed".into(), NO_VALUE)])
    };
    let hydro_map = layout.figure(
        "Late hydrostatic departure (relative RMS, last second of completed runs)",
        key,
        |runs| match spread(runs.iter().map(|r| r.hydro_late()).filter(|h| *h > 0.0)) {
            Some((h, _, _)) => (scale.colour(h), short(h)),
            None => (NO_VALUE, why_no_departure(runs).into()),
        },
    );
    page.figure(
        &render(&hydro_map, out, "heatmap_hydro")?,
        "Late hydrostatic departure (log colour scale)",
    );
    Ok(())
}

/// The grey of a heatmap cell without a value.
const NO_VALUE: RGBColor = RGBColor(220, 220, 220);

/// Why a case has no late hydrostatic departure.
fn why_no_departure(runs: &[&Row]) -> &'static str {
    if runs.iter().all(|r| r.status() == Status::BlewUp) {
        "blew up"
    } else if runs.iter().all(|r| r.status() == Status::Failed) {
        "failed"
    } else {
        "no value"
    }
}

/// Heatmap form: the median, with ± half the range when the runs differ.
fn compact(s: (f64, f64, f64)) -> String {
    let half = 0.5 * (s.2 - s.1);
    if half < 0.005 {
        format!("{:.2}", s.0)
    } else {
        format!("{:.2}±{:.2}", s.0, half)
    }
}
