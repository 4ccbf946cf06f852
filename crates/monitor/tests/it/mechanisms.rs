//! Planted mechanisms: a scene that forces M1, M2 or M3 gives it the
//! largest share of the event particles' velocity change, and the
//! decomposition closes to round-off (docs/physics.md section 4c).

use monitor::mechanisms::{Mechanisms, Shares};
use solver::*;

use crate::common;

fn method(shape: ShapeKind) -> Method {
    Method {
        shape,
        transfer: TransferKind::Flip,
        flip_alpha: 1.0,
        scheme: SchemeKind::Usl,
        dt: DtMode::Dynamic,
        ..Method::default()
    }
}

/// Shares over `steps` explained steps of `particles` (one more step
/// before them primes the cell-crossing memory).
fn shares(s: &mut Solver, particles: &[usize], steps: usize) -> Shares {
    let cfg = s.config().scene.clone();
    let rho0 = s.config().first_rho0();
    let mut m = Mechanisms::new(Vec2::from(cfg.origin), cfg.cell, rho0, cfg.gravity);
    m.prime(&s.step_explained(particles).unwrap());
    for _ in 0..steps {
        let parts = m.add(&s.step_explained(particles).unwrap());
        assert!(parts.rest_max < 1e-9, "closure {}", parts.rest_max);
    }
    let sh = m.shares();
    assert!((sh.split_sum() - 1.0).abs() < 1e-9, "{sh:?}");
    sh
}

fn nearest(s: &Solver, x: Vec2, except: Option<usize>) -> Vec<usize> {
    let v = s.view();
    let mut idx: Vec<usize> = (0..v.x.len()).filter(|&p| Some(p) != except).collect();
    idx.sort_by(|&a, &b| (v.x[a] - x).norm().total_cmp(&(v.x[b] - x).norm()));
    idx
}

/// The water of a column at rest under gravity (hydrostatic start).
fn column(shape: ShapeKind) -> Solver {
    let mut scene = common::water_box(
        [0.3, 0.4],
        [0.0, 0.0, 0.3, 0.3],
        common::tait(1.5e5, 0.0),
        9.81,
    );
    scene.initial = InitialState::Hydrostatic;
    Solver::new(SolverConfig {
        scene,
        method: method(shape),
        perturb: vec![],
    })
    .unwrap()
}

#[test]
fn m3_one_compressed_particle_in_a_quiet_column() {
    let mut s = column(ShapeKind::Bspline2);
    let centre = Vec2::new(0.155, 0.155);
    let q = nearest(&s, centre, None)[0];
    s.plant_j(q, 0.9);
    s.step().unwrap(); // its stress follows J at this step's stress update
    let around: Vec<usize> = nearest(&s, s.view().x[q], Some(q))[..8].to_vec();
    let sh = shares(&mut s, &around, 3);
    let (name, value) = sh.leading();
    assert_eq!(name, "M3 stress outlier", "{sh:?}");
    assert!(value > 0.5, "{sh:?}");
}

/// A particle of a column at rest planted 1e-5 h above the line y = 15 h,
/// moving down at 2e-3 h per step (it moves with the grid, at a share of
/// that): its first step's P2G finds it above the line, the next one below. The counted step is that next one, and its
/// parts for the 6 particles nearest the crossing point.
fn crossing(shape: ShapeKind) -> (monitor::mechanisms::StepParts, Shares) {
    let mut s = column(shape);
    let h = s.config().scene.cell;
    let q = nearest(&s, Vec2::new(0.1525, 0.1525), None)[0];
    let x = s.view().x[q];
    let dt = s.next_dt();
    s.plant_motion(
        q,
        Vec2::new(x.x, 15.0 * h + 1e-5 * h),
        Vec2::new(0.0, -2e-3 * h / dt),
    );
    let around: Vec<usize> = nearest(&s, Vec2::new(x.x, 15.0 * h), Some(q))[..6].to_vec();
    let mut m = Mechanisms::new(Vec2::zeros(), h, 1000.0, 9.81);
    m.prime(&s.step_explained(&around).unwrap());
    let parts = m.add(&s.step_explained(&around).unwrap());
    assert!(parts.rest_max < 1e-9);
    (parts, m.shares())
}

#[test]
fn m2_a_particle_crossing_a_cell_line_in_a_pressure_gradient() {
    let (parts, sh) = crossing(ShapeKind::Linear);
    assert_eq!(parts.crossers, 1, "{parts:?}");
    let (name, value) = sh.leading();
    assert_eq!(name, "M2 cell crossing", "{sh:?}");
    assert!(value > 0.3, "{sh:?}");
    // uGIMP's gradient is continuous: the same crossing gives its
    // neighbours a kick of 2 % of the linear one's sum |dv|^2 (measured).
    let (control, _) = crossing(ShapeKind::Gimp);
    assert_eq!(control.crossers, 1, "{control:?}");
    assert!(
        control.dv2 < 0.05 * parts.dv2,
        "uGIMP {} vs linear {}",
        control.dv2,
        parts.dv2
    );
}

#[test]
fn m1_a_lone_particle_in_the_corner_of_an_empty_cell() {
    // A compressed block, no gravity; one particle of it alone in the
    // corner of the empty cell beside the block's right edge.
    let scene = common::water_box(
        [0.4, 0.3],
        [0.0, 0.0, 0.2, 0.2],
        common::tait(1.5e5, 0.0),
        0.0,
    );
    let mut ps = scene::seed(&scene);
    let h = scene.cell;
    let m0 = ps.mass[0];
    let v0 = ps.vol0[0];
    ps.push(
        Vec2::new(0.2 + 0.04 * h, 0.1 + 0.04 * h),
        Vec2::zeros(),
        m0,
        v0,
        0,
    );
    let lone = ps.len() - 1;
    for p in 0..ps.len() {
        let j: f64 = 0.99;
        ps.f[p] = Mat2::identity() * j.sqrt();
        ps.j[p] = j;
        ps.vol[p] = j * ps.vol0[p];
    }
    let mut s = Solver::with_particles(
        SolverConfig {
            scene,
            method: method(ShapeKind::Linear),
            perturb: vec![],
        },
        ps,
    );
    s.step().unwrap(); // the stresses follow J
                       // Its own pressure pushes its light nodes off: one step, after which
                       // it has expanded and the block's edge carries it.
    let mut m = Mechanisms::new(Vec2::zeros(), h, 1000.0, 0.0);
    let parts = m.add(&s.step_explained(&[lone]).unwrap());
    assert!(
        parts.rest_max < 1e-9 && parts.min_node_share < 0.01,
        "{parts:?}"
    );
    let sh = m.shares();
    let (name, value) = sh.leading();
    assert_eq!(name, "M1 small-mass node", "{sh:?}");
    assert!(value > 0.4, "{sh:?}");
}

/// M4's drift in m/s is Galilean: one particle 0.01 m/s off a uniform flow
/// drifts the same from the grid at 0.01 and at 1 m/s (the grid carries
/// the flow exactly, its shapes summing to 1), while the ratio to the
/// particles' own speed falls by about the flows' ratio. The first is the
/// one events are compared by (over sqrt(g H) in the explanation).
#[test]
fn m4_drift_speed_is_the_same_on_a_slow_and_a_fast_flow() {
    let first_step = |u: f64| {
        let mut scene = common::water_box(
            [0.4, 0.3],
            [0.0, 0.0, 0.2, 0.2],
            common::tait(1.5e5, 0.0),
            0.0,
        );
        scene.bodies[0].velocity = [u, 0.0];
        let mut s = Solver::new(SolverConfig {
            scene,
            method: method(ShapeKind::Linear),
            perturb: vec![],
        })
        .unwrap();
        let h = s.config().scene.cell;
        let q = nearest(&s, Vec2::new(0.1025, 0.1025), None)[0];
        let x = s.view().x[q];
        s.plant_motion(q, x, Vec2::new(u + 0.01, 0.0));
        let around = nearest(&s, x, None)[..6].to_vec();
        let mut m = Mechanisms::new(Vec2::zeros(), h, 1000.0, 0.0);
        m.add(&s.step_explained(&around).unwrap())
    };
    let (slow, fast) = (first_step(0.01), first_step(1.0));
    assert!(slow.drift_speed > 1e-3, "{slow:?}");
    assert!(
        (slow.drift_speed - fast.drift_speed).abs() < 1e-9 * slow.drift_speed.max(1.0),
        "{} vs {}",
        slow.drift_speed,
        fast.drift_speed
    );
    assert!(
        slow.drift > 30.0 * fast.drift,
        "{} vs {}",
        slow.drift,
        fast.drift
    );
}

#[test]
fn the_cancellation_index_is_one_when_the_parts_agree_and_large_when_they_cancel() {
    use monitor::mechanisms::{cancellation, CANCELLING};
    let agree = Shares {
        internal: 0.7,
        jump: 0.3,
        ..Shares::default()
    };
    assert!((cancellation(&agree) - 1.0).abs() < 1e-12);
    // A burst read as internal force 145 against a transfer jump of -142
    // (and gravity -2): the parts cancel, no mechanism is named.
    let cancel = Shares {
        internal: 145.0,
        jump: -142.0,
        external: -2.0,
        ..Shares::default()
    };
    assert!((cancellation(&cancel) - 289.0).abs() < 1e-9);
    assert!(cancellation(&cancel) > CANCELLING);
}
