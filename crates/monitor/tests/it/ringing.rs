//! Brackbill's ringing test on small periodic boxes (docs/physics.md
//! section 7b): a uniform flow U = 1 m/s along x through an N x N grid
//! (h = 1 cm, 2 x 2 per cell, Tait water, no gravity) with a seed of share
//! eps near the grid scale; the growth rate of E' (the kinetic energy about
//! the drift) per step, at U dt / h and c dt / h set by a fixed dt and K.

use monitor::ringing_growth::{GrowthFigures, PerturbationGrowth};
use solver::flows::Flow;
use solver::*;

const H: f64 = 0.01;

struct Point {
    /// U dt / h and c dt / h.
    flow_courant: f64,
    sound_courant: f64,
}

fn config(method: &Method, at: &Point, cells: usize, mode: u32, share: f64) -> SolverConfig {
    let l = cells as f64 * H;
    let dt = at.flow_courant * H / 1.0;
    let c = at.sound_courant * H / dt;
    let mut material = Material::tait(1000.0 * c * c);
    material.viscosity = 0.0;
    let scene = Scene {
        size: [l, l],
        cell: H,
        ppc: 2,
        gravity: 0.0,
        periodic: [true, true],
        t_end: 1e3,
        materials: vec![material],
        bodies: vec![Body {
            rect: [0.0, 0.0, l, l],
            material: String::new(),
            velocity: [1.0, 0.0],
            fraction: 1.0,
            phase: None,
            flow: Some(Flow::GridSeed { share, mode }),
        }],
        ..Scene::default()
    };
    let mut method = method.clone();
    method.dt = DtMode::Fixed;
    method.dt_value = Some(dt);
    SolverConfig {
        scene,
        method,
        perturb: vec![],
    }
}

fn growth(
    method: &Method,
    at: &Point,
    cells: usize,
    mode: u32,
    share: f64,
    steps: u64,
) -> GrowthFigures {
    let mut s = Solver::new(config(method, at, cells, mode, share)).unwrap();
    let mut g = PerturbationGrowth::with_capacity(steps as usize);
    g.observe(&s.view());
    for _ in 0..steps {
        if s.step().is_err() {
            break;
        }
        g.observe(&s.view());
        if g.closed() {
            break;
        }
    }
    g.figures()
}

fn methods() -> Vec<(String, Method)> {
    let mut out = vec![];
    for shape in [ShapeKind::Linear, ShapeKind::Bspline2] {
        for transfer in [
            TransferKind::Pic,
            TransferKind::Flip,
            TransferKind::Apic,
            TransferKind::Xpic,
        ] {
            let mut m = Method::baseline();
            m.shape = shape;
            m.transfer = transfer;
            m.xpic_order = 5;
            out.push((format!("{shape:?}-{transfer:?}"), m));
        }
    }
    out
}

/// E' grows faster than this per step: the map calls the point unstable.
const UNSTABLE_PER_STEP: f64 = 1e-3;

/// In the linear window E' scales with the seed's square, so the growth
/// rate of every method does not depend on the seed's amplitude: halving
/// it moves each rate by less than 10 %, at a point where linear FLIP
/// rings and at one where the quadratic B-spline's does.
#[test]
fn halving_the_seed_keeps_every_methods_growth_rate() {
    let points = [
        Point {
            flow_courant: 0.05,
            sound_courant: 0.3,
        },
        Point {
            flow_courant: 0.05,
            sound_courant: 0.6,
        },
    ];
    for at in &points {
        for (name, m) in methods() {
            let full = growth(&m, at, 16, 5, 1e-4, 2000);
            let half = growth(&m, at, 16, 5, 5e-5, 2000);
            let (a, b) = (full.rate_per_step.unwrap(), half.rate_per_step.unwrap());
            assert!(
                (b / a - 1.0).abs() < 0.1,
                "{name} at U dt/h {} c dt/h {}: {a:e} vs {b:e} ({full:?}, {half:?})",
                at.flow_courant,
                at.sound_courant
            );
        }
    }
}

/// FLIP rings where PIC does not: at a point of each shape's unstable
/// region FLIP's E' grows faster than the map's threshold while PIC's
/// decays.
#[test]
fn flip_grows_where_pic_decays() {
    let cases = [
        (
            ShapeKind::Linear,
            Point {
                flow_courant: 0.05,
                sound_courant: 0.3,
            },
        ),
        (
            ShapeKind::Bspline2,
            Point {
                flow_courant: 0.05,
                sound_courant: 0.6,
            },
        ),
    ];
    for (shape, at) in cases {
        let rate = |transfer| {
            let m = methods()
                .into_iter()
                .find(|(_, m)| m.shape == shape && m.transfer == transfer)
                .unwrap()
                .1;
            growth(&m, &at, 16, 5, 1e-4, 2000).rate_per_step.unwrap()
        };
        let (flip, pic) = (rate(TransferKind::Flip), rate(TransferKind::Pic));
        assert!(flip > UNSTABLE_PER_STEP, "{shape:?}: FLIP {flip:e}");
        assert!(pic < 0.0, "{shape:?}: PIC {pic:e}");
    }
}

/// A uniform flow alone is a discrete steady state: with no seed, E' stays
/// at round-off (below 1e-24 of the drift's energy over 500 steps), so
/// the seed is what grows.
#[test]
fn a_uniform_flow_alone_stays_uniform() {
    for (name, m) in methods() {
        let at = Point {
            flow_courant: 0.05,
            sound_courant: 0.3,
        };
        let mut cfg = config(&m, &at, 16, 5, 1e-4);
        cfg.scene.bodies[0].flow = None;
        let mut s = Solver::new(cfg).unwrap();
        for _ in 0..500 {
            s.step().unwrap();
        }
        let (e, drift) = monitor::ringing_growth::perturbation_energy(&s.view());
        assert!(e < 1e-24 * drift, "{name}: {e:e} of {drift:e}");
    }
}
