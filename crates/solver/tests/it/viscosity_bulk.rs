//! Artificial bulk viscosity (`[method.bulk_damping] coefficient`): its stress and power,
//! and a standing acoustic wave in a periodic box that loses its energy at
//! the linear-theory rate nu k^2 (nu = b c h), with the budget closed.

use crate::common;

use solver::viscosity::bulk;
use solver::*;

#[test]
fn bulk_stress_is_isotropic_and_its_power_is_sigma_d() {
    let d = Mat2::new(-2.0, 0.7, 0.3, 0.5);
    let (s, power) = bulk(3.0, &d);
    assert_eq!(s, Mat2::identity() * (3.0 * -1.5));
    assert!((power - s.component_mul(&d).sum()).abs() < 1e-12);
    assert!(power > 0.0);
}

/// Mechanical energy (kinetic + stored) of a standing wave v_x = v0 sin(k x)
/// after one period, over its start, and the budget's drift.
fn wave(b: f64) -> (f64, f64, f64) {
    let size = 0.32;
    let mut material = Material::tait(1e5);
    material.viscosity = 0.0;
    let mut scene = common::box_scene([size, size], [0.0, 0.0, size, size], material, 0.0);
    scene.cell = 0.005;
    scene.periodic = [true, true];
    let mut method = common::method(ShapeKind::Bspline2, TransferKind::Flip, SchemeKind::Usl);
    method.remedies.bulk_damping =
        (b > 0.0).then_some(solver::remedies::bulk_damping::Settings { coefficient: b });
    let cfg = SolverConfig {
        scene: scene.clone(),
        method,
        perturb: vec![],
    };
    let mut ps = solver::scene::seed(&scene);
    let k = 2.0 * std::f64::consts::PI / size;
    for p in 0..ps.len() {
        ps.v[p] = Vec2::new(1e-3 * (k * ps.x[p].x).sin(), 0.0);
    }
    let mut s = Solver::with_particles(cfg, ps);
    let c = (1e5f64 / 1000.0).sqrt();
    let period = size / c;
    let e0 = s.energy();
    while s.time() < period {
        s.step().unwrap();
    }
    let e = s.energy();
    let mech = |e: &Energy| e.kinetic + e.stored;
    let nu_k2_t = b * c * 0.005 * k * k * s.time();
    (
        mech(&e) / mech(&e0),
        (-nu_k2_t).exp(),
        (e.total() - e0.total()) / mech(&e0),
    )
}

#[test]
fn standing_wave_decays_at_the_linear_theory_rate() {
    let (kept, _, drift) = wave(0.0);
    eprintln!("b = 0: energy kept {kept:.5}, budget drift {drift:.2e}");
    assert!((kept - 1.0).abs() < 2e-3, "undamped wave kept {kept}");
    for b in [0.2, 0.5] {
        let (ratio, exact, drift) = wave(b);
        eprintln!(
            "b = {b}: energy ratio {ratio:.4}, exp(-nu k^2 t) {exact:.4}, budget drift {drift:.2e}"
        );
        assert!(
            (ratio / exact - 1.0).abs() < 0.03,
            "b {b}: {ratio} vs {exact}"
        );
        assert!(drift.abs() < 2e-3, "b {b}: budget drift {drift}");
    }
}
