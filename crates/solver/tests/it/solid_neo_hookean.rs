//! The neo-Hookean shear part: exact simple shear, objectivity, stress power
//! equal to the rate of stored energy, and in the solver an elastic shear
//! wave in a periodic box against its exact period with energy kept. The
//! unified model's history variable xi: simple shear driven at a material
//! point against the closed forms, and in the solver a block that stands as
//! a solid and flows once softened, with the energy budget kept.

use crate::common;

use solver::remedies::{
    cell_dilatation, f_reset, j_bar, pressure_smoothing, shifting, volume_relaxation,
    RemedySettings,
};
use solver::solid_neo_hookean::{add_to, history_increment, shear};
use solver::*;

const G: f64 = 1e4;

#[test]
fn simple_shear_is_exact_and_identity_is_free() {
    let rest = shear(&Mat2::identity(), G);
    assert_eq!(rest.stress, Mat2::zeros());
    assert_eq!(rest.energy, 0.0);
    for gamma in [1e-3, 0.1, 0.5, 2.0] {
        let s = shear(&Mat2::new(1.0, gamma, 0.0, 1.0), G);
        let tol = 1e-12 * G * (1.0 + gamma * gamma);
        assert!((s.stress[(0, 1)] - G * gamma).abs() < tol, "{gamma}: {s:?}");
        assert!((s.stress[(1, 0)] - G * gamma).abs() < tol);
        // Normal stress difference G gamma^2; sigma_zz = -(sigma_xx + sigma_yy).
        let n1 = s.stress[(0, 0)] - s.stress[(1, 1)];
        assert!((n1 - G * gamma * gamma).abs() < tol, "{gamma}: N1 {n1}");
        let szz = -s.stress.trace();
        assert!(
            (szz + G * gamma * gamma / 3.0).abs() < tol,
            "{gamma}: zz {szz}"
        );
        assert!(
            (s.energy - 0.5 * G * gamma * gamma).abs() < tol,
            "{gamma}: W {}",
            s.energy
        );
    }
}

fn sample_f(k: usize) -> Mat2 {
    let a = 0.1 * k as f64;
    Mat2::new(
        1.0 + 0.3 * a.sin(),
        0.4 * (2.0 * a).cos(),
        -0.2 * a.cos(),
        0.8 + 0.25 * (3.0 * a).sin(),
    )
}

#[test]
fn shear_part_is_objective() {
    for k in 0..20 {
        let f = sample_f(k);
        let (c, s) = ((0.3 * k as f64).cos(), (0.3 * k as f64).sin());
        let r = Mat2::new(c, -s, s, c);
        let (a, b) = (shear(&f, G), shear(&(r * f), G));
        let rotated = r * a.stress * r.transpose();
        assert!((rotated - b.stress).norm() < 1e-11 * G, "{k}");
        assert!((a.energy - b.energy).abs() < 1e-11 * G, "{k}");
    }
}

/// d/dt (V0 W) = V sigma : L for F' = L F (V = J V0): the stress is the
/// energy's work conjugate, so the energy budget stays closed.
#[test]
fn stress_power_is_the_rate_of_stored_energy() {
    for k in 0..20 {
        let f = sample_f(k);
        let l = Mat2::new(0.3, -1.1, 0.7, -0.4 + 0.05 * k as f64);
        let e = 1e-6;
        let w = |m: Mat2| shear(&m, G).energy;
        let rate = (w(f + e * l * f) - w(f - e * l * f)) / (2.0 * e);
        let s = shear(&f, G).stress;
        let power = f.determinant() * (s.component_mul(&l)).sum();
        assert!(
            (rate - power).abs() < 1e-6 * G,
            "{k}: dW/dt {rate} vs J sigma:L {power}"
        );
    }
}

/// A standing elastic shear wave, v_x = v0 sin(2 pi y / L), in a periodic
/// box: kinetic energy goes to (nearly) zero a quarter period later,
/// T = L / c_s with c_s = sqrt(G / rho0), and the total energy is kept.
#[test]
fn periodic_shear_wave_has_the_exact_period_and_keeps_its_energy() {
    let size = 0.32;
    let mut material = Material::tait(1e5);
    material.shear_modulus = G;
    let mut scene = common::box_scene([size, size], [0.0, 0.0, size, size], material, 0.0);
    // 64 cells a wavelength: dispersion ~ (k h)^2 / 12 ~ 1e-3.
    scene.cell = 0.005;
    scene.periodic = [true, true];
    let method = common::method(ShapeKind::Bspline2, TransferKind::Flip, SchemeKind::Usl);
    let cfg = SolverConfig {
        scene: scene.clone(),
        method,
        perturb: vec![],
    };
    let mut ps = solver::scene::seed(&scene);
    let v0 = 1e-3;
    let k = 2.0 * std::f64::consts::PI / size;
    for p in 0..ps.len() {
        ps.v[p] = Vec2::new(v0 * (k * ps.x[p].y).sin(), 0.0);
    }
    let mut s = Solver::with_particles(cfg, ps);
    let e0 = s.energy().total();
    let kin0 = s.energy().kinetic;
    let period = size / (G / 1000.0f64).sqrt();
    // Track the kinetic energy's first minimum.
    let (mut t_min, mut kin_min) = (0.0, f64::INFINITY);
    while s.time() < 0.5 * period {
        s.step().unwrap();
        let kin = s.energy().kinetic;
        if kin < kin_min {
            (t_min, kin_min) = (s.time(), kin);
        }
    }
    let quarter = 0.25 * period;
    assert!(
        // Measured 0.6 % here (1.7 % at h = 0.01: dispersion and dt sampling).
        (t_min / quarter - 1.0).abs() < 0.01,
        "kinetic minimum at {t_min} s, exact {quarter} s"
    );
    assert!(
        kin_min < 0.01 * kin0,
        "kinetic energy at its minimum {kin_min} of {kin0}"
    );
    let drift = (s.energy().total() - e0) / kin0;
    eprintln!("quarter period {quarter:.5} s, kinetic minimum at {t_min:.5} s ({:.2e} of the initial), energy drift {drift:.2e}", kin_min / kin0);
    assert!(
        drift.abs() < 1e-3,
        "energy drift {drift} of the initial kinetic energy"
    );
    // Half a period on, the wave is back with the opposite sign.
    let view = s.view();
    let mut corr = 0.0;
    let mut norm = 0.0;
    for p in 0..view.x.len() {
        let exact = -v0 * (k * view.x[p].y).sin();
        corr += view.v[p].x * exact;
        norm += exact * exact;
    }
    eprintln!(
        "correlation with -v0 sin(ky) after half a period: {:.4}",
        corr / norm
    );
    assert!(
        corr / norm > 0.95,
        "velocity back to -v0 sin(ky): {}",
        corr / norm
    );
}

/// A solid refuses the F reset and the fluid-only J remedies, by key.
#[test]
fn solid_refuses_f_reset_and_the_fluid_j_remedies() {
    let mut material = Material::tait(1e5);
    material.shear_modulus = G;
    let scene = common::box_scene([1.0, 1.0], [0.4, 0.4, 0.6, 0.6], material, 9.81);
    let base = common::method(ShapeKind::Bspline2, TransferKind::Apic, SchemeKind::Usl);
    let with = |set: &dyn Fn(&mut RemedySettings)| {
        let mut m = base.clone();
        set(&mut m.remedies);
        m
    };
    for (method, key) in [
        (
            with(&|r| r.f_reset = Some(f_reset::Settings {})),
            "method.f_reset",
        ),
        (
            with(&|r| r.j_bar = Some(j_bar::Settings::default())),
            "method.j_bar",
        ),
        (
            with(&|r| r.cell_dilatation = Some(cell_dilatation::Settings::default())),
            "method.cell_dilatation",
        ),
        (
            with(&|r| r.pressure_smoothing = Some(pressure_smoothing::Settings {})),
            "method.pressure_smoothing",
        ),
        (
            with(&|r| r.volume_relaxation = Some(volume_relaxation::Settings { time: 0.1 })),
            "method.volume_relaxation",
        ),
        (
            with(&|r| {
                r.shifting = Some(shifting::Settings {
                    time: 0.1,
                    ..Default::default()
                })
            }),
            "method.shifting",
        ),
    ] {
        let err =
            common::refusal(scene.clone(), method).unwrap_or_else(|| panic!("{key}: accepted"));
        assert_eq!(err.key, key, "{err:?}");
    }
}

/// The history increment is the equivalent shear strain: gamma' dt in simple
/// shear, nothing for a rigid spin, objective, and sqrt(4/3) |d| dt for
/// in-plane isotropic compression (a 3D shear under plane strain).
#[test]
fn history_increment_is_the_equivalent_shear_strain() {
    let dt = 1e-3;
    let rate = 7.0;
    let simple = Mat2::new(0.0, 0.5 * rate, 0.5 * rate, 0.0);
    assert!((history_increment(&simple, dt) - rate * dt).abs() < 1e-15);
    assert_eq!(history_increment(&Mat2::zeros(), dt), 0.0);
    let planar = Mat2::new(-2.0, 0.0, 0.0, -2.0);
    let expected = (4.0f64 / 3.0).sqrt() * 2.0 * dt;
    assert!((history_increment(&planar, dt) - expected).abs() < 1e-15);
    for k in 0..10 {
        let (c, s) = ((0.7 * k as f64).cos(), (0.7 * k as f64).sin());
        let r = Mat2::new(c, -s, s, c);
        let d = Mat2::new(0.3, -0.2, -0.2, 1.1);
        let rotated = r * d * r.transpose();
        assert!((history_increment(&rotated, dt) - history_increment(&d, dt)).abs() < 1e-15);
    }
}

/// A material point in simple shear at rate gamma', stepped as the stress
/// stage steps it (F <- (I + dt L) F, xi += increment, shear part at the new
/// xi). Closed forms with G(xi) = G exp(-xi / s): xi = gamma, sigma_xy =
/// G(gamma) gamma, stored energy G(gamma) gamma^2 / 2, and the work put in,
/// int G(g) g dg = G s^2 (1 - e^(-gamma/s) (1 + gamma/s)), is what is stored
/// plus what the softening released.
#[test]
fn softening_simple_shear_meets_the_closed_forms_and_books_its_release() {
    let mut m = Material::tait(1e5);
    m.shear_modulus = G;
    let soft = 0.2;
    m.softening_strain = soft;
    let (rate, dt, steps) = (1.0, 1e-5, 100_000);
    let l = Mat2::new(0.0, rate, 0.0, 0.0);
    let d = 0.5 * (l + l.transpose());
    let vol0 = 1.0;
    let (mut f, mut xi, mut released, mut work) = (Mat2::identity(), 0.0, 0.0, 0.0);
    let mut stress = Mat2::zeros();
    let (mut wave, mut stored) = (0.0, 0.0);
    for _ in 0..steps {
        // Stress power of the step with the stress at its start.
        work += f.determinant() * vol0 * stress.component_mul(&d).sum() * dt;
        f = (Mat2::identity() + dt * l) * f;
        let before = xi;
        xi += history_increment(&d, dt);
        (stress, wave, stored) = (Mat2::zeros(), 0.0, 0.0);
        released += add_to(
            &m,
            &f,
            vol0,
            before,
            xi,
            &mut stress,
            &mut wave,
            &mut stored,
        );
    }
    let gamma = rate * dt * steps as f64;
    let g = G * (-gamma / soft).exp();
    assert!((xi - gamma).abs() < 1e-9, "xi {xi} vs gamma {gamma}");
    assert!((f[(0, 1)] - gamma).abs() < 1e-9);
    assert!((stress[(0, 1)] - g * gamma).abs() < 1e-9 * G, "{stress}");
    assert!((stored - 0.5 * g * gamma * gamma).abs() < 1e-9 * G);
    // xi is gamma up to the round-off of 1e5 additions.
    assert!((wave / (4.0 * g / 3.0 / m.rho0).sqrt() - 1.0).abs() < 1e-9);
    let input = G * soft * soft * (1.0 - (-gamma / soft).exp() * (1.0 + gamma / soft));
    let exact_release = input - 0.5 * g * gamma * gamma;
    eprintln!("gamma {gamma}: G(xi)/G {:.4e}, released {released:.6} (exact {exact_release:.6}), work {work:.6} (exact {input:.6})", g / G);
    // First order in dt: (1e-5 here) times the energies.
    assert!(
        (released - exact_release).abs() < 1e-4 * input,
        "released {released} vs {exact_release}"
    );
    assert!(
        (work - (stored + released)).abs() < 1e-4 * input,
        "work {work} vs stored + released {}",
        stored + released
    );
    // Without softening nothing is released and xi does not move.
    m.softening_strain = 0.0;
    let plain = add_to(&m, &f, vol0, 0.0, 0.5, &mut stress, &mut wave, &mut stored);
    assert_eq!(plain, 0.0);
    assert_eq!(m.shear_modulus_at(10.0), G);
}

/// A block of solid on the floor: with its full shear modulus it stands
/// (elastic sag only), with `softening_strain` below its elastic strain
/// (rho g H / G ~ 1 %) it softens, collapses and runs out like the fluid it
/// becomes. Either way the energy budget (with the released energy booked as
/// dissipated) does not grow.
#[test]
fn a_block_stands_as_a_solid_and_flows_once_softened() {
    let run = |shear_modulus: f64, softening: f64| {
        let mut material = Material::tait(1e6);
        material.shear_modulus = shear_modulus;
        material.viscosity = 0.1;
        material.softening_strain = softening;
        let mut scene = common::box_scene([1.0, 0.4], [0.0, 0.0, 0.2, 0.2], material, 9.81);
        scene.cell = 0.01;
        let method = Method {
            cfl: 0.3,
            dt: DtMode::Dynamic,
            ..common::method(ShapeKind::Bspline2, TransferKind::Apic, SchemeKind::Usl)
        };
        let mut s = common::solver(scene, method);
        let e0 = s.energy().total();
        let start = s.view().x.iter().map(|x| x.x).fold(0.0, f64::max);
        let mut growth: f64 = 0.0;
        // Before a fluid's front reaches the far wall.
        while s.time() < 0.3 {
            s.step().unwrap();
            growth = growth.max(s.energy().total() - e0);
        }
        let v = s.view();
        let front = v.x.iter().map(|x| x.x).fold(0.0, f64::max);
        let mean_xi = v.history.iter().sum::<f64>() / v.history.len() as f64;
        (front - start, mean_xi, growth, s.energy(), e0)
    };
    let (fluid_runout, ..) = run(0.0, 0.0);
    let (runout, xi, growth, e, e0) = run(2e5, 0.0);
    eprintln!("fluid: run-out {fluid_runout:.3} m; solid: run-out {runout:.4} m, mean xi {xi}, energy growth {growth:.3e} J of {e0:.3e}");
    assert!(runout < 0.005, "the solid block ran out {runout} m");
    assert_eq!(xi, 0.0);
    assert!(
        growth <= 1e-6 * e.gravitational.abs().max(1.0),
        "energy grew {growth}"
    );
    let (runout, xi, growth, e, e0) = run(2e5, 0.005);
    let fell = e0 - (e.gravitational + e.stored + e.kinetic);
    eprintln!("softened: run-out {runout:.3} m, mean xi {xi:.3}, energy growth {growth:.3e} J, dissipated {:.3} J, total drop {fell:.3} J", e.dissipated);
    // Softening only delays the collapse: behind the fluid, not far behind.
    assert!(
        runout < fluid_runout && runout > 0.8 * fluid_runout,
        "the softened block ran out {runout} m, the fluid {fluid_runout} m"
    );
    assert!(
        xi > 5.0 * 0.005,
        "mean xi {xi}: the shear modulus is not gone"
    );
    assert!(growth <= 1e-3 * fell, "energy grew {growth} J of {fell} J");
}
