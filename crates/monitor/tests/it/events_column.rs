//! Injected kicks in a column at rest (hydrostatic initial state, Tait
//! K = 1.5 MPa, quadratic B-spline APIC): a 1 m/s [[perturb]] on patches of
//! 1 x 1 to 5 x 5 cells, in the interior, at the walls, the floor and the free
//! surface, is logged as a kick at its step inside the patch plus two cells;
//! no event starts outside [s, s + 2L/c]; without the perturbation there is no
//! event at all. The injected energy is 1/2 m dv^2 of the perturbed particles.
//! All with the shipped default thresholds.

use monitor::Cause;
use monitor::{EventKind, Rule};
use solver::*;

use crate::common;

#[test]
fn injected_kicks_in_a_column_at_rest_are_found_where_and_when_they_happen() {
    let col = common::column();
    let s = 30;
    let steps = s + col.window + 100;
    let (quiet, _) = common::run_window(&col.cfg, &col.start, &col.monitor, vec![], steps);
    assert!(
        quiet.events().is_empty(),
        "column at rest: {:#?}",
        quiet.events()
    );
    // (cells [i0, j0, i1, j1), dv): interior, walls, floor, free surface; 1x1 to 5x5.
    let cases: [([usize; 4], [f64; 2], &str); 6] = [
        ([18, 15, 21, 18], [1.0, 0.0], "interior 3x3 along"),
        ([0, 10, 5, 15], [1.0, 0.0], "left wall 5x5 into the fluid"),
        (
            [37, 20, 40, 23],
            [-1.0, 0.0],
            "right wall 3x3 into the fluid",
        ),
        ([20, 0, 23, 3], [1.0, 0.0], "floor 3x3 along"),
        (
            [10, 37, 13, 40],
            [0.0, -1.0],
            "free surface 3x3 down into the fluid",
        ),
        ([30, 25, 31, 26], [0.0, 1.0], "interior 1x1 up"),
    ];
    for (cells, dv, tag) in cases {
        let perturb = vec![Perturb::at_step(
            s,
            common::region(0.01, cells[0], cells[1], cells[2], cells[3]),
            dv,
        )];
        let (m, _) = common::run_window(&col.cfg, &col.start, &col.monitor, perturb, steps);
        common::assert_detected(m.events(), s, col.window, cells, tag);
        let kick = m
            .events()
            .iter()
            .find(|e| e.kind == EventKind::Kick)
            .unwrap();
        assert!(
            kick.quiescent_before,
            "{tag}: the column was at rest before"
        );
        assert!(
            !kick.previously_deformed(),
            "{tag}: the column was never deformed"
        );
        assert!(kick.rules.contains(Rule::VelocityJump), "{tag}: {kick:?}");
    }
}

#[test]
fn injected_energy_is_half_m_dv_squared() {
    let col = common::column();
    let s = 10;
    let cells = [15, 10, 20, 15];
    let dv = [0.6, 0.8];
    let region = common::region(0.01, cells[0], cells[1], cells[2], cells[3]);
    let perturb = vec![Perturb::at_step(s, region, dv)];
    let (m, solver) = common::run_window(&col.cfg, &col.start, &col.monitor, perturb, s);
    let v = solver.view();
    let mass: f64 = (0..v.x.len())
        .filter(|&p| {
            let x = v.x[p];
            x.x >= region[0] && x.x <= region[2] && x.y >= region[1] && x.y <= region[3]
        })
        .map(|p| v.mass[p])
        .sum();
    assert!(mass > 0.0);
    let expected = 0.5 * mass * (dv[0] * dv[0] + dv[1] * dv[1]);
    let injected = m.report().energy_injected;
    assert!(
        (injected / expected - 1.0).abs() < 0.05,
        "injected {injected} vs 1/2 m dv^2 = {expected}"
    );
    let e = m
        .events()
        .iter()
        .find(|e| e.kind == EventKind::Kick)
        .unwrap();
    assert!((e.energy_injected / expected - 1.0).abs() < 0.05, "{e:?}");
}

/// The smallest push found: dv from 0.01 to 1 m/s on an interior 3 x 3 patch
/// of the column at rest. Every push of at least 0.03 m/s opens an event at
/// its step in its region with no other event (no false alarm; below
/// `jump_speed`, 0.02 m/s, the velocity-jump rule does not fire), and it is
/// a kick: the pushed energy 1/2 m dv^2 passes the event's floor, 1/2 m
/// `jump_speed`^2 (an injection), or else it is a velocity jump.
#[test]
fn the_smallest_push_found_and_when_it_counts_as_a_kick() {
    let col = common::column();
    let s = 30;
    let steps = s + col.window + 100;
    let cells = [18, 15, 21, 18];
    let mut table = vec![];
    for dv in [0.01, 0.015, 0.03, 0.05, 0.07, 0.1, 0.2, 0.5, 1.0] {
        let perturb = vec![Perturb::at_step(
            s,
            common::region(0.01, cells[0], cells[1], cells[2], cells[3]),
            [dv, 0.0],
        )];
        let (m, _) = common::run_window(&col.cfg, &col.start, &col.monitor, perturb, steps);
        let at_push: Vec<_> = m
            .events()
            .iter()
            .filter(|e| (s..=s + 1).contains(&e.first_step))
            .collect();
        let others = m.events().len() - at_push.len();
        let cause = at_push.iter().map(|e| e.cause).min();
        // Injected energy over floor.
        let margin = at_push
            .iter()
            .map(|e| e.energy_injected / e.evidence.energy_floor)
            .fold(f64::NAN, f64::max);
        table.push((dv, at_push.len(), others, cause, margin));
    }
    eprintln!("dv (m/s), events at the push, other events, cause, injected / floor");
    for row in &table {
        eprintln!("{row:?}");
    }
    for &(dv, at_push, others, cause, margin) in &table {
        assert_eq!(others, 0, "dv {dv}: a false alarm");
        if dv < 0.02 {
            assert_eq!(at_push, 0, "dv {dv}: below jump_speed");
        } else {
            assert!(at_push >= 1, "dv {dv}: not found");
            let expected = if margin > 1.0 {
                Cause::Injection
            } else {
                Cause::Jump
            };
            assert_eq!(cause, Some(expected), "dv {dv}: {margin}");
        }
    }
}
