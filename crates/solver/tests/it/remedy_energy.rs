//! Each remedy's energy report (`Solver::remedy_energy`) against an
//! independent recomputation: two solvers cloned from the same state, one
//! with the remedy and one without (`set_method`), stepped once; the
//! difference between them is what the remedy did. Agreement to 1e-12 of
//! the total energy, on a jittered dam break a few steps in, where each
//! remedy is checked to act (its change well above that tolerance).

#![allow(clippy::needless_range_loop)]

use crate::common;

use solver::remedies::{
    artificial_viscosity, bulk_damping, cell_dilatation, f_reset, grid_damping, j_bar,
    min_node_mass, null_space_filter, pic_damping, pressure_smoothing, shifting, speed_cap,
    volume_relaxation, RemedySettings,
};
use solver::shapes::Shape;
use solver::*;

/// Agreement required, relative to the total energy.
const TOL: f64 = 1e-12;
/// Steps taken before the compared step.
const STEPS: usize = 30;
const G: f64 = 9.81;

/// A water column (0.1 x 0.12 m) in the corner of a 0.3 x 0.2 m box, h = 1
/// cm, 2 x 2 ppc, Tait K = 20 kPa, a little viscosity, every particle moved
/// by up to 0.15 l per axis (so that the packing, J and the velocities are
/// disordered), with velocities of up to `noise` (m/s) per axis added at
/// random.
fn dam(method: Method, noise: f64) -> Solver {
    let mut material = Material::tait(2e4);
    material.viscosity = 0.01;
    let scene = common::box_scene([0.3, 0.2], [0.0, 0.0, 0.1, 0.12], material, G);
    let l = scene.cell / scene.ppc as f64;
    let mut ps = solver::scene::seed(&scene);
    let mut state = 11u64;
    for x in ps.x.iter_mut() {
        for k in 0..2 {
            x[k] += 0.15 * l * (2.0 * solver::scene::uniform01(&mut state) - 1.0);
        }
    }
    for v in ps.v.iter_mut() {
        for k in 0..2 {
            v[k] = noise * (2.0 * solver::scene::uniform01(&mut state) - 1.0);
        }
    }
    let cfg = SolverConfig {
        scene,
        method,
        perturb: vec![],
    };
    Solver::with_particles(cfg, ps)
}

/// Quadratic B-splines, FLIP (pure), USL: the stress is the step's last
/// stage and nothing changes the velocities after G2P but the remedies.
fn base() -> Method {
    common::method(ShapeKind::Bspline2, TransferKind::Flip, SchemeKind::Usl)
}

fn with(set: impl FnOnce(&mut RemedySettings)) -> Method {
    let mut m = base();
    set(&mut m.remedies);
    m
}

/// The dam break `STEPS` steps into a run with `run`, then two copies:
/// one with `on`, one with `off`.
fn pair(run: Method, on: Method, off: Method) -> (Solver, Solver) {
    pair_noisy(run, on, off, 0.0)
}

/// `pair` with velocity noise in the initial state.
fn pair_noisy(run: Method, on: Method, off: Method, noise: f64) -> (Solver, Solver) {
    let mut s = dam(run, noise);
    for _ in 0..STEPS {
        s.step().unwrap();
    }
    let mut with = s.clone();
    with.set_method(on).unwrap();
    let mut without = s;
    without.set_method(off).unwrap();
    (with, without)
}

/// The one report of remedy `key` for the last step.
/// The energy `key` changed in the last step (among several remedies).
fn reported_of(s: &Solver, key: &str) -> EnergyChange {
    s.remedy_energy()
        .find(|(k, _)| *k == key)
        .map_or(EnergyChange::default(), |(_, e)| e)
}

fn reported(s: &Solver, key: &str) -> EnergyChange {
    let all: Vec<(&str, EnergyChange)> = s.remedy_energy().collect();
    assert_eq!(all.len(), 1, "{all:?}");
    assert_eq!(all[0].0, key);
    all[0].1
}

/// Asserts agreement to `TOL` of `total`, and that the change is at least
/// `acts` of it (the remedy acted); returns the relative error.
fn agree(name: &str, reported: f64, recomputed: f64, total: f64, acts: f64) -> f64 {
    let err = (reported - recomputed).abs() / total.abs();
    eprintln!(
        "{name}: reported {reported:.6e}, recomputed {recomputed:.6e} ({:.2e} of the total), relative error {err:.2e}",
        recomputed / total
    );
    assert!(
        err <= TOL,
        "{name}: {reported} vs {recomputed} (total {total})"
    );
    assert!(
        recomputed.abs() >= acts * total.abs(),
        "{name}: the remedy hardly acted ({recomputed} of {total})"
    );
    err
}

/// sum 1/2 m |v|^2 of the view's velocities (what G2P and the after-G2P
/// hooks left).
fn kinetic(s: &Solver) -> f64 {
    let v = s.view();
    v.mass
        .iter()
        .zip(v.v)
        .map(|(m, v)| 0.5 * m * v.norm_squared())
        .sum()
}

#[test]
fn pic_damping_reports_the_kinetic_energy_the_blend_takes_from_flip() {
    let on = with(|r| r.pic_damping = Some(pic_damping::Settings { time: 2e-3 }));
    let (mut a, mut b) = pair(on.clone(), on, base());
    a.step().unwrap();
    b.step().unwrap();
    let e = reported(&a, "pic_damping");
    assert_eq!((e.stored, e.gravitational, e.work), (0.0, 0.0, 0.0));
    let (va, vb) = (a.view(), b.view());
    let recomputed: f64 = (0..va.v.len())
        .map(|p| 0.5 * va.mass[p] * (va.v[p].norm_squared() - vb.v[p].norm_squared()))
        .sum();
    assert!(recomputed < 0.0, "PIC's share damps");
    agree(
        "pic_damping",
        e.kinetic,
        recomputed,
        a.energy().total(),
        1e-6,
    );
}

#[test]
fn the_null_space_filter_reports_the_kinetic_energy_it_changes() {
    let on = with(|r| r.null_space_filter = Some(null_space_filter::Settings {}));
    // Velocity noise the grid cannot see, kept by FLIP in a run without it.
    let (mut a, mut b) = pair_noisy(base(), on, base(), 0.05);
    a.step().unwrap();
    b.step().unwrap();
    let e = reported(&a, "null_space_filter");
    assert_eq!((e.stored, e.gravitational, e.work), (0.0, 0.0, 0.0));
    let recomputed = a.energy().kinetic - b.energy().kinetic;
    assert_eq!(a.energy().kinetic, kinetic(&a));
    agree(
        "null_space_filter",
        e.kinetic,
        recomputed,
        a.energy().total(),
        1e-8,
    );
}

#[test]
fn shifting_reports_the_gravitational_energy_of_its_moves() {
    let on = with(|r| {
        r.shifting = Some(shifting::Settings {
            time: 0.01,
            ..Default::default()
        })
    });
    let (mut a, mut b) = pair(on.clone(), on, base());
    a.step().unwrap();
    b.step().unwrap();
    let e = reported(&a, "shifting");
    assert_eq!((e.kinetic, e.stored, e.work), (0.0, 0.0, 0.0));
    let (va, vb) = (a.view(), b.view());
    let recomputed: f64 = G
        * (0..va.x.len())
            .map(|p| va.mass[p] * (va.x[p].y - vb.x[p].y))
            .sum::<f64>();
    let moved = (0..va.x.len())
        .map(|p| (va.x[p] - vb.x[p]).norm())
        .fold(0.0, f64::max);
    assert!(moved > 1e-6, "largest shift {moved} m");
    agree(
        "shifting",
        e.gravitational,
        recomputed,
        a.energy().total(),
        1e-7,
    );
}

/// A remedy that changes J (carried): its report is the stored energy the
/// run with it has over the run without.
fn stored_change(name: &str, key: &str, on: Method) -> f64 {
    let (mut a, mut b) = pair(on.clone(), on, base());
    a.step().unwrap();
    b.step().unwrap();
    let e = reported(&a, key);
    assert_eq!((e.kinetic, e.gravitational, e.work), (0.0, 0.0, 0.0));
    let recomputed = a.energy().stored - b.energy().stored;
    agree(name, e.stored, recomputed, a.energy().total(), 1e-8)
}

#[test]
fn j_bar_reports_the_stored_energy_of_its_j_change() {
    stored_change(
        "j_bar",
        "j_bar",
        with(|r| r.j_bar = Some(j_bar::Settings::default())),
    );
    stored_change(
        "j_bar (linear fit, blend 0.5, increment)",
        "j_bar",
        with(|r| {
            r.j_bar = Some(j_bar::Settings {
                blend: 0.5,
                fit: JBarFit::Linear,
                average_increment: true,
                ..Default::default()
            })
        }),
    );
}

#[test]
fn cell_dilatation_reports_the_stored_energy_of_its_j_change() {
    stored_change(
        "cell_dilatation",
        "cell_dilatation",
        with(|r| r.cell_dilatation = Some(cell_dilatation::Settings::default())),
    );
}

#[test]
fn volume_relaxation_reports_the_stored_energy_of_its_j_change() {
    stored_change(
        "volume_relaxation",
        "volume_relaxation",
        with(|r| r.volume_relaxation = Some(volume_relaxation::Settings { time: 0.01 })),
    );
}

#[test]
fn bulk_damping_reports_its_work_as_the_extra_dissipation() {
    let on = with(|r| r.bulk_damping = Some(bulk_damping::Settings { coefficient: 0.5 }));
    let (mut a, mut b) = pair(on.clone(), on, base());
    a.step().unwrap();
    b.step().unwrap();
    let e = reported(&a, "bulk_damping");
    assert_eq!((e.kinetic, e.stored, e.gravitational), (0.0, 0.0, 0.0));
    let recomputed = -(a.energy().dissipated - b.energy().dissipated);
    assert!(recomputed < 0.0);
    agree("bulk_damping", e.work, recomputed, a.energy().total(), 1e-6);
}

#[test]
fn artificial_viscosity_reports_its_work_as_the_extra_dissipation() {
    let on = with(|r| r.artificial_viscosity = Some(artificial_viscosity::Settings::default()));
    let (mut a, mut b) = pair(on.clone(), on, base());
    a.step().unwrap();
    b.step().unwrap();
    let e = reported(&a, "artificial_viscosity");
    assert_eq!((e.kinetic, e.stored, e.gravitational), (0.0, 0.0, 0.0));
    let recomputed = -(a.energy().dissipated - b.energy().dissipated);
    assert!(recomputed < 0.0);
    agree(
        "artificial_viscosity",
        e.work,
        recomputed,
        a.energy().total(),
        1e-6,
    );
}

#[test]
fn f_reset_reports_nothing_and_changes_no_stored_energy() {
    let on = with(|r| r.f_reset = Some(f_reset::Settings {}));
    // Run without it, so that F carries the flow's distortion.
    let (mut a, mut b) = pair(base(), on, base());
    a.step().unwrap();
    b.step().unwrap();
    assert_eq!(reported(&a, "f_reset"), EnergyChange::default());
    assert_eq!(a.energy().stored, b.energy().stored);
    let (va, vb) = (a.view(), b.view());
    let mut sheared: f64 = 0.0;
    for p in 0..va.j.len() {
        assert_eq!(va.j[p], vb.j[p]);
        let f = va.deformation[p];
        assert_eq!((f[(0, 1)], f[(1, 0)]), (0.0, 0.0));
        assert_eq!(f[(0, 0)], f[(1, 1)]);
        sheared = sheared.max(vb.deformation[p][(0, 1)].abs());
    }
    assert!(sheared > 1e-4, "the F it reset was sheared by {sheared}");
    eprintln!(
        "f_reset: stored {:.6e} in both runs, largest shear reset {sheared:.2e}",
        a.energy().stored
    );
}

/// Whether padded node `n` of `g` lies in the box (walls included).
fn in_box(g: &GridView, n: usize, origin: Vec2, size: Vec2) -> bool {
    let (i, j) = (n % g.dims[0], n / g.dims[0]);
    let x = g.padded_origin + Vec2::new(i as f64, j as f64) * g.h;
    let eps = 1e-9 * g.h;
    (0..2).all(|k| x[k] > origin[k] - eps && x[k] < origin[k] + size[k] + eps)
}

#[test]
fn min_node_mass_reports_the_work_of_the_forces_it_replaces() {
    let share = 0.1;
    let on = with(|r| r.min_node_mass = Some(min_node_mass::Settings { share }));
    let (mut a, mut b) = pair(on.clone(), on, base());
    a.step().unwrap();
    b.step().unwrap();
    let e = reported(&a, "min_node_mass");
    assert_eq!((e.kinetic, e.stored, e.gravitational), (0.0, 0.0, 0.0));
    let (va, vb) = (a.view(), b.view());
    let (ga, gb) = (va.grid, vb.grid);
    let origin = Vec2::from(va.scene.origin);
    let size = Vec2::from(va.scene.size);
    let threshold = share * va.materials[0].rho0 * ga.h * ga.h;
    let dt = va.dt;
    let (mut recomputed, mut guarded) = (0.0, 0);
    for &n in ga.active {
        let n = n as usize;
        if !in_box(&ga, n, origin, size) {
            continue;
        }
        let m = ga.mass[n];
        assert_eq!(m, gb.mass[n]);
        let a_with = ga.acceleration[n];
        if m > 0.0 && m <= threshold {
            guarded += 1;
        } else {
            assert_eq!(a_with, gb.acceleration[n], "node {n} kept its force");
        }
        let half = ga.velocity[n] - 0.5 * dt * a_with;
        recomputed += dt * m * (a_with - gb.acceleration[n]).dot(&half);
    }
    assert!(guarded > 0);
    eprintln!("min_node_mass: {guarded} nodes guarded");
    agree(
        "min_node_mass",
        e.work,
        recomputed,
        a.energy().total(),
        1e-6,
    );
}

#[test]
fn grid_damping_takes_c_v_from_every_node_and_reports_its_work() {
    let c = 5.0;
    let on = with(|r| r.grid_damping = Some(grid_damping::Settings { coefficient: c }));
    let (mut a, mut b) = pair_noisy(on.clone(), on, base(), 0.05);
    a.step().unwrap();
    b.step().unwrap();
    let e = reported(&a, "grid_damping");
    assert_eq!((e.kinetic, e.stored, e.gravitational), (0.0, 0.0, 0.0));
    let (va, vb) = (a.view(), b.view());
    let (ga, gb) = (va.grid, vb.grid);
    let origin = Vec2::from(va.scene.origin);
    let size = Vec2::from(va.scene.size);
    let dt = va.dt;
    let (mut recomputed, mut damped) = (0.0, 0);
    // Every active node with its own P2G mass, as the grid's kinetic
    // energy is measured (ghost images included).
    for &n in ga.active {
        let n = n as usize;
        let da = ga.acceleration[n] - gb.acceleration[n];
        // v^n, the velocity P2G gave the node, is v^{n+1} - dt a.
        let v_n = ga.velocity[n] - dt * ga.acceleration[n];
        // Off the walls (whose nodes keep only the tangential part).
        let inner = Vec2::repeat(ga.h);
        if ga.mass[n] > 0.0 && in_box(&ga, n, origin + inner, size - 2.0 * inner) {
            let want = -c * v_n;
            assert!(
                (da - want).norm() <= 1e-9 * want.norm().max(1e-12),
                "node {n}: {da} vs {want}"
            );
            damped += 1;
        }
        let half = ga.velocity[n] - 0.5 * dt * ga.acceleration[n];
        recomputed += dt * ga.mass_raw[n] * da.dot(&half);
    }
    assert!(damped > 100, "{damped} nodes damped");
    assert!(e.work < 0.0, "damping takes energy: {}", e.work);
    agree("grid_damping", e.work, recomputed, a.energy().total(), 1e-6);
}

/// A body sliding along the free-slip floor (no gravity, no stress) loses
/// exactly the kinetic energy the damping books, wall nodes included.
#[test]
fn grid_damping_books_the_kinetic_energy_a_sliding_body_loses() {
    let c = 20.0;
    let mut method = common::method(ShapeKind::Bspline2, TransferKind::Pic, SchemeKind::Usl);
    method.remedies.grid_damping = Some(grid_damping::Settings { coefficient: c });
    let mut scene = common::box_scene([1.0, 0.5], [0.2, 0.0, 0.5, 0.1], Material::tait(1e5), 0.0);
    scene.bodies[0].velocity = [0.4, 0.0];
    let mut s = common::solver(scene, method);
    let kinetic = |s: &Solver| -> f64 {
        let v = s.view();
        (0..v.v.len())
            .map(|p| 0.5 * v.mass[p] * v.v[p].norm_squared())
            .sum()
    };
    let k0 = kinetic(&s);
    let mut booked = 0.0;
    for _ in 0..20 {
        s.step().unwrap();
        booked += reported(&s, "grid_damping").work;
    }
    let lost = kinetic(&s) - k0;
    assert!(lost < -0.05 * k0, "it damped: {lost} of {k0}");
    assert!(
        (booked - lost).abs() < 1e-12 * k0,
        "booked {booked}, lost {lost}"
    );
}

/// The speed cap (Uintah's USL ceiling of 2014) slows every particle
/// faster than the cap whose speed did not fall in the step to 0.9 of the
/// cap, along its own direction, touches no other, and reports the
/// kinetic energy it took.
#[test]
fn speed_cap_slows_the_fast_particles_and_reports_their_energy() {
    let cap = 0.08;
    let on = with(|r| r.speed_cap = Some(speed_cap::Settings { speed: cap }));
    let (mut a, mut b) = pair_noisy(on.clone(), on, base(), 0.1);
    let start: Vec<f64> = a.view().v.iter().map(|v| v.norm()).collect();
    a.step().unwrap();
    b.step().unwrap();
    let e = reported(&a, "speed_cap");
    assert_eq!((e.stored, e.gravitational, e.work), (0.0, 0.0, 0.0));
    let (va, vb) = (a.view(), b.view());
    let (mut recomputed, mut capped, mut kept_fast) = (0.0, 0, 0);
    for p in 0..va.v.len() {
        let (with, without) = (va.v[p], vb.v[p]);
        assert_eq!(va.x[p], vb.x[p], "positions are G2P's");
        if without.norm() > cap && without.norm() >= start[p] {
            capped += 1;
            let want = without * (0.9 * cap / without.norm());
            assert!((with - want).norm() < 1e-15, "{with} {want}");
            recomputed += 0.5 * va.mass[p] * (with.norm_squared() - without.norm_squared());
        } else {
            kept_fast += usize::from(without.norm() > cap);
            assert_eq!(with, without);
        }
    }
    assert!(
        capped > 10,
        "{capped} capped ({kept_fast} fast but slowing)"
    );
    agree("speed_cap", e.kinetic, recomputed, a.energy().total(), 1e-6);
}

/// A particle above the cap that slows in the step keeps its speed (the
/// 2014 ceiling acts only on speeds that did not fall): a body gliding
/// at 0.3 m/s under grid damping, with the cap at 0.1 m/s, is never
/// capped, while the same body in free fall is held at 0.9 of the cap.
#[test]
fn speed_cap_leaves_a_slowing_particle_and_holds_a_falling_one() {
    let run = |gravity: f64, damping: Option<f64>| {
        let mut method = common::method(ShapeKind::Bspline2, TransferKind::Flip, SchemeKind::Usl);
        method.remedies.speed_cap = Some(speed_cap::Settings { speed: 0.1 });
        method.remedies.grid_damping = damping.map(|c| grid_damping::Settings { coefficient: c });
        let mut scene = common::box_scene(
            [1.0, 1.0],
            [0.4, 0.4, 0.6, 0.6],
            Material::tait(1e5),
            gravity,
        );
        scene.bodies[0].velocity = if damping.is_some() {
            [0.3, 0.0]
        } else {
            [0.0, 0.0]
        };
        let mut s = common::solver(scene, method);
        let mut capped = 0.0;
        for _ in 0..100 {
            s.step().unwrap();
            capped += reported_of(&s, "speed_cap").kinetic;
        }
        let speeds: Vec<f64> = s.view().v.iter().map(|v| v.norm()).collect();
        (speeds, capped)
    };
    let (gliding, taken) = run(0.0, Some(5.0));
    assert_eq!(taken, 0.0);
    assert!(gliding.iter().all(|v| *v > 0.1), "{:?}", gliding.first());
    let (falling, taken) = run(9.81, None);
    assert!(taken < 0.0, "free fall is capped");
    assert!(falling.iter().all(|v| *v <= 0.1), "{:?}", falling.first());
}

/// A body gliding through an empty box (no gravity, no stress) under
/// damping c keeps each step's factor 1 - c dt exactly: every particle's
/// velocity is U prod (1 - c dt_k) to round-off, whatever the transfer.
#[test]
fn grid_damping_slows_a_gliding_body_by_one_minus_c_dt_a_step() {
    let c = 20.0;
    for transfer in [TransferKind::Flip, TransferKind::Apic, TransferKind::Pic] {
        let mut method = common::method(ShapeKind::Bspline2, transfer, SchemeKind::Usl);
        method.remedies.grid_damping = Some(grid_damping::Settings { coefficient: c });
        let mut scene =
            common::box_scene([1.0, 1.0], [0.4, 0.4, 0.6, 0.6], Material::tait(1e5), 0.0);
        scene.bodies[0].velocity = [0.3, -0.1];
        let mut s = common::solver(scene, method);
        let mut factor = 1.0;
        for _ in 0..20 {
            s.step().unwrap();
            factor *= 1.0 - c * s.view().dt;
        }
        assert!(factor < 0.95, "{transfer:?}: it damped only to {factor}");
        for v in s.view().v {
            let want = factor * Vec2::new(0.3, -0.1);
            assert!((v - want).norm() < 1e-12, "{transfer:?}: {v} vs {want}");
        }
    }
}

/// dt sum_i df_i . v_i^{n+1/2} with df_i = -sum_p d_p grad N_ip, d_p a
/// change of V sigma: the particles `x`, F (`f`) and `d` as at the start
/// of the step whose grid `g` is given (v^{n+1/2} = v^{n+1} - dt a / 2 at
/// every padded node, ghosts included), summed node by node.
fn stress_change_work(
    shape: &Shape,
    origin: Vec2,
    g: &GridView,
    dt: f64,
    x: &[Vec2],
    f: &[Mat2],
    d: &[Mat2],
) -> f64 {
    match shape.width() {
        2 => stress_change_work_w::<2>(shape, origin, g, dt, x, f, d),
        3 => stress_change_work_w::<3>(shape, origin, g, dt, x, f, d),
        _ => stress_change_work_w::<4>(shape, origin, g, dt, x, f, d),
    }
}

fn stress_change_work_w<const W: usize>(
    shape: &Shape,
    origin: Vec2,
    g: &GridView,
    dt: f64,
    x: &[Vec2],
    f: &[Mat2],
    d: &[Mat2],
) -> f64 {
    let nx = g.dims[0];
    let pad = ((origin - g.padded_origin).x / g.h).round() as i64;
    assert_eq!(pad, solver::grid::PAD as i64);
    let mut df = vec![Vec2::zeros(); g.dims[0] * g.dims[1]];
    let inv_h = 1.0 / g.h;
    for p in 0..x.len() {
        let r = (x[p] - origin) * inv_h;
        let half = shape.half_widths(&f[p]);
        let (bx, fx) = shape.locate(r.x);
        let (by, fy) = shape.locate(r.y);
        let (wx, dwx) = shape.stencil_weights::<W>(fx, half[0]);
        let (wy, dwy) = shape.stencil_weights::<W>(fy, half[1]);
        for c in 0..W {
            for a in 0..W {
                let n = (bx + pad + a as i64) as usize + (by + pad + c as i64) as usize * nx;
                let grad = Vec2::new(dwx[a] * wy[c], wx[a] * dwy[c]) * inv_h;
                df[n] -= d[p] * grad;
            }
        }
    }
    let mut work = 0.0;
    for n in 0..df.len() {
        let v_half = g.velocity[n] - 0.5 * dt * g.acceleration[n];
        work += dt * df[n].dot(&v_half);
    }
    work
}

/// A remedy that changes the stress of a step and not the state carried on
/// (pressure smoothing, an averaged J not carried, which also leaves the
/// step's volume): under USL the change made at the end of step n acts on
/// the grid at step n + 1, where its work is booked. The change is
/// d = V_with sigma_with - V_without sigma_without after step n. Returns
/// the relative error and the share of the work that the volume change
/// alone, (V_with - V_without) sigma_without, does.
fn stress_work(name: &str, key: &str, on: Method) -> (f64, f64) {
    let (mut a, mut b) = pair(on.clone(), on, base());
    a.step().unwrap();
    b.step().unwrap();
    let (va, vb) = (a.view(), b.view());
    let n = va.x.len();
    let changed = (0..n).filter(|&p| va.pressure[p] != vb.pressure[p]).count();
    assert!(
        changed > n / 2,
        "{name}: {changed} of {n} pressures changed"
    );
    for p in 0..n {
        assert_eq!(va.j[p], vb.j[p], "{name}: J is not carried");
        assert_eq!(va.x[p], vb.x[p]);
    }
    let x = va.x.to_vec();
    let f = va.deformation.to_vec();
    let d: Vec<Mat2> = (0..n)
        .map(|p| va.volume[p] * va.stress[p] - vb.volume[p] * vb.stress[p])
        .collect();
    let d_volume: Vec<Mat2> = (0..n)
        .map(|p| (va.volume[p] - vb.volume[p]) * vb.stress[p])
        .collect();
    let origin = Vec2::from(va.scene.origin);
    let shape = Shape::new(a.config().method.shape, a.config().scene.ppc);
    // Step n + 1 with the remedy: the booking.
    a.step().unwrap();
    let e = reported(&a, key);
    assert_eq!((e.kinetic, e.stored, e.gravitational), (0.0, 0.0, 0.0));
    let v = a.view();
    let recomputed = stress_change_work(&shape, origin, &v.grid, v.dt, &x, &f, &d);
    let volume_part = stress_change_work(&shape, origin, &v.grid, v.dt, &x, &f, &d_volume);
    let err = agree(name, e.work, recomputed, a.energy().total(), 5e-8);
    (err, volume_part / recomputed)
}

#[test]
fn pressure_smoothing_reports_the_work_of_its_pressure_change_at_the_next_grid_update() {
    let on = with(|r| r.pressure_smoothing = Some(pressure_smoothing::Settings {}));
    let (_, volume_part) = stress_work("pressure_smoothing", "pressure_smoothing", on);
    // The volumes are the run's own: nothing else changes the force.
    assert_eq!(volume_part, 0.0);
}

#[test]
fn an_averaged_j_not_carried_reports_the_work_of_its_pressure_change() {
    let j_bar = with(|r| {
        r.j_bar = Some(j_bar::Settings {
            carry: false,
            ..Default::default()
        })
    });
    let (_, volume_share) = stress_work("j_bar (carry = false)", "j_bar", j_bar);
    // The averaged volume stays for the step: its share is booked too.
    assert!(volume_share.abs() > 1e-3, "{volume_share}");
    let cell = with(|r| {
        r.cell_dilatation = Some(cell_dilatation::Settings {
            carry: false,
            ..Default::default()
        })
    });
    let (_, volume_share) = stress_work("cell_dilatation (carry = false)", "cell_dilatation", cell);
    assert!(volume_share.abs() > 1e-3, "{volume_share}");
}
