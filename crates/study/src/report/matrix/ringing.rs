//! The ringing map of the matrix page (docs/physics.md section 7b): for
//! the cases that ran Brackbill's ringing test (`checks.ringing`), one
//! panel per method over U dt / h (x) and c dt / h (y), each cell coloured
//! by the growth rate of the perturbation's kinetic energy per step, with
//! the rate of the run whose seed was halved beside it when there is one.

use crate::report::data::Matrix;
use crate::report::html::{escape, Cell, Page};
use crate::report::plot::matrix::{HeatCell, HeatKey, HeatPanel, HeatmapFigure};
use crate::report::plot::{render, Res};
use monitor::ringing_growth::WindowEnd;
use plotters::style::RGBColor;
use std::collections::BTreeMap;
use std::path::Path;
use study::output::summary::Summary;
use study::run::probes::ringing::RingingFigures;

/// E' growing faster than this per step: the map calls the point unstable
/// (E' e-folds within 1000 steps).
pub const UNSTABLE_PER_STEP: f64 = 1e-3;
/// |rate| below this per step: neutral on the map.
pub const NEUTRAL_PER_STEP: f64 = 1e-4;
/// The halved seed's rate may differ by this share.
pub const HALVING_TOLERANCE: f64 = 0.1;

/// The rate's class on the map: label and colour.
const CLASSES: [(&str, RGBColor); 6] = [
    ("grows > 1e-2 / step", RGBColor(150, 20, 20)),
    ("grows 1e-3..1e-2", RGBColor(230, 90, 60)),
    ("grows 1e-4..1e-3", RGBColor(250, 190, 120)),
    ("neutral |r| < 1e-4", RGBColor(235, 235, 235)),
    ("decays", RGBColor(110, 150, 210)),
    ("blew up / no rate", RGBColor(90, 90, 90)),
];

fn class(rate: Option<f64>, end: WindowEnd) -> usize {
    match rate {
        _ if end == WindowEnd::NotFinite => 5,
        None => 5,
        Some(r) if r > 1e-2 => 0,
        Some(r) if r > UNSTABLE_PER_STEP => 1,
        Some(r) if r > NEUTRAL_PER_STEP => 2,
        Some(r) if r >= -NEUTRAL_PER_STEP => 3,
        Some(_) => 4,
    }
}

/// A method as the map names it: shape, transfer (with XPIC's order) and scheme.
pub fn method_label(s: &Summary) -> String {
    let text = |k: &str| {
        s.params
            .get(k)
            .map(|v| v.as_str().map_or(v.to_string(), str::to_string))
            .unwrap_or_default()
    };
    let mut transfer = text("method.transfer").to_uppercase();
    if transfer == "XPIC" {
        transfer = format!("XPIC({})", text("method.xpic_order"));
    }
    format!(
        "{} {} {}",
        text("method.shape"),
        transfer,
        text("method.scheme").to_uppercase()
    )
}

/// One point of a method's map: the full seed's figures and the halved one's.
#[derive(Default)]
struct MapPoint {
    full: Option<RingingFigures>,
    halved: Option<RingingFigures>,
}

impl MapPoint {
    /// The halved seed's rate differs from the full one's by this share.
    fn halving_change(&self) -> Option<f64> {
        let a = self.full.as_ref()?.growth.rate_per_step?;
        let b = self.halved.as_ref()?.growth.rate_per_step?;
        Some((b / a - 1.0).abs())
    }
}

/// Key of a map coordinate (3 significant digits, as text that sorts by value).
fn coordinate(x: f64) -> String {
    format!("{x:.3}")
}

/// method -> (U dt / h, c dt / h) -> point.
type Maps = BTreeMap<String, BTreeMap<(String, String), MapPoint>>;

/// The ringing cases of a matrix, on the map's axes.
struct Gathered {
    maps: Maps,
    /// The larger seed share: the full seed (the other is the halved one).
    full_share: f64,
    /// How many seed shares the matrix ran.
    seeds: usize,
    x_cats: Vec<String>,
    y_cats: Vec<String>,
}

/// The ringing cases' figures by method and point; None without any.
fn gather(m: &Matrix) -> Option<Gathered> {
    let mut maps = Maps::new();
    let mut shares: Vec<f64> = vec![];
    let figures: Vec<(&Summary, RingingFigures)> = m
        .rows
        .iter()
        .filter_map(|r| Some((&r.summary, r.summary.metrics.check::<RingingFigures>()?)))
        .collect();
    if figures.is_empty() {
        return None;
    }
    for (_, f) in &figures {
        if !shares.iter().any(|s| (s / f.share - 1.0).abs() < 1e-9) {
            shares.push(f.share);
        }
    }
    let full_share = shares.iter().copied().fold(0.0, f64::max);
    let (mut xs, mut ys) = (vec![], vec![]);
    for (s, f) in figures {
        let at = (coordinate(f.flow_courant), coordinate(f.sound_courant));
        xs.push(f.flow_courant);
        ys.push(f.sound_courant);
        let point = maps
            .entry(method_label(s))
            .or_default()
            .entry(at)
            .or_default();
        if (f.share / full_share - 1.0).abs() < 1e-9 {
            point.full = Some(f);
        } else {
            point.halved = Some(f);
        }
    }
    let cats = |v: &mut Vec<f64>| {
        v.sort_by(f64::total_cmp);
        v.dedup_by(|a, b| coordinate(*a) == coordinate(*b));
        v.iter().map(|x| coordinate(*x)).collect::<Vec<_>>()
    };
    let (x_cats, y_cats) = (cats(&mut xs), cats(&mut ys));
    Some(Gathered {
        maps,
        full_share,
        seeds: shares.len(),
        x_cats,
        y_cats,
    })
}

/// One panel per method: each point's growth rate per 1000 steps.
fn panels(g: &Gathered) -> Vec<HeatPanel> {
    let (x_cats, y_cats) = (&g.x_cats, &g.y_cats);
    g.maps
        .iter()
        .map(|(method, points)| HeatPanel {
            title: method.clone(),
            cells: points
                .iter()
                .filter_map(|((x, y), p)| {
                    let f = p.full.as_ref()?;
                    let g = &f.growth;
                    let (colour, mut text) = match class(g.rate_per_step, g.window_end) {
                        5 => (CLASSES[5].1, "x".to_string()),
                        k => (
                            CLASSES[k].1,
                            format!("{:+.2}", 1e3 * g.rate_per_step.unwrap_or(0.0)),
                        ),
                    };
                    if p.halving_change().is_some_and(|c| c > HALVING_TOLERANCE) {
                        text.push('?');
                    }
                    Some(HeatCell {
                        x: x_cats.iter().position(|c| c == x)?,
                        y: y_cats.iter().position(|c| c == y)?,
                        colour,
                        text,
                    })
                })
                .collect(),
        })
        .collect()
}

/// Per method: its points, the unstable ones, the fastest growth and the
/// halved seed's agreement.
fn method_rows(maps: &Maps) -> Vec<(String, Vec<Cell>)> {
    maps.iter()
        .map(|(method, points)| {
            let full: Vec<(&(String, String), &RingingFigures)> = points
                .iter()
                .filter_map(|(at, p)| Some((at, p.full.as_ref()?)))
                .collect();
            let unstable = full
                .iter()
                .filter(|(_, f)| {
                    f.growth
                        .rate_per_step
                        .is_some_and(|r| r > UNSTABLE_PER_STEP)
                })
                .count();
            let fastest = full
                .iter()
                .filter(|(_, f)| f.growth.window_end != WindowEnd::NotFinite)
                .filter_map(|(at, f)| Some((*at, f.growth.rate_per_step?)))
                .max_by(|a, b| a.1.total_cmp(&b.1));
            let changes: Vec<f64> = points
                .values()
                .filter_map(MapPoint::halving_change)
                .collect();
            let within = changes.iter().filter(|c| **c <= HALVING_TOLERANCE).count();
            let largest = changes.iter().copied().fold(f64::NAN, f64::max);
            (
                String::new(),
                vec![
                    Cell::Text(escape(method)),
                    Cell::Num(full.len().to_string()),
                    Cell::Num(unstable.to_string()),
                    Cell::Num(fastest.map_or("-".into(), |f| format!("{:.3e}", f.1))),
                    Cell::Num(fastest.map_or("-".into(), |f| format!("{}, {}", f.0 .0, f.0 .1))),
                    Cell::Num(format!("{within} of {}", changes.len())),
                    Cell::Num(if largest.is_nan() {
                        "-".into()
                    } else {
                        format!("{:.1} %", 100.0 * largest)
                    }),
                ],
            )
        })
        .collect()
}

/// The ringing section: the map and a table per method.
/// (A matrix section: `matrix::MATRIX_SECTIONS`.)
pub fn ringing_map(m: &Matrix, out: &Path, page: &mut Page) -> Res {
    let Some(g) = gather(m) else {
        return Ok(());
    };
    let fig = HeatmapFigure {
        title: "Ringing map: growth of the perturbation's kinetic energy per 1000 steps".into(),
        x_label: "U dt / h".into(),
        y_label: "c dt / h".into(),
        x_cats: g.x_cats.clone(),
        y_cats: g.y_cats.clone(),
        panels: panels(&g),
        key: HeatKey::Legend(CLASSES.iter().map(|(l, c)| (l.to_string(), *c)).collect()),
    };
    page.h2("Ringing map");
    page.p(&format!(
        "Brackbill's ringing test (docs/physics.md section 7b): a uniform flow U through a periodic grid with a seed of {} |U| near the grid scale; the growth rate of E' (the kinetic energy about the drift), fitted over the second half of its linear window. Unstable: E' grows faster than {UNSTABLE_PER_STEP:e} per step. A cell marked ? moved by more than {:.0} % when the seed was halved ({}).",
        g.full_share,
        100.0 * HALVING_TOLERANCE,
        if g.seeds > 1 { "runs with both seeds" } else { "no halved seed in this matrix" }
    ));
    page.figure(
        &render(&fig, out, "ringing_map")?,
        "Growth rate of E' per 1000 steps by method over U dt / h and c dt / h (x: blew up or no rate; ?: the halved seed's rate differs by more than 10 %)",
    );
    let headers: Vec<String> = [
        "method",
        "points",
        "unstable (rate > 1e-3 / step)",
        "fastest growth (1 / step)",
        "at U dt / h, c dt / h",
        "halved seed: within 10 %",
        "halved seed: largest change",
    ]
    .map(String::from)
    .to_vec();
    page.table("ringing", &headers, &method_rows(&g.maps));
    Ok(())
}
