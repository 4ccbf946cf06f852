//! The clamped mass-above reference is exact (to round-off) on a hydrostatic
//! lattice of any compressibility and any ppc, and matches a hand computation
//! on a perturbed column.

use monitor::hydrostatic::Hydrostatic;
use monitor::Geometry;
use solver::{scene, EosKind, InitialState, Material, Scene, Vec2};

#[test]
fn exact_on_hydrostatic_lattices() {
    for (eos, gamma, k) in [
        (EosKind::Tait, 7.0, 1.5e4),
        (EosKind::Tait, 7.0, 1.5e7),
        (EosKind::Power, 7.0, 1.5e5),
        (EosKind::Power, 1.0, 6e3),
    ] {
        for ppc in [1, 2, 3, 4] {
            let mut mat = Material::tait(k);
            mat.eos = eos;
            mat.gamma = gamma;
            let mut sc = Scene::dam_break(mat);
            sc.ppc = ppc;
            sc.initial = InitialState::Hydrostatic;
            // Seeding alone (no relaxation) is the exact lattice: rows spaced by J.
            let ps = scene::seed(&sc);
            let j_min = ps.j.iter().cloned().fold(1.0, f64::min);
            let g = Geometry::from_scene(&sc);
            let mut h = Hydrostatic::new(&g, ps.len());
            h.compute(&g, &ps.x, &ps.mass, &vec![Vec2::zeros(); ps.len()]);
            let d = h.departure(&g, &ps.vol, &ps.pressure);
            assert!(
                d.rel_rms < 1e-13,
                "{eos:?} K {k} ppc {ppc} (J min {j_min}): {d:?}"
            );
            assert!(d.max < 1e-12, "{eos:?} K {k} ppc {ppc}: {d:?}");
            if k < 1e4 {
                // Rows 40 % closer than the reference spacing, still above l / 2.
                assert!(
                    j_min < 0.65,
                    "the soft case really is compressed: J min {j_min}"
                );
            }
        }
    }
}

#[test]
fn matches_hand_computation_on_a_perturbed_column() {
    // One strip, ppc 1 (l = h), three particles of mass m; the middle one is
    // lifted to a quarter row below the top one.
    let mut sc = Scene::dam_break(Material::tait(1e5));
    sc.ppc = 1;
    sc.bodies[0].rect = [0.0, 0.0, 0.01, 0.03];
    let g = Geometry::from_scene(&sc);
    let (h, m) = (0.01, 0.1);
    let x = vec![
        Vec2::new(0.005, 0.5 * h),
        Vec2::new(0.005, 2.25 * h),
        Vec2::new(0.005, 2.5 * h),
    ];
    let mass = vec![m; 3];
    let mut hyd = Hydrostatic::new(&g, 3);
    hyd.compute(&g, &x, &mass, &[Vec2::zeros(); 3]);
    let gh = 9.81 / h;
    // bottom: 1/2 (self) + 1 + 1; middle: 1/2 + clamp(0.25 + 0.5) = 1.25;
    // top: 1/2 + clamp(-0.25 + 0.5) = 0.75.
    let expected = [2.5 * m * gh, 1.25 * m * gh, 0.75 * m * gh];
    for (r, e) in hyd.reference.iter().zip(expected) {
        assert!((r - e).abs() < 1e-12 * e, "{r} vs {e}");
    }
    // Lattice pressures (k + 1/2) rho0 g l with rho0 l^2 = m: 2.5, 1.5, 0.5 (x m g / h).
    let pressure = [2.5 * m * gh, 1.5 * m * gh, 0.5 * m * gh];
    let volume = [1.0, 2.0, 1.0];
    let d = hyd.departure(&g, &volume, &pressure);
    let num: f64 = (0..3)
        .map(|k| volume[k] * (pressure[k] - expected[k]).powi(2))
        .sum();
    let den: f64 = (0..3).map(|k| volume[k] * expected[k].powi(2)).sum();
    assert!((d.rel_rms - (num / den).sqrt()).abs() < 1e-14);
    // max |p - p_h| = 0.25 m g / h over rho0 g H with H = 0.03 m.
    let max = 0.25 * m * gh / (1000.0 * 9.81 * 0.03);
    assert!((d.max - max).abs() < 1e-12, "{} vs {max}", d.max);
}

#[test]
fn vertical_acceleration_scales_the_explained_pressure() {
    // A hydrostatic lattice in a lift accelerating at a: p = rho (g + a) depth.
    // The hydrostatic departure is |a| / g; the accelerations explain all of it.
    let mut sc = Scene::dam_break(Material::tait(1.5e6));
    sc.initial = InitialState::Hydrostatic;
    let ps = scene::seed(&sc);
    let g = Geometry::from_scene(&sc);
    let mut h = Hydrostatic::new(&g, ps.len());
    for a in [-9.81, -3.0, 4.5] {
        let accel = vec![Vec2::new(0.7, a); ps.len()];
        h.compute(&g, &ps.x, &ps.mass, &accel);
        let scale = (9.81 + a) / 9.81;
        for (pa, ph) in h.with_accel.iter().zip(&h.reference) {
            assert!(
                (pa - scale * ph).abs() <= 1e-12 * ph.abs().max(1.0),
                "{pa} vs {scale} x {ph}"
            );
        }
        let pressure: Vec<f64> = ps.pressure.iter().map(|p| scale * p).collect();
        let d = h.departure(&g, &ps.vol, &pressure);
        assert!((d.rel_rms - (a / 9.81).abs()).abs() < 1e-12, "a {a}: {d:?}");
        assert!(d.unexplained_rel_rms < 1e-12, "a {a}: {d:?}");
        // At rest-level pressure in a falling lift, all of the departure is unexplained.
        let d = h.departure(&g, &ps.vol, &ps.pressure);
        assert!(
            (d.unexplained_rel_rms - (a / 9.81).abs()).abs() < 1e-12,
            "a {a}: {d:?}"
        );
    }
}
