//! Clean physics raises no kick (K = 1.5 MPa Tait, quadratic B-spline, APIC,
//! USL, dynamic dt, 0.5 Pa s): a block falling 0.2 m onto the floor gives
//! impact events only, the dam break to 1 s (the surge hits the far wall at
//! about 0.3 s) gives no kick, and a hydrostatic column gives no event at all.

use crate::common;

use monitor::{Cause, Event};
use solver::*;

fn method() -> Method {
    Method {
        scheme: SchemeKind::Usl,
        dt: DtMode::Dynamic,
        ..common::method(ShapeKind::Bspline2, TransferKind::Apic)
    }
}

/// Runs to `t_end` under a fresh monitor; the events (the run must not stop).
fn events(scene: Scene, t_end: f64) -> Vec<Event> {
    let mut s = Solver::new(SolverConfig {
        scene,
        method: method(),
        perturb: vec![],
    })
    .unwrap();
    let mut m = common::fresh_monitor(&s);
    while s.time() < t_end {
        s.step().unwrap();
        let r = m.observe(&s.view());
        assert!(r.blow_out.is_none(), "{:?}", r.blow_out);
    }
    m.events().to_vec()
}

fn summary(events: &[Event]) -> Vec<(u64, Cause, f64, f64, f64)> {
    events
        .iter()
        .map(|e| {
            let v = &e.evidence;
            (
                e.first_step,
                e.cause,
                v.courant_before,
                e.energy_injected,
                v.energy_floor,
            )
        })
        .collect()
}

#[test]
fn a_falling_block_hitting_the_floor_is_an_impact() {
    let mut scene = Scene::dam_break(common::tait(1.5e6, 0.5));
    scene.bodies[0].rect = [0.3, 0.2, 0.5, 0.4];
    let events = events(scene, 0.5);
    eprintln!(
        "(first step, cause, Courant before, injected, floor): {:?}",
        summary(&events)
    );
    assert!(
        events.iter().all(|e| e.cause == Cause::Impact),
        "{:?}",
        summary(&events)
    );
}

#[test]
fn the_dam_break_to_one_second_has_no_kick() {
    let events = events(Scene::dam_break(common::tait(1.5e6, 0.5)), 1.0);
    eprintln!(
        "(first step, cause, Courant before, injected, floor): {:?}",
        summary(&events)
    );
    assert!(
        events.iter().all(|e| !e.is_kick()),
        "{:?}",
        summary(&events)
    );
}

#[test]
fn a_hydrostatic_column_for_one_second_has_no_event() {
    let mut scene = Scene::dam_break(common::tait(1.5e6, 0.5));
    scene.size = [0.4, 0.6];
    scene.bodies[0].rect = [0.0, 0.0, 0.4, 0.4];
    scene.initial = InitialState::Hydrostatic;
    let events = events(scene, 1.0);
    assert!(events.is_empty(), "{:?}", summary(&events));
}
