#![allow(dead_code)]
use monitor::{Event, EventKind, Monitor, MonitorConfig};
use solver::*;

pub fn method(shape: ShapeKind, transfer: TransferKind) -> Method {
    let mut m = Method::baseline();
    m.shape = shape;
    m.transfer = transfer;
    m
}

/// A box of `size` (h = 1 cm, 2 x 2 per cell, zero stress) holding one
/// body of `material` over `rect`.
pub fn water_box(size: [f64; 2], rect: [f64; 4], material: Material, gravity: f64) -> Scene {
    Scene {
        size,
        cell: 0.01,
        ppc: 2,
        gravity,
        materials: vec![material],
        bodies: vec![Body {
            rect,
            material: String::new(),
            velocity: [0.0, 0.0],
            fraction: 1.0,
            phase: None,
            flow: None,
        }],
        ..Scene::default()
    }
}

/// Water at rest under `formulation` (quadratic B-spline, APIC): 0.4 m
/// wide and 0.2 m deep in a 0.3 m tall box (h = 1 cm, 1.5 MPa Tait,
/// 0.5 Pa s, hydrostatic start).
pub fn resting_water(formulation: Formulation) -> Solver {
    let mut method = method(ShapeKind::Bspline2, TransferKind::Apic);
    method.formulation = formulation;
    let scene = Scene {
        t_end: 1.0,
        initial: InitialState::Hydrostatic,
        ..water_box([0.4, 0.3], [0.0, 0.0, 0.4, 0.2], tait(1.5e6, 0.5), 9.81)
    };
    Solver::new(SolverConfig {
        scene,
        method,
        perturb: vec![],
    })
    .unwrap()
}

pub fn tait(k: f64, viscosity: f64) -> Material {
    let mut m = Material::tait(k);
    m.viscosity = viscosity;
    m
}

/// A cell block [i0, i1) x [j0, j1) as a perturbation region in metres.
pub fn region(h: f64, i0: usize, j0: usize, i1: usize, j1: usize) -> [f64; 4] {
    [i0 as f64 * h, j0 as f64 * h, i1 as f64 * h, j1 as f64 * h]
}

/// Runs `steps` steps from `start`, with `perturb` applied, under a clone of `monitor`.
pub fn run_window(
    cfg: &SolverConfig,
    start: &[u8],
    monitor: &Monitor,
    perturb: Vec<Perturb>,
    steps: u64,
) -> (Monitor, Solver) {
    let mut cfg = cfg.clone();
    cfg.scene.initial = InitialState::ZeroStress;
    cfg.perturb = perturb;
    let mut s = Solver::new(cfg).unwrap();
    s.restore(start).unwrap();
    let mut m = monitor.clone();
    for _ in 0..steps {
        s.step().unwrap();
        let r = m.observe(&s.view());
        assert!(r.blow_out.is_none(), "{:?}", r.blow_out);
    }
    (m, s)
}

/// Observes `view` with `push(t)` m/s added upward to the velocities of
/// the particles `pushed` marks (a test-only ramp on the read-only view,
/// the solver untouched; a particle past its end is not pushed), `v` and
/// `v_prev` its scratch; asserts no blow-out.
pub fn observe_pushed(
    m: &mut Monitor,
    view: StateView,
    pushed: &[bool],
    push: impl Fn(f64) -> f64,
    v: &mut Vec<Vec2>,
    v_prev: &mut Vec<Vec2>,
) {
    v.clear();
    v_prev.clear();
    for p in 0..view.x.len() {
        let (now, before) = if pushed.get(p).copied().unwrap_or(false) {
            (push(view.time), push(view.time - view.dt))
        } else {
            (0.0, 0.0)
        };
        v.push(view.v[p] + Vec2::new(0.0, now));
        v_prev.push(view.v_prev[p] + Vec2::new(0.0, before));
    }
    let mut ramped = view;
    (ramped.v, ramped.v_prev) = (v, v_prev);
    let r = m.observe(&ramped);
    assert!(r.blow_out.is_none(), "{:?}", r.blow_out);
}

/// Asserts that the first of `kicks` came within one judging interval
/// (half the 30 ms window) of a push's end at `push_end` and read the
/// push's 0.06 m/s.
pub fn assert_first_kick_by(kicks: &[Event], push_end: f64, dt: f64, tag: &str) {
    let first = kicks
        .first()
        .unwrap_or_else(|| panic!("{tag} (dt {dt}): missed"));
    let latest = push_end + 0.015 + 2.0 * dt;
    assert!(first.t <= latest, "{tag}: {first:?}");
    assert!(
        (0.02..=0.0601).contains(&first.jump_speed),
        "{tag}: {first:?}"
    );
}

pub fn fresh_monitor(s: &Solver) -> Monitor {
    Monitor::new(MonitorConfig::default(), &s.view())
}

pub fn events_after(m: &Monitor, step: u64) -> Vec<Event> {
    m.events()
        .iter()
        .filter(|e| e.first_step > step)
        .cloned()
        .collect()
}

/// Asserts the acceptance of an injected kick: a kick event at step s (or s+1)
/// whose first-step cells lie within the perturbed cells plus two, and no event
/// starting outside [s, s + window].
pub fn assert_detected(events: &[Event], s: u64, window: u64, cells: [usize; 4], tag: &str) {
    let [i0, j0, i1, j1] = cells;
    let kick = events
        .iter()
        .find(|e| e.kind == EventKind::Kick && (e.first_step == s || e.first_step == s + 1))
        .unwrap_or_else(|| panic!("{tag}: no kick at step {s}: {events:#?}"));
    let c = kick.cells;
    assert!(
        c.i_min + 2 >= i0 && c.j_min + 2 >= j0 && c.i_max <= i1 - 1 + 2 && c.j_max <= j1 - 1 + 2,
        "{tag}: first-step cells {c:?} outside perturbed {cells:?} + 2"
    );
    assert!(kick.peak_accel_g > 10.0, "{tag}: {kick:?}");
    // The push adds energy: a kick by cause, whatever the rule that found it.
    assert_eq!(kick.cause, monitor::Cause::Injection, "{tag}: {kick:?}");
    assert!(kick.is_kick());
    for e in events {
        assert!(
            e.first_step >= s && e.first_step <= s + window,
            "{tag}: event {} starts at {} outside [{s}, {}]: {e:?}",
            e.id,
            e.first_step,
            s + window
        );
    }
}

/// A Tait column at rest (K = 1.5 MPa, bspline2 APIC, hydrostatic start), its
/// step-0 checkpoint, a fresh monitor and the echo window 2L/c in steps.
pub struct Column {
    pub cfg: SolverConfig,
    pub start: Vec<u8>,
    pub monitor: monitor::Monitor,
    pub window: u64,
}

pub fn column() -> Column {
    let mut scene = Scene::dam_break(tait(1.5e6, 0.5));
    scene.size = [0.4, 0.6];
    scene.bodies[0].rect = [0.0, 0.0, 0.4, 0.4];
    scene.initial = InitialState::Hydrostatic;
    let cfg = SolverConfig {
        scene,
        method: method(ShapeKind::Bspline2, TransferKind::Apic),
        perturb: vec![],
    };
    let s = Solver::new(cfg.clone()).unwrap();
    let c = s.config().scene.materials[0].wave_speed(1.0);
    let window = (2.0 * 0.4 / c / s.next_dt()).ceil() as u64;
    Column {
        monitor: fresh_monitor(&s),
        start: s.checkpoint(),
        cfg,
        window,
    }
}
