//! The stress stage against closed forms: simple shear gives the Newtonian
//! shear stress, a uniform deformation at rest the EOS pressure of each EOS,
//! a uniform compression the EOS pressure of the updated J (both J updates)
//! plus the bulk part of the plane-strain viscous stress; and perturbations
//! land after G2P of their step.

use solver::*;

use crate::common;

/// Box of `CELLS` x `CELLS` cells of `H` filled with 2 x 2 particles per cell.
const CELLS: usize = 32;
const H: f64 = 0.01;
const DT: f64 = 1e-4;

/// One step of `method` from the seeded lattice of `scene` (whole box, no
/// gravity) after `init` set each particle's velocity and deformation
/// gradient from its position (J = det F, V = V0 J, zero stress).
fn one_step(scene: Scene, method: Method, init: impl Fn(Vec2) -> (Vec2, Mat2)) -> Solver {
    let mut ps = scene::seed(&scene);
    for p in 0..ps.len() {
        let (v, f) = init(ps.x[p]);
        ps.v[p] = v;
        ps.f[p] = f;
        ps.j[p] = f.determinant();
        ps.vol[p] = ps.vol0[p] * ps.j[p];
    }
    let cfg = SolverConfig {
        scene,
        method: Method {
            dt_value: Some(DT),
            ..method
        },
        perturb: vec![],
    };
    let mut s = Solver::with_particles(cfg, ps);
    s.step().unwrap();
    assert_eq!(s.view().dt, DT);
    s
}

fn full_box(material: Material, periodic: [bool; 2]) -> Scene {
    let size = CELLS as f64 * H;
    let mut scene = common::box_scene([size, size], [0.0, 0.0, size, size], material, 0.0);
    scene.cell = H;
    scene.periodic = periodic;
    scene
}

/// Cells between a wall and the particles checked: the wall's mirror images
/// break a linear velocity field, and MUSL chains four stencils of up to 2
/// cells radius (P2G, G2P, re-projection, stress) before the gradient.
const MARGIN: usize = 9;

/// Particles at least `MARGIN` cells from the walls on the `axes` marked:
/// there a linear particle velocity gives a linear grid velocity.
fn interior(x: Vec2, axes: [bool; 2]) -> bool {
    let (lo, hi) = (MARGIN as f64 * H, (CELLS - MARGIN) as f64 * H);
    (0..2).all(|a| !axes[a] || (lo..=hi).contains(&x[a]))
}

/// Round-off bound of the velocity gradient at an interior particle,
/// relative to the rate g of the linear velocity field: the grid velocities
/// g (x_i - x_c) come out of the P2G sums within a few (4) ulps, and the
/// gradient sums W^2 <= 16 of them times dN / h, each term up to
/// |x_i - x_c| / h <= CELLS / 2 times the result.
fn gradient_round_off() -> f64 {
    16.0 * 4.0 * (CELLS / 2) as f64 * f64::EPSILON
}

/// The EOS forms of docs/physics.md section 2, written out independently of the solver.
fn eos_pressure(m: &Material, j: f64) -> f64 {
    let p = match m.eos {
        EosKind::Power => m.k * (j.powf(-m.gamma) - 1.0),
        EosKind::Tait => {
            let c = solver::eos::tait::TAIT_C;
            c * m.k * (((1.0 - j) / c).exp() - 1.0)
        }
        EosKind::Linear => m.k * (1.0 - j),
    };
    m.pressure_floor.map_or(p, |floor| p.max(floor))
}

/// Round-off bound of `eos_pressure` and the solver's evaluation (integer
/// powers by squaring, exp): a few ulps of the largest term, K J^-gamma or
/// C K exp((1 - J) / C) (1 + |1 - J| / C).
fn eos_round_off(m: &Material, j: f64) -> f64 {
    let scale = match m.eos {
        EosKind::Power => m.k * (1.0 + m.gamma) * j.powf(-m.gamma),
        EosKind::Tait => {
            let c = solver::eos::tait::TAIT_C;
            m.k * ((1.0 - j) / c).exp() * (c + (1.0 - j).abs())
        }
        EosKind::Linear => m.k * (1.0 - j).abs(),
    };
    8.0 * f64::EPSILON * scale
}

fn materials() -> Vec<Material> {
    let power = |gamma: f64| Material {
        eos: EosKind::Power,
        gamma,
        ..Material::new(1e5)
    };
    let mut out = vec![
        power(7.0),
        // A non-integer exponent takes powf instead of the squaring loop.
        power(6.5),
        Material::tait(1e5),
        Material {
            eos: EosKind::Linear,
            ..Material::new(1e5)
        },
        // Tension below the floor is cut.
        Material {
            pressure_floor: Some(-300.0),
            ..power(7.0)
        },
    ];
    for (i, m) in out.iter_mut().enumerate() {
        m.name = format!("m{i}");
    }
    out
}

/// Simple shear v = (g (y - y_c), 0) between the walls of a box periodic in
/// x: in the interior L = [[0, g], [0, 0]], D is traceless, J stays 1 and the
/// stress is the Newtonian sigma_xy = mu g with no normal stress, for every
/// shape, transfer and scheme (MUSL re-projects the same linear field).
#[test]
fn simple_shear_gives_newtonian_shear_stress() {
    let (mu, rate, y_c) = (0.5, 4.0, 0.5 * CELLS as f64 * H);
    let tau = mu * rate;
    let eta = gradient_round_off();
    let mut worst = [0.0f64; 2];
    for shape in common::RUN_SHAPES {
        for transfer in common::TRANSFERS {
            for scheme in common::SCHEMES {
                let mat = Material {
                    viscosity: mu,
                    ..Material::tait(1e5)
                };
                let s = one_step(
                    full_box(mat.clone(), [true, false]),
                    common::method(shape, transfer, scheme),
                    |x| (Vec2::new(rate * (x.y - y_c), 0.0), Mat2::identity()),
                );
                let v = s.view();
                let mut checked = 0;
                for p in (0..v.x.len()).filter(|&p| interior(v.x[p], [false, true])) {
                    let sigma = v.stress[p];
                    let what = format!("{shape:?} {transfer:?} {scheme:?} at {}", v.x[p]);
                    // det (I + dt L) F = 1 up to dt times the round-off of L.
                    assert!(
                        (v.j[p] - 1.0).abs() <= 4.0 * f64::EPSILON,
                        "{what}: J {}",
                        v.j[p]
                    );
                    let p_err = (v.pressure[p] - eos_pressure(&mat, v.j[p])).abs();
                    assert!(
                        p_err <= eos_round_off(&mat, v.j[p]),
                        "{what}: p {}",
                        v.pressure[p]
                    );
                    let shear = (sigma[(0, 1)] - tau).abs();
                    let normal = (sigma[(0, 0)] + v.pressure[p])
                        .abs()
                        .max((sigma[(1, 1)] + v.pressure[p]).abs());
                    assert!(
                        shear <= eta * tau,
                        "{what}: sigma_xy {} vs {tau}",
                        sigma[(0, 1)]
                    );
                    assert!(
                        normal <= eta * tau,
                        "{what}: normal viscous stress {normal}"
                    );
                    assert_eq!(sigma[(1, 0)], sigma[(0, 1)], "{what}");
                    // |dev D| of simple shear: g / sqrt 2.
                    let rate_err = (v.dev_rate[p] - rate / 2f64.sqrt()).abs();
                    assert!(rate_err <= eta * rate, "{what}: |dev D| {}", v.dev_rate[p]);
                    worst[0] = worst[0].max(shear / tau);
                    worst[1] = worst[1].max(normal / tau);
                    checked += 1;
                }
                assert_eq!(checked, 2 * CELLS * 2 * (CELLS - 2 * MARGIN));
            }
        }
    }
    eprintln!(
        "simple shear: max |sigma_xy - mu g| / mu g = {:.2e}, max normal viscous stress / mu g = {:.2e} (bound {eta:.2e})",
        worst[0], worst[1]
    );
}

/// Uniform F = diag(s, s) at rest in a periodic box: the stress stage sees
/// an exactly zero grid velocity (the initial stress is zero; USF applies the
/// new one only after), so F and J = s^2 do not change, and the stress is
/// -p(J) I with the EOS pressure, for each EOS (one material per run, then all of them in
/// strips, which takes the mixed-material path) and both J updates.
#[test]
fn uniform_deformation_gives_the_eos_pressure() {
    let mats = materials();
    let mut worst: f64 = 0.0;
    let mut runs: Vec<(Vec<Material>, Vec<usize>)> = (0..mats.len())
        .map(|i| (vec![mats[i].clone()], vec![i]))
        .collect();
    runs.push((mats.clone(), (0..mats.len()).collect()));
    for (run_mats, index) in runs {
        for s_factor in [0.9, 0.97, 0.999, 1.0, 1.003, 1.02] {
            for (scheme, j_update) in [
                (SchemeKind::Usf, JUpdate::Det),
                (SchemeKind::Usl, JUpdate::Exp),
                (SchemeKind::Musl, JUpdate::Det),
            ] {
                let mut scene = full_box(run_mats[0].clone(), [true, true]);
                let size = scene.size[0];
                let strip = size / run_mats.len() as f64;
                scene.bodies = (0..run_mats.len())
                    .map(|k| Body {
                        rect: [k as f64 * strip, 0.0, (k + 1) as f64 * strip, size],
                        material: run_mats[k].name.clone(),
                        velocity: [0.0, 0.0],
                        fraction: 1.0,
                        phase: None,
                        flow: None,
                    })
                    .collect();
                scene.materials = run_mats.clone();
                let f0 = Mat2::new(s_factor, 0.0, 0.0, s_factor);
                let mut method = common::method(ShapeKind::Bspline2, TransferKind::Apic, scheme);
                method.j_update = j_update;
                let s = one_step(scene, method, |_| (Vec2::zeros(), f0));
                let v = s.view();
                let j = s_factor * s_factor;
                for p in 0..v.x.len() {
                    let m = &mats[index[v.material[p] as usize]];
                    let what = format!(
                        "{:?} gamma {} s {s_factor} {scheme:?} {j_update:?}",
                        m.eos, m.gamma
                    );
                    assert_eq!(v.deformation[p], f0, "{what}");
                    assert_eq!(v.j[p], j, "{what}");
                    assert_eq!(v.volume[p], v.volume0[p] * j, "{what}");
                    let expected = eos_pressure(m, j);
                    let err = (v.pressure[p] - expected).abs();
                    assert!(
                        err <= eos_round_off(m, j),
                        "{what}: p {} vs {expected}",
                        v.pressure[p]
                    );
                    assert_eq!(v.stress[p], -v.pressure[p] * Mat2::identity(), "{what}");
                    if expected != 0.0 {
                        worst = worst.max(err / expected.abs());
                    }
                }
            }
        }
    }
    eprintln!("uniform F: max relative pressure error {worst:.2e}");
}

/// Uniform compression v = -e (x - x_c) between walls: in the interior
/// L = -e I, so F = (1 - e dt) I, J = (1 - e dt)^2 (det update) or
/// exp(-2 e dt) (exp update), and with the 3D deviator of plane strain
/// (D_zz = 0) sigma = -(p(J) + 2 mu e / 3) I, for each EOS and scheme.
#[test]
fn uniform_compression_gives_eos_pressure_and_bulk_viscous_stress() {
    let (mu, e) = (0.5, 5.0);
    let c = 0.5 * CELLS as f64 * H;
    let eta = gradient_round_off();
    let mut worst = [0.0f64; 3];
    for mat in materials().into_iter().take(4) {
        let mat = Material {
            viscosity: mu,
            ..mat
        };
        for j_update in [JUpdate::Det, JUpdate::Exp, JUpdate::Substeps] {
            for shape in common::RUN_SHAPES {
                for transfer in common::TRANSFERS {
                    for scheme in common::SCHEMES {
                        let mut method = common::method(shape, transfer, scheme);
                        method.j_update = j_update;
                        let s = one_step(full_box(mat.clone(), [false, false]), method, |x| {
                            (-e * (x - Vec2::new(c, c)), Mat2::identity())
                        });
                        let v = s.view();
                        let x = e * DT;
                        let j = match j_update {
                            // |L| dt < 1: Uintah's substeps are the plain update.
                            JUpdate::Det | JUpdate::Substeps => (1.0 - x) * (1.0 - x),
                            JUpdate::Exp => (-2.0 * x).exp(),
                        };
                        let p = eos_pressure(&mat, j);
                        let visc = 2.0 / 3.0 * mu * e;
                        // L is -e I to a relative eta: J to 2 dt e eta, p to
                        // K_t / J times that, the viscous stress to 2 mu e eta.
                        let k_t = mat.eos(j).tangent_modulus / j;
                        let j_tol = 2.0 * x * eta + 4.0 * f64::EPSILON;
                        let tol = k_t * j_tol + 2.0 * mu * e * eta + eos_round_off(&mat, j);
                        let mut checked = 0;
                        for q in (0..v.x.len()).filter(|&q| interior(v.x[q], [true, true])) {
                            let what = format!(
                                "{:?} {j_update:?} {shape:?} {transfer:?} {scheme:?} at {}",
                                mat.eos, v.x[q]
                            );
                            let f = v.deformation[q];
                            let sqrt_j = j.sqrt();
                            assert!((v.j[q] - j).abs() <= j_tol, "{what}: J {} vs {j}", v.j[q]);
                            assert!(
                                (f - sqrt_j * Mat2::identity()).abs().max() <= j_tol,
                                "{what}: F {f}"
                            );
                            assert!((f.determinant() - v.j[q]).abs() <= 4.0 * f64::EPSILON);
                            let sigma = v.stress[q];
                            let err = (sigma + (p + visc) * Mat2::identity()).abs().max();
                            assert!(err <= tol, "{what}: sigma {sigma} vs -{}", p + visc);
                            worst[0] = worst[0].max(err / (p + visc));
                            worst[2] = worst[2].max(err / tol);
                            worst[1] = worst[1].max((v.j[q] - j).abs());
                            checked += 1;
                        }
                        assert_eq!(checked, (2 * (CELLS - 2 * MARGIN)).pow(2));
                    }
                }
            }
        }
    }
    eprintln!(
        "uniform compression: max |sigma - sigma_exact| / |sigma| = {:.2e} ({:.2} of the bound), max |J - J_exact| = {:.2e}",
        worst[0], worst[2], worst[1]
    );
}

#[test]
fn perturbation_adds_dv_after_g2p_of_its_step() {
    let mut scene = common::box_scene([0.4, 0.4], [0.1, 0.1, 0.3, 0.3], Material::tait(1e5), 0.0);
    scene.periodic = [true, true];
    let region = [0.15, 0.15, 0.2, 0.2];
    let cfg = SolverConfig {
        scene,
        method: common::method(ShapeKind::Bspline2, TransferKind::Pic, SchemeKind::Usf),
        perturb: vec![Perturb::at_step(3, region, [1.0, -0.5])],
    };
    let mut s = Solver::new(cfg).unwrap();
    for _ in 0..2 {
        s.step().unwrap();
        assert!(s.view().v.iter().all(|v| v.norm() == 0.0));
    }
    s.step().unwrap();
    let v = s.view();
    assert_eq!(v.step, 3);
    let mut hit = 0;
    for p in 0..v.x.len() {
        let x = v.x[p];
        let inside = x.x >= region[0] && x.x <= region[2] && x.y >= region[1] && x.y <= region[3];
        if inside {
            hit += 1;
            assert_eq!(v.v[p], Vec2::new(1.0, -0.5));
        } else {
            assert_eq!(v.v[p], Vec2::zeros());
        }
        assert_eq!(v.v_prev[p], Vec2::zeros());
    }
    assert_eq!(
        hit, 100,
        "a 5 x 5-cell region holds 100 particles at 2 x 2 ppc"
    );
    let expected = 0.5 * 1.25 * v.mass[0] * hit as f64;
    assert!((v.energy.kinetic - expected).abs() < 1e-12 * expected);
}

/// F reset (F <- J^(1/2) I) changes nothing but round-off for shapes that
/// ignore F: a quadratic B-spline APIC dam break follows the same path for
/// 300 steps, with an isotropic F and the same J.
#[test]
fn f_reset_changes_only_round_off() {
    let run = |f_reset: bool| {
        let mut mat = Material::tait(1.5e5);
        mat.viscosity = 0.5;
        let scene = Scene::dam_break(mat);
        let mut method = common::method(ShapeKind::Bspline2, TransferKind::Apic, SchemeKind::Usl);
        method.remedies.f_reset = f_reset.then_some(solver::remedies::f_reset::Settings {});
        let mut s = common::solver(scene, method);
        for _ in 0..300 {
            s.step().unwrap();
        }
        s
    };
    let (plain, reset) = (run(false), run(true));
    let (a, b) = (plain.view(), reset.view());
    let mut worst_x: f64 = 0.0;
    let mut worst_j: f64 = 0.0;
    for p in 0..a.x.len() {
        worst_x = worst_x.max((a.x[p] - b.x[p]).norm());
        worst_j = worst_j.max((a.j[p] - b.j[p]).abs());
        let f = b.deformation[p];
        assert_eq!(f[(0, 1)], 0.0);
        assert_eq!(f[(1, 0)], 0.0);
        assert_eq!(f[(0, 0)], f[(1, 1)]);
    }
    // The fluid is moving: the differences are round-off grown over 300 steps.
    let fastest = a.v.iter().map(|v| v.norm()).fold(0.0, f64::max);
    assert!(fastest > 0.1, "{fastest}");
    assert!(worst_x < 1e-10, "positions differ by {worst_x} m");
    assert!(worst_j < 1e-10, "J differs by {worst_j}");
    let distorted = (0..a.x.len())
        .map(|p| a.deformation[p][(0, 1)].abs())
        .fold(0.0, f64::max);
    assert!(
        distorted > 1e-3,
        "the plain run's F is sheared ({distorted})"
    );
}

/// A push at a time, placed in the bulk and relative to the flow, is the
/// push its record says: replayed as a push at that step, in that region,
/// with that dv, the run is bit-identical; it lands in the step that spans
/// its time, on the patch the placement rules give, once.
#[test]
fn a_timed_placed_push_is_the_push_its_record_names() {
    let mut scene = common::box_scene([0.4, 0.3], [0.0, 0.0, 0.4, 0.2], Material::tait(1e5), 9.81);
    scene.initial = InitialState::Hydrostatic;
    let method = common::method(ShapeKind::Bspline2, TransferKind::Apic, SchemeKind::Usl);
    let timed = Perturb {
        step: None,
        t: Some(0.01),
        region: None,
        place: Some(Placement::Bulk),
        cells: 2,
        near: Some([0.1, 0.1]),
        min_particles: None,
        dv: None,
        speed: Some(0.05),
        direction: Some(Direction::Up),
        duration: None,
        j_scale: None,
        dx: None,
    };
    let run = |perturb: Vec<Perturb>| {
        let cfg = SolverConfig {
            scene: scene.clone(),
            method: method.clone(),
            perturb,
        };
        let mut s = Solver::new(cfg).unwrap();
        while s.time() < 0.02 {
            s.step().unwrap();
        }
        s
    };
    let s = run(vec![timed]);
    let planted = s.planted().to_vec();
    assert_eq!(planted.len(), 1, "applied once");
    let p = planted[0];
    // The step that spans t = 0.01 (it starts at or before it, ends after it).
    assert!(p.t <= 0.01, "{p:?}");
    // A 2 x 2-cell block on cell lines, at least 3 cells from the walls and
    // the surface (rows up to 0.2 m hold fluid), nearest (0.1, 0.1).
    let [x0, y0, x1, y1] = p.region;
    assert!(
        (x1 - x0 - 0.02).abs() < 1e-12 && (y1 - y0 - 0.02).abs() < 1e-12,
        "{p:?}"
    );
    assert!(
        x0 >= 0.03 - 1e-12 && y0 >= 0.03 - 1e-12 && y1 <= 0.17 + 1e-12,
        "{p:?}"
    );
    assert!(
        (x0 - 0.09).abs() < 1e-12 && (y0 - 0.09).abs() < 1e-12,
        "{p:?}"
    );
    assert_eq!(p.dv, [0.0, 0.05]);
    assert_eq!(p.particles, 16);
    let replayed = run(vec![Perturb::at_step(p.step, p.region, p.dv)]);
    assert_eq!(replayed.state_hash(), s.state_hash());
    assert_eq!(replayed.planted(), planted.as_slice());
}

/// `method.dt_min` raises a CFL step below it (Uintah's `delt_min`) and
/// leaves a larger one alone, under a dynamic and a fixed step.
#[test]
fn a_step_floor_raises_the_cfl_step_and_leaves_a_larger_one() {
    let scene = common::box_scene(
        [0.4, 0.3],
        [0.0, 0.0, 0.2, 0.2],
        Material::tait(1.5e5),
        9.81,
    );
    for dt in [DtMode::Dynamic, DtMode::Fixed] {
        let mut method = common::method(ShapeKind::Linear, TransferKind::Flip, SchemeKind::Usl);
        method.dt = dt;
        let solver = |method: Method| {
            Solver::new(SolverConfig {
                scene: scene.clone(),
                method,
                perturb: vec![],
            })
            .unwrap()
        };
        let cfl_step = solver(method.clone()).next_dt();
        let floor = 4.0 * cfl_step;
        let raised = solver(Method {
            dt_min: Some(floor),
            ..method.clone()
        });
        assert_eq!(raised.next_dt(), floor, "{dt:?}");
        let kept = solver(Method {
            dt_min: Some(0.25 * cfl_step),
            ..method
        });
        assert_eq!(kept.next_dt(), cfl_step, "{dt:?}");
    }
}

/// A plant with a duration pushes the particles its patch covered at its
/// start by its whole dv, as a force: on a free body (no walls, no
/// gravity) the momentum gained is the impulse's to round-off, over the
/// steps the duration spans; and a restart from a checkpoint taken while
/// it pushes continues to the same bits.
#[test]
fn a_plant_with_a_duration_adds_its_whole_impulse_and_restarts_bit_identically() {
    let scene = common::box_scene([0.4, 0.3], [0.1, 0.1, 0.3, 0.2], Material::tait(1e5), 0.0);
    let method = common::method(ShapeKind::Bspline2, TransferKind::Apic, SchemeKind::Usl);
    let plant = |duration: Option<f64>| Perturb {
        t: Some(0.002),
        step: None,
        duration,
        ..Perturb::at_step(1, [0.18, 0.14, 0.2, 0.16], [0.05, 0.0])
    };
    let solver = |perturb: Vec<Perturb>| {
        Solver::new(SolverConfig {
            scene: scene.clone(),
            method: method.clone(),
            perturb,
        })
        .unwrap()
    };
    let run_to = |s: &mut Solver, t: f64| {
        while s.time() < t {
            s.step().unwrap();
        }
    };
    let momentum = |s: &Solver| -> Vec2 {
        let v = s.view();
        (0..v.v.len()).map(|p| v.mass[p] * v.v[p]).sum()
    };
    let mut clean = solver(vec![]);
    let mut impulse = solver(vec![plant(None)]);
    let mut spread = solver(vec![plant(Some(0.005))]);
    for s in [&mut clean, &mut impulse, &mut spread] {
        run_to(s, 0.01);
    }
    let record = spread.planted()[0];
    assert_eq!(
        (record.duration, record.particles),
        (0.005, 16),
        "{record:?}"
    );
    assert_eq!(spread.planted().len(), 1, "one record for the whole push");
    let m_patch: f64 = 16.0 * spread.view().mass[0];
    let gained = |s: &Solver| momentum(s) - momentum(&clean);
    for s in [&impulse, &spread] {
        let g = gained(s);
        assert!((g.x - m_patch * 0.05).abs() < 1e-9 * m_patch, "{g:?}");
        assert!(g.y.abs() < 1e-9 * m_patch, "{g:?}");
    }
    assert_ne!(impulse.state_hash(), spread.state_hash());
    // Checkpointed mid-push, restored into a fresh solver, run on.
    let mut first = solver(vec![plant(Some(0.005))]);
    run_to(&mut first, 0.004);
    let bytes = first.checkpoint();
    let mut resumed = solver(vec![plant(Some(0.005))]);
    resumed.restore(&bytes).unwrap();
    run_to(&mut resumed, 0.01);
    assert_eq!(resumed.state_hash(), spread.state_hash());
    assert_eq!(resumed.step_count(), spread.step_count());
}
