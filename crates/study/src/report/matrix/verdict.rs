//! The matrix page's opening verdict: how many cases ran and how they
//! ended, what failed or blew up (earliest first), what kicked (by the
//! cause of the first kick, earliest first), the best methods
//! (`methods::best_methods`) and the best cases.

use crate::report::data::{Class, Matrix, Row};
use crate::report::html::{escape, link, Page};
use crate::report::matrix::methods::best_methods;
use crate::report::plot::{short, Res};
use std::path::Path;
use study::output::summary::Status;

/// At most this many cases are named in one sentence of the verdict.
const NAMED: usize = 6;

/// "a (x), b (y) and 3 more" over the first `NAMED` items.
fn named_list(items: Vec<String>) -> String {
    let n = items.len();
    let mut shown: Vec<String> = items.into_iter().take(NAMED).collect();
    if n > NAMED {
        shown.push(format!("and {} more", n - NAMED));
    }
    shown.join(", ")
}

/// The case name, linked to its page when there is one.
fn linked(r: &Row) -> String {
    link(r.link.as_deref(), r.case())
}

fn with_status(rows: &[Row], status: Status) -> Vec<&Row> {
    rows.iter().filter(|r| r.status() == status).collect()
}

/// The page opens with what failed, what kicked and the best methods (a
/// matrix section: `matrix::MATRIX_SECTIONS`).
pub fn verdict(m: &Matrix, _out: &Path, page: &mut Page) -> Res {
    let rows = &m.rows;
    page.begin_section("verdict");
    page.h2("Verdict");
    page.p(&counts_sentence(rows));
    failures(rows, page);
    page.p(&kicks_sentence(rows));
    best_methods_sentence(m, page);
    best_cases_sentence(rows, page);
    page.end_section();
    Ok(())
}

/// "N cases ran: a survived without a kick, b kicked ...".
fn counts_sentence(rows: &[Row]) -> String {
    let count = |s: Status| with_status(rows, s).len();
    let kicked = rows.iter().filter(|r| r.summary.kicked()).count();
    let completed_after_a_kick = rows.iter().filter(|r| r.completed_after_a_kick()).count();
    format!(
        "{} cases ran: {} survived without a kick, {} kicked at least once ({} of them then completed), {} blew up, {} failed.",
        rows.len(),
        count(Status::Completed) - completed_after_a_kick,
        kicked,
        completed_after_a_kick,
        count(Status::BlewUp),
        count(Status::Failed)
    )
}

/// What failed to run and what blew up, or that nothing did.
fn failures(rows: &[Row], page: &mut Page) {
    let failed: Vec<String> = with_status(rows, Status::Failed)
        .iter()
        .map(|r| format!("{} ({})", linked(r), escape(&r.summary.reason)))
        .collect();
    let none_failed = failed.is_empty();
    if !none_failed {
        page.p(&format!("<b>Failed to run</b>: {}.", named_list(failed)));
    }
    let mut blew = with_status(rows, Status::BlewUp);
    blew.sort_by(|a, b| a.t_end().total_cmp(&b.t_end()));
    if !blew.is_empty() {
        page.p(&format!(
            "<b>Blew up</b>, earliest first: {}.",
            named_list(
                blew.iter()
                    .map(|r| format!("{} at t = {:.3} s", linked(r), r.t_end()))
                    .collect()
            )
        ));
    }
    if none_failed && blew.is_empty() {
        page.p("<b>No case failed or blew up.</b>");
    }
}

/// What kicked: by the cause of the first kick, and earliest first.
fn kicks_sentence(rows: &[Row]) -> String {
    let kicked: Vec<&Row> = rows.iter().filter(|r| r.summary.kicked()).collect();
    if kicked.is_empty() {
        return "<b>No case kicked.</b>".into();
    }
    let first_by = |c: Class| rows.iter().filter(|r| r.class() == c).count();
    let mut by_time = kicked.clone();
    by_time.sort_by(|a, b| a.t_first_kick().total_cmp(&b.t_first_kick()));
    format!(
        "<b>Kicked</b>: {} of {} cases; the first kick was an injection or a jump in {}, an inversion in {} and had the hallmark (the anomaly) in {}. Earliest first: {}.",
        kicked.len(),
        rows.len(),
        first_by(Class::InjectionFirst),
        first_by(Class::InversionFirst),
        first_by(Class::AnomalyFirst),
        named_list(
            by_time
                .iter()
                .map(|r| format!("{} at t = {:.3} s", linked(r), r.t_first_kick()))
                .collect()
        )
    )
}

/// The best methods (none when no method key varies).
fn best_methods_sentence(m: &Matrix, page: &mut Page) {
    let best = best_methods(m, 3);
    if best.is_empty() {
        return;
    }
    let items: Vec<String> = best
        .iter()
        .map(|b| {
            format!(
                "<b>{}</b> ({} of {} runs completed without a kick, median late departure {})",
                escape(&b.label),
                b.clean,
                b.runs,
                b.late.map_or("-".into(), short)
            )
        })
        .collect();
    page.p(&format!(
        "<b>Best methods</b> (most runs completed without a kick, then the lowest late hydrostatic departure): {}.",
        items.join("; ")
    ));
}

/// The three completed cases closest to hydrostatic at the end, those
/// without a kick first.
fn best_cases_sentence(rows: &[Row], page: &mut Page) {
    let mut ranked: Vec<&Row> = with_status(rows, Status::Completed)
        .into_iter()
        .filter(|r| r.hydro_late().is_finite())
        .collect();
    ranked.sort_by(|a, b| {
        (a.summary.kicked(), a.hydro_late())
            .partial_cmp(&(b.summary.kicked(), b.hydro_late()))
            .unwrap_or(std::cmp::Ordering::Equal)
    });
    if ranked.is_empty() {
        return;
    }
    page.p(&format!(
        "<b>Best cases</b> (completed, without a kick first, then closest to hydrostatic at the end, late rel. RMS): {}.",
        ranked
            .iter()
            .take(3)
            .map(|r| format!(
                "{} ({}{})",
                linked(r),
                short(r.hydro_late()),
                if r.summary.kicked() { ", kicked" } else { "" }
            ))
            .collect::<Vec<_>>()
            .join(", ")
    ));
}
