//! Event bookkeeping in the column at rest: two pushes at the same place a
//! few dozen steps apart are one episode when they fall within
//! `merge_seconds`, two events without it; `max_events` caps what is stored
//! and counts the rest; the monitor's saved state continues bit for bit.

use monitor::{EventKind, MonitorConfig};
use solver::*;

use crate::common;

const FIRST: u64 = 30;
const GAP: u64 = 40;

/// 1 m/s along the floor-parallel axis on the same 3 x 3 interior cells, twice.
fn two_pushes() -> Vec<Perturb> {
    let region = common::region(0.01, 18, 15, 21, 18);
    [FIRST, FIRST + GAP]
        .iter()
        .map(|&step| Perturb::at_step(step, region, [1.0, 0.0]))
        .collect()
}

fn kicks(m: &monitor::Monitor) -> usize {
    m.events()
        .iter()
        .filter(|e| e.kind == EventKind::Kick)
        .count()
}

#[test]
fn pushes_within_merge_seconds_are_one_event_and_two_without_it() {
    let col = common::column();
    let dt = Solver::new(col.cfg.clone()).unwrap().next_dt();
    let cfg = MonitorConfig::default();
    // The second push is well within merge_seconds.
    assert!((GAP as f64) * dt < 0.5 * cfg.merge_seconds);
    let steps = FIRST + GAP + 60;
    let (merged, _) = common::run_window(&col.cfg, &col.start, &col.monitor, two_pushes(), steps);
    assert_eq!(kicks(&merged), 1, "{:#?}", merged.events());
    let e = &merged.events()[0];
    assert_eq!(e.first_step, FIRST);
    assert!(e.last_step >= FIRST + GAP, "{e:?}");

    let mut shorter = col.monitor.clone();
    // A window shorter than the gap, still spanning a few steps.
    shorter.cfg.merge_seconds = 0.25 * GAP as f64 * dt;
    let (split, _) = common::run_window(&col.cfg, &col.start, &shorter, two_pushes(), steps);
    assert_eq!(kicks(&split), 2, "{:#?}", split.events());
    assert_eq!(split.events_dropped(), 0);

    let mut capped = shorter.clone();
    capped.cfg.max_events = 1;
    let (one, _) = common::run_window(&col.cfg, &col.start, &capped, two_pushes(), steps);
    assert_eq!(one.events().len(), 1, "{:#?}", one.events());
    assert_eq!(one.events()[0].first_step, FIRST);
    // The refused second episode is counted on each step it was flagged.
    assert!(one.events_dropped() >= 1);
}

#[test]
fn saved_monitor_state_continues_bit_for_bit() {
    let col = common::column();
    let mut cfg = col.cfg.clone();
    cfg.scene.initial = InitialState::ZeroStress;
    cfg.perturb = two_pushes();
    let mut s = Solver::new(cfg.clone()).unwrap();
    s.restore(&col.start).unwrap();
    let mut m = col.monitor.clone();
    let mid = FIRST + 10; // inside the first event, which is still open
    for _ in 0..mid {
        s.step().unwrap();
        m.observe(&s.view());
    }
    let (solver_bytes, monitor_bytes) = (s.checkpoint(), m.save_state());
    for _ in mid..FIRST + GAP + 60 {
        s.step().unwrap();
        m.observe(&s.view());
    }
    let mut s2 = Solver::new(cfg).unwrap();
    s2.restore(&solver_bytes).unwrap();
    let mut m2 = col.monitor.clone();
    m2.restore_state(&monitor_bytes).unwrap();
    for _ in mid..FIRST + GAP + 60 {
        s2.step().unwrap();
        m2.observe(&s2.view());
    }
    assert_eq!(s.state_hash(), s2.state_hash());
    assert_eq!(m.events(), m2.events());
    assert_eq!(m.report(), m2.report());
    assert!(!m.events().is_empty());
    // A flipped byte is refused by the checksum.
    let mut bad = monitor_bytes.clone();
    let k = bad.len() / 2;
    bad[k] ^= 1;
    assert!(col.monitor.clone().restore_state(&bad).is_err());
}
