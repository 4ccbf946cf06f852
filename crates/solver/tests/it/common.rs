#![allow(dead_code)]
use solver::*;

pub fn method(shape: ShapeKind, transfer: TransferKind, scheme: SchemeKind) -> Method {
    Method {
        shape,
        transfer,
        flip_alpha: 1.0,
        scheme,
        cfl: 0.2,
        dt: DtMode::Fixed,
        dt_value: None,
        j_update: JUpdate::Det,
        ..Method::default()
    }
}

pub fn box_scene(size: [f64; 2], rect: [f64; 4], material: Material, gravity: f64) -> Scene {
    Scene {
        origin: [0.0, 0.0],
        size,
        cell: 0.01,
        ppc: 2,
        t_end: 1.0,
        gravity,
        initial: InitialState::ZeroStress,
        periodic: [false, false],
        jitter: 0.0,
        seed: 0,
        bodies: vec![Body {
            rect,
            material: String::new(),
            velocity: [0.0, 0.0],
            fraction: 1.0,
            phase: None,
            flow: None,
        }],
        materials: vec![material],
        ..Scene::default()
    }
}

pub fn solver(scene: Scene, method: Method) -> Solver {
    Solver::new(SolverConfig {
        scene,
        method,
        perturb: vec![],
    })
    .expect("valid config")
}

/// A water column `depth` deep (rho0 1000, g 9.81): the largest
/// |p - rho0 g (depth - y)| / (rho0 g depth) over the particles (each
/// reads its cell pressure through the reconstructed gradient), and the
/// largest |v|.
pub fn hydrostatic_departure(s: &Solver, depth: f64) -> (f64, f64) {
    let v = s.view();
    let scale = 1000.0 * 9.81 * depth;
    let dp = (0..v.x.len())
        .map(|p| (v.pressure[p] - 1000.0 * 9.81 * (depth - v.x[p].y)).abs() / scale)
        .fold(0.0, f64::max);
    (dp, max_speed(&v))
}

/// The largest particle speed |v| of a view.
pub fn max_speed(v: &StateView) -> f64 {
    v.v.iter().map(|u| u.norm()).fold(0.0, f64::max)
}

/// Linear theory's period of mode 1 in the 0.4 m slosh tank filled to
/// `depth`: 2 pi / sqrt(g k tanh(k d)), k = pi / 0.4.
pub fn slosh_period(depth: f64) -> f64 {
    let k = std::f64::consts::PI / 0.4;
    2.0 * std::f64::consts::PI / (9.81 * k * (k * depth).tanh()).sqrt()
}

/// The error a refused config gets (None when it is accepted).
pub fn refusal(scene: Scene, method: Method) -> Option<ConfigError> {
    Solver::new(SolverConfig {
        scene,
        method,
        perturb: vec![],
    })
    .err()
}

pub const SHAPES: [ShapeKind; 5] = [
    ShapeKind::Linear,
    ShapeKind::Gimp,
    ShapeKind::Cpgimp,
    ShapeKind::Bspline2,
    ShapeKind::Bspline3,
];
/// Every family, for the tests that run the solver; the tests of per-axis
/// weights take `SHAPES` (CPDI's weights are not one tensor product).
pub const RUN_SHAPES: [ShapeKind; 6] = [
    ShapeKind::Linear,
    ShapeKind::Gimp,
    ShapeKind::Cpgimp,
    ShapeKind::Cpdi,
    ShapeKind::Bspline2,
    ShapeKind::Bspline3,
];
pub const TRANSFERS: [TransferKind; 3] =
    [TransferKind::Pic, TransferKind::Flip, TransferKind::Apic];
pub const SCHEMES: [SchemeKind; 3] = [SchemeKind::Usf, SchemeKind::Usl, SchemeKind::Musl];

/// The lattice checkerboard u_i = (-1)^(i + j) e_x on a grid of cell `h`,
/// interpolated with linear shapes at `x`.
pub fn lattice_checkerboard(x: Vec2, h: f64) -> Vec2 {
    let (i, j) = ((x.x / h).floor(), (x.y / h).floor());
    let (fx, fy) = (x.x / h - i, x.y / h - j);
    let mut sum = 0.0;
    for (a, wa) in [(0.0, 1.0 - fx), (1.0, fx)] {
        for (b, wb) in [(0.0, 1.0 - fy), (1.0, fy)] {
            let sign = if (i + a + j + b) as i64 % 2 == 0 {
                1.0
            } else {
                -1.0
            };
            sum += wa * wb * sign;
        }
    }
    Vec2::new(sum, 0.0)
}

/// One phase of a mixture: `rect` of a periodic, weightless 0.1 m box
/// (h = 1 cm, Tait K = 0.1 MPa) at volume fraction `n`
/// (`scene.body.fraction`) and true density `rho`.
pub fn phase(
    rect: [f64; 4],
    rho: f64,
    n: f64,
    method: Method,
    velocity: impl Fn(Vec2) -> Vec2,
) -> Solver {
    phase_under_gravity(rect, rho, n, method, velocity, 0.0)
}

/// The same under gravity (periodic in y too: the phase falls through the box).
pub fn phase_under_gravity(
    rect: [f64; 4],
    rho: f64,
    n: f64,
    method: Method,
    velocity: impl Fn(Vec2) -> Vec2,
    gravity: f64,
) -> Solver {
    let mut material = Material::tait(1e5);
    material.rho0 = rho;
    let mut scene = box_scene([0.1, 0.1], rect, material, gravity);
    scene.periodic = [true, true];
    scene.bodies[0].fraction = n;
    let mut ps = scene::seed(&scene);
    for p in 0..ps.len() {
        ps.v[p] = velocity(ps.x[p]);
    }
    Solver::with_particles(
        SolverConfig {
            scene,
            method,
            perturb: vec![],
        },
        ps,
    )
}
