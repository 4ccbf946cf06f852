//! The detection table on the matrix page of a `kick calibrate` folder:
//! per case, placement and patch size, the smallest planted speed the
//! detector found, the largest it missed, the delay to detection, and the
//! kicks away from the patches (`study::replay::calibrate`).

use crate::report::data::{spread, Matrix};
use crate::report::html::{escape, link, Cell, Page};
use crate::report::plot::Res;
use monitor::stats::median_with_infinities;
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
    let push = match s.duration {
        Some(t) => format!("each speed spread over {t} s as a constant acceleration"),
        None => "each speed added at once".into(),
    };
    let least = match s.min_particles {
        Some(m) => format!("at least {m} particles"),
        None => "at least each case's monitor.min_cluster_particles".into(),
    };
    page.p(&escape(&format!(
        "Patches planted at t = {} s ({:?}, {push}; patches of {least}) and judged over {} s; {how}. \
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
    sites_tables(&d.rows, page);
    Ok(())
}

/// Where a study plants several patches of one placement (an ensemble of
/// sites, as a state that differs per method needs), each case's sites
/// summed up, and each placement's spread across the cases: the instrument
/// is the same when the largest case median is within 2 times the smallest.
fn sites_tables(rows: &[DetectionRow], page: &mut Page) {
    let groups = site_groups(rows);
    if groups
        .iter()
        .all(|g| g.found.len() + g.unfound + g.masked <= 1)
    {
        return;
    }
    let text = |v: Option<(f64, f64, f64)>| {
        v.map_or("-".into(), |(m, lo, hi)| {
            format!("{m:.3} [{lo:.3}, {hi:.3}]")
        })
    };
    let rows_out: Vec<(String, Vec<Cell>)> = groups
        .iter()
        .map(|g| {
            let n = g.found.len() + g.unfound;
            let cells = vec![
                Cell::Text(escape(&g.case)),
                Cell::Text(escape(&g.place)),
                Cell::Num(g.cells.to_string()),
                Cell::Num(format!("{} of {n}", g.found.len())),
                Cell::Num(g.masked.to_string()),
                Cell::Num(text(spread(g.found.iter().copied()))),
            ];
            (String::new(), cells)
        })
        .collect();
    let headers = [
        "case",
        "place",
        "cells",
        "distinct sites found",
        "masked",
        "smallest found, median [min, max] (m/s)",
    ]
    .map(String::from)
    .to_vec();
    page.p("Over the sites of each placement. A site masked by the twin's own event there, or where no patch qualified, is judged at no speed. The case medians below count a site where no planted speed was found as above every speed found; a case whose median is such a site (half or more of its sites) is counted apart, and the spread is then unbounded:");
    page.table("detection_sites", &headers, &rows_out);
    let across = case_medians(&groups);
    let rows_out: Vec<(String, Vec<Cell>)> = across
        .iter()
        .map(|(place, cells, v)| {
            let finite = v.iter().filter(|x| x.is_finite());
            let (lo, hi) = finite.fold((f64::INFINITY, 0.0f64), |(a, b), &x| (a.min(x), b.max(x)));
            let unfound = v.iter().filter(|x| x.is_infinite()).count();
            let cells = vec![
                Cell::Text(escape(place)),
                Cell::Num(cells.to_string()),
                Cell::Num(v.len().to_string()),
                Cell::Num(unfound.to_string()),
                Cell::Num(if lo <= hi {
                    format!("{lo:.3} - {hi:.3}")
                } else {
                    "-".into()
                }),
                Cell::Num(if lo <= hi && unfound == 0 {
                    format!("{:.2}", hi / lo)
                } else {
                    "unbounded".into()
                }),
            ];
            (String::new(), cells)
        })
        .collect();
    let headers = [
        "place",
        "cells",
        "cases",
        "cases with half or more unfound",
        "case medians (m/s)",
        "largest / smallest",
    ]
    .map(String::from)
    .to_vec();
    page.table("detection_across", &headers, &rows_out);
}

/// Per placement and size, each case's median over its judged sites, a
/// site where no speed was found counting as infinite.
fn case_medians(groups: &[SiteGroup]) -> Vec<(String, usize, Vec<f64>)> {
    let mut across: Vec<(String, usize, Vec<f64>)> = vec![];
    for g in groups {
        let mut judged = g.found.clone();
        judged.extend(std::iter::repeat_n(f64::INFINITY, g.unfound));
        let Some(median) = median_with_infinities(&judged) else {
            continue;
        };
        match across
            .iter_mut()
            .find(|(p, c, _)| *p == g.place && *c == g.cells)
        {
            Some((_, _, v)) => v.push(median),
            None => across.push((g.place.clone(), g.cells, vec![median])),
        }
    }
    across
}

/// The rows of one case, placement and size.
struct SiteGroup {
    case: String,
    place: String,
    cells: usize,
    found: Vec<f64>,
    /// Judged sites where no planted speed was found ...
    unfound: usize,
    /// ... and sites the twin's own event masked.
    masked: usize,
}

/// Sites that resolved to the same patch (the one block that qualified
/// nearest to several points) count once.
fn site_groups(rows: &[DetectionRow]) -> Vec<SiteGroup> {
    let mut groups: Vec<SiteGroup> = vec![];
    for (k, r) in rows.iter().enumerate() {
        let same = |o: &DetectionRow| {
            o.case == r.case && o.place == r.place && o.cells == r.cells && o.region == r.region
        };
        if !r.placed || (r.region.is_some() && rows[..k].iter().any(same)) {
            continue;
        }
        let at = groups
            .iter()
            .position(|g| g.case == r.case && g.place == r.place && g.cells == r.cells);
        let g = match at {
            Some(k) => &mut groups[k],
            None => {
                groups.push(SiteGroup {
                    case: r.case.clone(),
                    place: r.place.clone(),
                    cells: r.cells,
                    found: vec![],
                    unfound: 0,
                    masked: 0,
                });
                groups.last_mut().expect("just pushed")
            }
        };
        match (r.masked, r.dv_found) {
            (true, _) => g.masked += 1,
            (false, Some(v)) => g.found.push(v),
            (false, None) => g.unfound += 1,
        }
    }
    groups
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
    let place = match (r.placed, r.masked) {
        (false, _) if r.shares.is_some() => format!(
            "{} (shares the patch of placement {}, counted from 0)",
            escape(&r.place),
            r.shares.unwrap_or_default()
        ),
        (false, _) => format!("{} (no patch qualified)", escape(&r.place)),
        (true, true) => format!("{} (masked: the twin's own event there)", escape(&r.place)),
        (true, false) => escape(&r.place),
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

#[cfg(test)]
mod tests {
    use super::*;

    fn row(case: &str, place: &str, dv_found: Option<f64>) -> DetectionRow {
        DetectionRow {
            case: case.into(),
            t_plant_s: 2.0,
            place: place.into(),
            cells: 2,
            dv_found,
            dv_missed: None,
            delay_s: None,
            cause: None,
            runs: 7,
            placed: true,
            masked: false,
            shares: None,
            region: None,
            step: None,
            particles: None,
            predicted_dv: None,
            twin_kicks: 0,
            false_alarms: 0,
        }
    }

    #[test]
    fn sites_of_a_placement_give_each_case_a_median_and_the_cases_a_spread() {
        let mut rows = vec![
            row("a", "bulk", Some(0.02)),
            row("a", "bulk", Some(0.04)),
            row("a", "bulk", Some(0.03)),
            row("a", "surface", None),
            row("b", "bulk", Some(0.05)),
            row("b", "bulk", None),
            row("b", "bulk", Some(0.07)),
            row("b", "bulk", Some(0.07)),
            row("b", "bulk", None),
            row("b", "bulk", None),
        ];
        // Two resolved to the same patch: it counts once.
        rows[6].region = Some([0.1, 0.0, 0.12, 0.02]);
        rows[7].region = Some([0.1, 0.0, 0.12, 0.02]);
        // One masked by the twin's own event, one where no patch qualified.
        rows[8].masked = true;
        rows[9].placed = false;
        let groups = site_groups(&rows);
        assert_eq!(groups.len(), 3);
        assert_eq!((groups[0].found.len(), groups[0].unfound), (3, 0));
        let b = &groups[2];
        assert_eq!((b.found.len(), b.unfound, b.masked), (2, 1, 1));
        let across = case_medians(&groups);
        let (place, cells, medians) = &across[0];
        assert_eq!((place.as_str(), *cells), ("bulk", 2));
        // b: 0.05, 0.07 and a miss, which counts above both: median 0.07.
        assert_eq!(medians.len(), 2);
        assert!(
            (medians[0] - 0.03).abs() < 1e-12 && (medians[1] - 0.07).abs() < 1e-12,
            "{medians:?}"
        );
        // The surface found nothing at its one site: mostly unfound.
        assert_eq!(across[1].0, "surface");
        assert_eq!(across[1].2, vec![f64::INFINITY]);
    }
}
