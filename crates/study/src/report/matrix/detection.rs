//! The detection table on the matrix page of a `kick calibrate` folder:
//! per case, placement and patch size, the smallest planted speed the
//! detector found, the largest it missed, the delay to detection, and the
//! kicks away from the patches (`study::replay::calibrate`).

use crate::report::data::Matrix;
use crate::report::html::{escape, link, Cell, Page};
use crate::report::plot::Res;
use std::path::Path;
use study::replay::calibrate::{Detection, DetectionRow};

/// (A matrix section: `matrix::MATRIX_SECTIONS`.) Nothing outside a
/// calibration folder: the page is written into DIR/report, and
/// detection.json sits in DIR.
pub fn detection_table(m: &Matrix, out: &Path, page: &mut Page) -> Res {
    let Some(d) = out.parent().and_then(Detection::read) else {
        return Ok(());
    };
    page.h2("Detection of planted kicks");
    let s = &d.spec;
    let how = match s.bisect {
        Some([lo, hi]) => format!(
            "the smallest speed found is bisected between {lo} and {hi} m/s to a ratio of {}",
            s.ratio
        ),
        None => format!("planted at {:?} m/s", s.dv),
    };
    page.p(&escape(&format!(
        "Patches planted at t = {} s ({:?}) and judged over {} s; {how}. \
         Twins {:.0} s and planted runs {:.0} s of wall time.",
        s.plant_t, s.direction, s.window, d.twins_wall_s, d.planted_wall_s
    )));
    let headers: Vec<String> = [
        "case",
        "place",
        "cells",
        "smallest found (m/s)",
        "largest missed (m/s)",
        "delay (s)",
        "cause",
        "runs",
        "twin kicks",
        "false alarms",
    ]
    .map(String::from)
    .to_vec();
    let rows: Vec<(String, Vec<Cell>)> = d.rows.iter().map(|r| row(m, r)).collect();
    page.table("detection", &headers, &rows);
    Ok(())
}

fn row(m: &Matrix, r: &DetectionRow) -> (String, Vec<Cell>) {
    let num = |v: Option<f64>, unit: &str| {
        Cell::Num(v.map_or_else(|| "-".into(), |x| format!("{x:.3}{unit}")))
    };
    let href = m
        .rows
        .iter()
        .find(|row| row.case() == r.case)
        .and_then(|row| row.link.as_deref());
    let case = link(href, &r.case);
    let place = if r.placed {
        escape(&r.place)
    } else {
        format!("{} (no patch qualified)", escape(&r.place))
    };
    let class = if r.dv_found.is_none() { "blew_up" } else { "" };
    (
        class.to_string(),
        vec![
            Cell::Text(case),
            Cell::Text(place),
            Cell::Num(r.cells.to_string()),
            num(r.dv_found, ""),
            num(r.dv_missed, ""),
            num(r.delay_s, ""),
            Cell::Text(escape(r.cause.as_deref().unwrap_or("-"))),
            Cell::Num(r.runs.to_string()),
            Cell::Num(r.twin_kicks.to_string()),
            Cell::Num(r.false_alarms.to_string()),
        ],
    )
}
