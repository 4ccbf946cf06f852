//! The matrix page's tables of runs: the ensembles (survival and first
//! kick as median [min, max] over each case's members) and every case with
//! its parameters, status and figures.

use crate::report::data::{spread, with_spread, Matrix, Row};
use crate::report::html::{escape, link, Cell, Page};
use crate::report::plot::{short, Res};
use std::path::Path;
use study::output::summary::Status;
use study::run::probes::surge_front::SurgeFrontFigures;

/// Per case of an ensemble: survival and first kick as median [min, max]
/// over its runs (a matrix section: `matrix::MATRIX_SECTIONS`).
pub fn ensemble_table(m: &Matrix, _out: &Path, page: &mut Page) -> Res {
    let mut groups: Vec<(&Vec<String>, Vec<&Row>)> = vec![];
    for r in &m.rows {
        match groups.iter_mut().find(|(p, _)| **p == r.params) {
            Some((_, rows)) => rows.push(r),
            None => groups.push((&r.params, vec![r])),
        }
    }
    if groups.iter().all(|(_, rows)| rows.len() < 2) {
        return Ok(());
    }
    page.h2("Ensembles");
    page.p("Each case ran as several members whose initial positions differ by a seeded jitter of at most scene.jitter h (scene.seed per member): survival and first-kick time as median [min, max] over the members.");
    let mut headers: Vec<String> = m.axes.iter().map(ToString::to_string).collect();
    headers.extend(
        [
            "runs",
            "blew up",
            "kicked",
            "survived (s)",
            "first kick (s)",
        ]
        .map(String::from),
    );
    let text =
        |v: Option<(f64, f64, f64)>, n: usize| v.map_or("-".into(), |s| with_spread(s, n, 3));
    let rows: Vec<(String, Vec<Cell>)> = groups
        .iter()
        .map(|(params, runs)| {
            let n = runs.len();
            let kicked: Vec<f64> = runs
                .iter()
                .map(|r| r.t_first_kick())
                .filter(|t| t.is_finite())
                .collect();
            let mut cells: Vec<Cell> = params.iter().map(|p| Cell::Num(escape(p))).collect();
            cells.extend([
                Cell::Num(n.to_string()),
                Cell::Num(
                    runs.iter()
                        .filter(|r| r.status() == Status::BlewUp)
                        .count()
                        .to_string(),
                ),
                Cell::Num(kicked.len().to_string()),
                Cell::Num(text(spread(runs.iter().map(|r| r.t_end())), n)),
                Cell::Num(text(spread(kicked.iter().copied()), kicked.len())),
            ]);
            (String::new(), cells)
        })
        .collect();
    page.table("ensembles", &headers, &rows);
    Ok(())
}

/// Every case: its parameters, status and figures, linked to its page (a
/// matrix section: `matrix::MATRIX_SECTIONS`).
pub fn case_table(m: &Matrix, _out: &Path, page: &mut Page) -> Res {
    page.h2("Cases");
    let mut headers = vec!["case".to_string()];
    headers.extend(m.axes.iter().map(ToString::to_string));
    headers.extend(
        [
            "status",
            "t end (s)",
            "first kick (s)",
            "hydro late",
            "its floor",
            "excess over the floor",
            "of it not explained by accelerations",
            "checkerboard of cell means, late",
            "nodal checkerboard, late",
            "front error (Z)",
            "wall (s)",
        ]
        .map(String::from),
    );
    let cell = |v: Option<f64>| Cell::Num(v.filter(|v| v.is_finite()).map_or("-".into(), short));
    let rows: Vec<(String, Vec<Cell>)> = m
        .rows
        .iter()
        .map(|r| {
            let s = &r.summary;
            let mut cells = vec![Cell::Text(link(r.link.as_deref(), r.case()))];
            cells.extend(r.params.iter().map(|p| Cell::Num(escape(p))));
            cells.extend([
                Cell::Text(s.status.as_str().into()),
                Cell::Num(format!("{:.3}", s.t_end)),
                cell(s.metrics.t_first_kick),
                cell(s.metrics.figure("hydro_rel_rms_late")),
                cell(s.metrics.figure("hydro_floor_late")),
                cell(s.metrics.figure("hydro_excess_late")),
                cell(s.metrics.figure("hydro_unexplained_rel_rms_late")),
                cell(s.metrics.figure("checkerboard_means_late")),
                cell(s.metrics.figure("checkerboard_nodal_late")),
                cell(
                    s.metrics
                        .check::<SurgeFrontFigures>()
                        .and_then(|c| c.rms_error),
                ),
                Cell::Num(format!("{:.1}", s.wall_s)),
            ]);
            (format!("case-row {}", r.css_class()), cells)
        })
        .collect();
    page.table("cases", &headers, &rows);
    Ok(())
}
