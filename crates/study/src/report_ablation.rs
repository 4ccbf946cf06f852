//! The ablation table: one row per method (the `method.*` keys that vary),
//! labelled by what it changes from the most common value of each key (the
//! baseline), with the fraction of runs that kicked (by cause, and with the
//! hallmark), that blew up, and the survival time as median [min, max].

use crate::report_html::{Cell, Page};
use crate::report_matrix::{spread_text, Matrix, Row};
use crate::summary::Status;
use std::collections::BTreeMap;

/// For each varying `method.*` axis: its index and most common value.
fn baseline(m: &Matrix) -> Vec<(usize, String)> {
    m.axes
        .iter()
        .enumerate()
        .filter(|(_, k)| k.starts_with("method."))
        .map(|(i, _)| {
            let mut counts: BTreeMap<&String, usize> = BTreeMap::new();
            for r in &m.rows {
                *counts.entry(&r.params[i]).or_default() += 1;
            }
            let mode = counts
                .into_iter()
                .max_by_key(|(_, n)| *n)
                .map(|(v, _)| v.clone())
                .unwrap_or_default();
            (i, mode)
        })
        .collect()
}

/// What a run's method changes from the baseline ("baseline" when nothing).
fn label(m: &Matrix, base: &[(usize, String)], r: &Row) -> String {
    let changes: Vec<String> = base
        .iter()
        .filter(|(i, mode)| r.params[*i] != *mode)
        .map(|(i, _)| {
            let key = m.axes[*i].trim_start_matches("method.");
            format!("{key} = {}", r.params[*i])
        })
        .collect();
    if changes.is_empty() {
        "baseline".into()
    } else {
        changes.join(", ")
    }
}

fn percent(k: usize, n: usize) -> Cell {
    Cell::Num(format!("{:.0} %", 100.0 * k as f64 / n.max(1) as f64))
}

pub fn ablation_table(m: &Matrix, page: &mut Page) {
    let base = baseline(m);
    if base.is_empty() {
        return;
    }
    let mut groups: Vec<(String, Vec<&Row>)> = vec![];
    for r in &m.rows {
        let l = label(m, &base, r);
        match groups.iter_mut().find(|(g, _)| *g == l) {
            Some((_, rows)) => rows.push(r),
            None => groups.push((l, vec![r])),
        }
    }
    if groups.len() < 2 {
        return;
    }
    // The baseline first, then by name.
    groups.sort_by(|a, b| (a.0 != "baseline", &a.0).cmp(&(b.0 != "baseline", &b.0)));
    page.h2("Methods: which change removes the kick");
    page.p("One row per method, named by what it changes from the most common value of each varying method key. Over all its runs (every case and ensemble member): the share with at least one kick, with a kick of each cause, with a kick that has the hallmark (the anomaly proper), and that blew up; the time survived (a completed run counts its t_end) as median [min, max]; the median particle-steps per second.");
    let headers: Vec<String> = [
        "method",
        "runs",
        "kicked",
        "injection",
        "inversion",
        "anomaly",
        "blew up",
        "survived (s)",
        "particle-steps/s",
    ]
    .map(String::from)
    .to_vec();
    let rows: Vec<(String, Vec<Cell>)> = groups
        .iter()
        .map(|(l, runs)| {
            let n = runs.len();
            let with = |keep: &dyn Fn(&monitor::Event) -> bool| {
                runs.iter()
                    .filter(|r| r.summary.events.iter().any(keep))
                    .count()
            };
            let blew = runs
                .iter()
                .filter(|r| r.summary.status == Status::BlewUp)
                .count();
            let cells = vec![
                Cell::Text(l.clone()),
                Cell::Num(n.to_string()),
                percent(with(&|e| e.is_kick()), n),
                percent(with(&|e| e.cause == monitor::Cause::Injection), n),
                percent(with(&|e| e.cause == monitor::Cause::Inversion), n),
                percent(with(&|e| e.is_anomaly()), n),
                percent(blew, n),
                Cell::Num(spread_text(runs.iter().map(|r| r.summary.t_end), n, 2)),
                Cell::Num(spread_text(
                    runs.iter().map(|r| r.summary.particle_steps_per_s),
                    1,
                    0,
                )),
            ];
            (l.clone(), cells)
        })
        .collect();
    page.table("ablation", &headers, &rows);
}
