//! A standing acoustic wave in a periodic box oscillates with the period
//! L / c that the EOS's tangent modulus predicts (c = sqrt(K_t / rho0) at J = 1).

use solver::*;

use crate::common;

/// Period from the zero crossings of the mode amplitude sum m v_x sin(2 pi x / L).
fn measured_period(eos: EosKind, gamma: f64, k: f64) -> (f64, f64) {
    let length = 0.5;
    let mut mat = Material::tait(k);
    mat.eos = eos;
    mat.gamma = gamma;
    let c = mat.wave_speed(1.0);
    let mut scene = common::box_scene([length, 0.04], [0.0, 0.0, length, 0.04], mat, 0.0);
    scene.periodic = [true, true];
    let wave = 2.0 * std::f64::consts::PI / length;
    let mut ps = scene::seed(&scene);
    for p in 0..ps.len() {
        ps.v[p] = Vec2::new(1e-4 * c * (wave * ps.x[p].x).sin(), 0.0);
    }
    let mut method = common::method(ShapeKind::Bspline2, TransferKind::Apic, SchemeKind::Usf);
    method.cfl = 0.1;
    let mut s = Solver::with_particles(
        SolverConfig {
            scene,
            method,
            perturb: vec![],
        },
        ps,
    );
    let amplitude = |v: &StateView| -> f64 {
        (0..v.x.len())
            .map(|p| v.mass[p] * v.v[p].x * (wave * v.x[p].x).sin())
            .sum()
    };
    let mut crossings = vec![];
    let mut prev = (0.0, amplitude(&s.view()));
    while crossings.len() < 5 {
        s.step().unwrap();
        let v = s.view();
        let a = amplitude(&v);
        if prev.1 * a < 0.0 {
            // Linear interpolation of the crossing time.
            crossings.push(prev.0 + (v.time - prev.0) * prev.1 / (prev.1 - a));
        }
        prev = (v.time, a);
    }
    let half_periods = (crossings[4] - crossings[0]) / 4.0;
    (2.0 * half_periods, length / c)
}

#[test]
fn standing_wave_period_matches_tangent_modulus() {
    for (eos, gamma, k) in [
        (EosKind::Tait, 7.0, 1.5e5),
        (EosKind::Power, 7.0, 1.5e4),
        (EosKind::Power, 1.0, 1.5e5),
    ] {
        let (measured, predicted) = measured_period(eos, gamma, k);
        let err = (measured / predicted - 1.0).abs();
        assert!(
            err < 0.02,
            "{eos:?} gamma {gamma}: {measured} vs {predicted} ({err})"
        );
    }
}
