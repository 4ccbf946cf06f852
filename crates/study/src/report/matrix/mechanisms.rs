//! The matrix-level table of explained events by mechanism: every
//! `kick explain` record (CASE/explain/event_K/explain.json) among the
//! matrix's cases, by the smallest K's neighbourhood in time (collapse
//! t < 0.15 s, impact 0.15-0.6 s, late >= 0.6 s) and by K: how many, how
//! many replays matched, which mechanism leads (docs/physics.md section 4c)
//! and the median shares of the internal force and of M1-M3.

use crate::report::data::{median, Matrix, ParamKey};
use crate::report::html::{Cell, Page};
use crate::report::plot::Res;
use std::collections::BTreeMap;
use std::path::Path;
use study::replay::explain::record::ExplainedHead;

/// A mechanism leads an event when its share is at least this (else none).
pub const LEADS_FROM: f64 = monitor::mechanisms::NAMED_SHARE;
/// The time strata (s): collapse before the first, impact before the second.
pub const STRATA: (f64, f64) = (0.15, 0.6);
const LEADERS: [&str; 5] = [
    "M1 small-mass node",
    "M2 cell crossing",
    "M3 stress outlier",
    "none",
    "undecided",
];
/// The precursors named (docs/physics.md section 4c), counted per row.
const PRECURSORS: [&str; 3] = [
    "M1 small-mass node",
    "M2 cell crossing",
    "M3 stress outlier",
];

fn stratum(t: f64) -> &'static str {
    if t < STRATA.0 {
        "collapse"
    } else if t < STRATA.1 {
        "impact"
    } else {
        "late"
    }
}

/// One explained event's figures.
struct Explained {
    matched: bool,
    leader: usize,
    internal: f64,
    m: [f64; 3],
    /// The named precursor's index in `PRECURSORS`, if any; None also
    /// when the record has no precursors.
    precursor: Option<usize>,
    has_precursors: bool,
}

fn read(head: ExplainedHead) -> Option<Explained> {
    let sh = head.shares;
    let share = |v: Option<f64>| v.unwrap_or(f64::NAN);
    let m = [
        share(sh.small_mass_node),
        share(sh.cell_crossing),
        share(sh.stress_outlier),
    ];
    let (best, value) =
        m.iter().enumerate().fold(
            (3, f64::NEG_INFINITY),
            |a, (k, v)| if *v > a.1 { (k, *v) } else { a },
        );
    let cancelling = head
        .cancellation
        .is_some_and(|c| c > monitor::mechanisms::CANCELLING);
    let named = head.precursors.as_ref().map(|p| p.named.as_str());
    Some(Explained {
        matched: head.matched,
        leader: match () {
            _ if cancelling => 4,
            _ if value >= LEADS_FROM => best,
            _ => 3,
        },
        internal: share(sh.internal),
        m,
        precursor: named.and_then(|n| PRECURSORS.iter().position(|p| *p == n)),
        has_precursors: named.is_some(),
    })
}

/// The section (`matrix::MATRIX_SECTIONS`); nothing when no event
/// of the matrix was explained.
pub fn mechanism_table(m: &Matrix, _out: &Path, page: &mut Page) -> Res {
    let mut groups: BTreeMap<(u64, usize), Vec<Explained>> = BTreeMap::new();
    let mut k_of: BTreeMap<u64, f64> = BTreeMap::new();
    for r in &m.rows {
        let k = r
            .summary
            .params
            .iter()
            .find(|(key, _)| ParamKey::parse(key).is_bulk_modulus())
            .and_then(|(_, v)| v.as_f64())
            .unwrap_or(f64::NAN);
        for e in &r.summary.events {
            if let Some(x) = ExplainedHead::read(&r.dir, e.id).and_then(read) {
                let order = ["collapse", "impact", "late"]
                    .iter()
                    .position(|s| *s == stratum(e.t))
                    .unwrap_or(0);
                let key = k.to_bits();
                k_of.insert(key, k);
                groups.entry((key, order)).or_default().push(x);
            }
        }
    }
    if groups.is_empty() {
        return Ok(());
    }
    let mut keys: Vec<(u64, usize)> = groups.keys().copied().collect();
    keys.sort_by(|a, b| k_of[&a.0].total_cmp(&k_of[&b.0]).then(a.1.cmp(&b.1)));
    let med = |v: Vec<f64>| median(&v).map_or("-".into(), |x| format!("{x:.2}"));
    let row = |label: String, events: &[&Explained]| -> (String, Vec<Cell>) {
        let mut counts = [0usize; 5];
        let mut named = [0usize; 3];
        for e in events {
            counts[e.leader] += 1;
            if let Some(k) = e.precursor {
                named[k] += 1;
            }
        }
        let with_precursors = events.iter().filter(|e| e.has_precursors).count();
        let mut cells = vec![
            Cell::Text(label),
            Cell::Num(events.len().to_string()),
            Cell::Num(events.iter().filter(|e| e.matched).count().to_string()),
        ];
        cells.extend(counts.iter().map(|c| Cell::Num(c.to_string())));
        cells.push(Cell::Num(med(events.iter().map(|e| e.internal).collect())));
        for k in 0..3 {
            cells.push(Cell::Num(med(events.iter().map(|e| e.m[k]).collect())));
        }
        cells.push(Cell::Text(format!(
            "{} / {} / {} of {with_precursors}",
            named[0], named[1], named[2]
        )));
        (String::new(), cells)
    };
    let mut rows = vec![];
    for key in &keys {
        let events: Vec<&Explained> = groups[key].iter().collect();
        let label = format!(
            "K = {} Pa, {}",
            crate::report::plot::short(k_of[&key.0]),
            ["collapse", "impact", "late"][key.1]
        );
        rows.push(row(label, &events));
    }
    let all: Vec<&Explained> = groups.values().flatten().collect();
    rows.push(row("all".into(), &all));
    let headers = headers();
    page.h2("Explained events by mechanism");
    page.p(&format!(
        "Every event of this matrix that <code>kick explain</code> has explained (CASE/explain/event_K), by K and by time: collapse before {} s, impact before {} s, late after. A mechanism leads when its share of the kick's velocity change is the largest of M1-M3 and at least {LEADS_FROM}, else none, and none is decided when the split's parts cancel (index above {}). The precursor is what the event's particles showed over the quiet window before it against matched quiet regions of the same run, counted among the records that measured it (docs/physics.md section 4c).",
        STRATA.0,
        STRATA.1,
        monitor::mechanisms::CANCELLING
    ));
    page.table("mechanisms", &headers, &rows);
    Ok(())
}

/// The table's column headers.
fn headers() -> Vec<String> {
    let mut headers: Vec<String> = ["events by K and time", "explained", "replay matched"]
        .map(String::from)
        .to_vec();
    headers.extend(LEADERS.iter().map(|l| format!("leads: {l}")));
    headers.push("internal force share (median)".into());
    headers.extend(
        ["M1 share", "M2 share", "M3 share"]
            .iter()
            .map(|s| format!("{s} (median)")),
    );
    headers.push("precursor named: M1 / M2 / M3".into());
    headers
}

#[cfg(test)]
mod tests {
    use super::*;

    fn head(m1: f64, m3: f64, cancellation: f64, named: &str) -> ExplainedHead {
        serde_json::from_value(serde_json::json!({
            "matched": true,
            "shares": {"internal": 1.0, "small_mass_node": m1, "cell_crossing": 0.0, "stress_outlier": m3},
            "leading": {"mechanism": "", "share": null},
            "largest_part": {"part": "internal force", "share": 1.0},
            "cancellation": cancellation,
            "precursors": {"named": named},
        }))
        .unwrap()
    }

    #[test]
    fn an_event_leads_by_its_largest_share_unless_too_small_or_cancelling() {
        let e = read(head(0.4, 0.2, 1.0, "M1 small-mass node")).unwrap();
        assert_eq!(
            (e.leader, e.precursor, e.has_precursors),
            (0, Some(0), true)
        );
        let e = read(head(0.05, 0.08, 1.0, "none")).unwrap();
        assert_eq!(
            (e.leader, e.precursor),
            (3, None),
            "under {LEADS_FROM}: none"
        );
        let e = read(head(0.4, 0.9, 3.0, "no control")).unwrap();
        assert_eq!((e.leader, e.precursor), (4, None), "cancelling: undecided");
        // A record written before precursors were measured.
        let mut old = head(0.0, 0.5, 1.0, "");
        old.precursors = None;
        old.cancellation = None;
        let e = read(old).unwrap();
        assert_eq!((e.leader, e.has_precursors), (2, false));
    }
}
