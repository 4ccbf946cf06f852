//! Controls of the energy ledger in both directions (docs/physics.md
//! section 4b), planted through a formulation's booked term: the monitor
//! reads the pressure-implicit step's view with that step's booking
//! changed (a test-only hook on the read-only view, the solver untouched).
//! A local addition the projection books as its own is an injection that
//! names the term; a zero-mean alternating term below the floor, which
//! credited step by step would ratchet past it, raises nothing.

use crate::common::*;
use monitor::{Cause, EventKind, Monitor, MonitorConfig};
use solver::*;

/// Pressure-implicit water at rest, 0.4 m wide and 0.2 m deep (h = 1 cm),
/// run 0.2 s so the start-up has settled; its monitor.
fn settled_implicit_water() -> (Solver, Monitor) {
    let mut s = resting_water(Formulation::PressureImplicit);
    let mut m = Monitor::new(MonitorConfig::default(), &s.view());
    while s.time() < 0.2 {
        s.step().unwrap();
        m.observe(&s.view());
    }
    (s, m)
}

#[test]
fn a_local_addition_the_projection_books_is_an_injection_naming_it() {
    let (mut s, mut m) = settled_implicit_water();
    assert!(m.events().is_empty(), "{:?}", m.events());
    s.step().unwrap();
    // A 2 x 2-cell block in the bulk gains 0.3 m/s upward; the projection
    // books the kinetic energy as its own (a negative dissipation).
    let view = s.view();
    let mut v = view.v.to_vec();
    let mut added = 0.0;
    for ((vel, x), m) in v.iter_mut().zip(view.x).zip(view.mass) {
        if (0.19..0.21).contains(&x.x) && (0.09..0.11).contains(&x.y) {
            let before = vel.norm_squared();
            vel.y += 0.3;
            added += 0.5 * m * (vel.norm_squared() - before);
        }
    }
    assert!(added > 0.0);
    let mut planted = view;
    planted.v = &v;
    planted.energy.kinetic += added;
    planted.energy.dissipated -= added;
    let mut projection = planted.projection.expect("the pressure-implicit step");
    projection.stats.dissipated_projection -= added;
    planted.projection = Some(projection);
    m.observe(&planted);
    let e = m
        .events()
        .iter()
        .find(|e| e.cause == Cause::Injection)
        .unwrap_or_else(|| panic!("no injection: {:?}", m.events()));
    assert_eq!(e.first_step, s.step_count());
    assert_eq!(e.evidence.booked_added.names(), ["projection"], "{e:?}");
    let centre = |r: &monitor::Region| [(r.x_min + r.x_max) / 2.0, (r.y_min + r.y_max) / 2.0];
    let [cx, cy] = centre(&e.region);
    assert!(
        (cx - 0.2).abs() < 0.04 && (cy - 0.1).abs() < 0.04,
        "{:?}",
        e.region
    );
    assert!(e.kind == EventKind::EnergyInjection || e.kind == EventKind::Kick);
}

#[test]
fn a_zero_mean_alternating_booked_term_raises_nothing() {
    let (mut s, mut m) = settled_implicit_water();
    let floor = m.report().injection_floor;
    let pump_before = m.report().energy_injected;
    // Every other step the projection books a removal of 0.6 floors that
    // the kinetic energy shows, and the next step puts it back, booked as
    // an addition: credited step by step, the window would gain 0.6 floors
    // a cycle and pass the floor within two.
    let amplitude = 0.6 * floor;
    let (mut worst, mut pump): (f64, f64) = (0.0, 0.0);
    for k in 0..60 {
        s.step().unwrap();
        let mut alternating = s.view();
        let mut projection = alternating.projection.expect("the pressure-implicit step");
        if k % 2 == 0 {
            alternating.energy.kinetic -= amplitude;
            alternating.energy.dissipated += amplitude;
            projection.stats.dissipated_projection += amplitude;
        } else {
            projection.stats.dissipated_projection -= amplitude;
        }
        alternating.projection = Some(projection);
        m.observe(&alternating);
        worst = worst.max(m.report().injection_window);
        pump = pump.max(m.report().energy_injected);
    }
    assert!(m.events().is_empty(), "{:?}", m.events());
    assert!(
        worst < floor,
        "window gain {worst:e} against the floor {floor:e}"
    );
    assert!(
        pump - pump_before < 0.1 * amplitude,
        "run gain {pump:e} from {pump_before:e}, amplitude {amplitude:e}"
    );
}

/// The sloshing tank of studies/slosh.toml (0.4 m wide, 0.2 m deep, mode
/// 1 standing wave of 5 mm), inviscid and incompressible (K = inf) under
/// the pressure-implicit step: the formulation gains energy spread over
/// the body (docs/findings), which the pump figure shows; no whole-body
/// injection event opens for it.
#[test]
fn the_inviscid_incompressible_slosh_raises_the_pump_figure_not_a_body_injection() {
    let mut method = method(ShapeKind::Bspline2, TransferKind::Apic);
    method.formulation = Formulation::PressureImplicit;
    let water = Material {
        k: f64::INFINITY,
        ..Material::new(1.0)
    };
    let mut scene = Scene {
        t_end: 4.1,
        initial: InitialState::Hydrostatic,
        ..water_box([0.4, 0.3], [0.0, 0.0, 0.4, 0.2], water, 9.81)
    };
    scene.bodies[0].flow = Some(solver::flows::Flow::StandingWave {
        amplitude: 0.005,
        mode: 1,
    });
    let mut s = Solver::new(SolverConfig {
        scene,
        method,
        perturb: vec![],
    })
    .unwrap();
    let wave = s.view().energy.kinetic;
    let mut m = Monitor::new(MonitorConfig::default(), &s.view());
    let mut pump: f64 = 0.0;
    while !s.finished() {
        s.step().unwrap();
        m.observe(&s.view());
        pump = pump.max(m.report().energy_injected);
    }
    assert!(
        pump > 0.5 * wave,
        "pump figure {pump:e} J/m, the wave's energy {wave:e} J/m"
    );
    let body: Vec<_> = m
        .events()
        .iter()
        .filter(|e| e.kind == EventKind::EnergyInjection)
        .collect();
    assert!(body.is_empty(), "{body:?}");
}
