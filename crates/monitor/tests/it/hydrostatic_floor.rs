//! The hydrostatic floor: the exact rest field of a flat layer,
//! scored through the same departure metric. Zero on an EOS-consistent
//! lattice, positive on a disordered one, equal to the departure when the
//! pressure is the rest field itself; mass-conserving; all zero without
//! gravity.

use monitor::hydrostatic::Hydrostatic;
use monitor::Geometry;
use solver::particles::Particles;
use solver::{scene, EosKind, Material, Scene, Vec2};

const TAIT_C: f64 = 0.0894;
const G: f64 = 9.81;
const RHO0: f64 = 1000.0;

fn material(eos: EosKind, k: f64) -> Material {
    let mut m = Material::tait(k);
    m.eos = eos;
    m.gamma = 7.0;
    m
}

/// integral_0^p J(p') dp' in closed form, for Tait and the power law.
fn integral_of_j(m: &Material, p: f64) -> f64 {
    match m.eos {
        EosKind::Tait => {
            let u = 1.0 + p / (TAIT_C * m.k);
            p - TAIT_C * TAIT_C * m.k * (u * u.ln() - u + 1.0)
        }
        EosKind::Power => {
            let e = (m.gamma - 1.0) / m.gamma;
            m.k / e * ((1.0 + p / m.k).powf(e) - 1.0)
        }
        EosKind::Linear => p - p * p / (2.0 * m.k),
    }
}

/// A column 0.2 m wide, 0.4 m high, filling its box's width.
fn column_scene(mat: Material, ppc: usize) -> Scene {
    let mut sc = Scene::dam_break(mat);
    sc.size = [0.2, 0.6];
    sc.bodies[0].rect = [0.0, 0.0, 0.2, 0.4];
    sc.ppc = ppc;
    sc
}

/// The column's lattice at its EOS-consistent rest heights: positions,
/// masses, volumes and the exact pressures rho0 g (H0 - Y).
fn rest_lattice(sc: &Scene, m: &Material) -> (Vec<Vec2>, Vec<f64>, Vec<f64>, Vec<f64>) {
    let l = sc.cell / sc.ppc as f64;
    let (w, h0) = (sc.bodies[0].rect[2], sc.bodies[0].rect[3]);
    let (columns, rows) = ((w / l).round() as usize, (h0 / l).round() as usize);
    let depth = |p: f64| integral_of_j(m, p) / (RHO0 * G);
    let surface = depth(RHO0 * G * h0);
    let (mut x, mut mass, mut vol, mut pressure) = (vec![], vec![], vec![], vec![]);
    for i in 0..columns {
        for k in 0..rows {
            let y_ref = (k as f64 + 0.5) * l;
            let p = RHO0 * G * (h0 - y_ref);
            x.push(Vec2::new((i as f64 + 0.5) * l, surface - depth(p)));
            mass.push(RHO0 * l * l);
            vol.push(m.j_at_pressure(p) * l * l);
            pressure.push(p);
        }
    }
    (x, mass, vol, pressure)
}

#[test]
fn the_closed_form_depth_uses_the_solvers_eos() {
    for eos in [EosKind::Tait, EosKind::Power] {
        let m = material(eos, 1.5e4);
        // d/dp of the closed form is J(p).
        let (p, dp) = (3000.0, 1e-3);
        let slope = (integral_of_j(&m, p + dp) - integral_of_j(&m, p - dp)) / (2.0 * dp);
        assert!(
            (slope - m.j_at_pressure(p)).abs() < 1e-8,
            "{eos:?}: {slope}"
        );
    }
}

#[test]
fn floor_and_departure_vanish_on_a_compressible_rest_lattice() {
    for eos in [EosKind::Tait, EosKind::Power] {
        for ppc in [2, 3] {
            let m = material(eos, 1.5e4);
            let sc = column_scene(m.clone(), ppc);
            let g = Geometry::from_scene(&sc);
            let (x, mass, vol, pressure) = rest_lattice(&sc, &m);
            let j_bottom = m.j_at_pressure(RHO0 * G * 0.4);
            assert!(
                j_bottom < 0.97,
                "{eos:?}: compressibility shows, J {j_bottom}"
            );
            let mut h = Hydrostatic::new(&g, x.len());
            h.compute(&g, &x, &mass, &vec![Vec2::zeros(); x.len()]);
            let scale = RHO0 * G * 0.4;
            for (rest, exact) in h.rest.pressure.iter().zip(&pressure) {
                assert!(
                    (rest - exact).abs() < 1e-10 * scale,
                    "{eos:?} ppc {ppc}: {rest} vs {exact}"
                );
            }
            let d = h.departure(&g, &vol, &pressure);
            assert!(d.rel_rms < 1e-10, "{eos:?} ppc {ppc}: {d:?}");
            assert!(d.floor_rel_rms < 1e-10, "{eos:?} ppc {ppc}: {d:?}");
            assert!(d.excess_rel_rms < 1e-6, "{eos:?} ppc {ppc}: {d:?}");
        }
    }
}

/// A dam-break lattice (column a quarter of the box wide) with each
/// particle moved by up to `jitter` h: a disordered arrangement.
fn jittered(mat: Material, ppc: usize, jitter: f64) -> (Geometry, Particles) {
    let mut sc = Scene::dam_break(mat);
    sc.ppc = ppc;
    sc.jitter = jitter;
    sc.seed = 7;
    (Geometry::from_scene(&sc), scene::seed(&sc))
}

#[test]
fn the_layer_holds_the_particles_mass_and_its_bottom_carries_their_weight() {
    for eos in [EosKind::Tait, EosKind::Power] {
        let m = material(eos, 1.5e4);
        let (g, ps) = jittered(m.clone(), 2, 0.3);
        let mut h = Hydrostatic::new(&g, ps.len());
        h.compute(&g, &ps.x, &ps.mass, &vec![Vec2::zeros(); ps.len()]);
        let per_width = ps.mass.iter().sum::<f64>() / g.size.x;
        let bottom = h.rest.pressure_at(&g, g.origin.y);
        assert!((bottom - G * per_width).abs() < 1e-12 * G * per_width);
        assert!((h.rest.bottom_pressure - G * per_width).abs() < 1e-12 * G * per_width);
        // Mass per unit width: integral of rho0 / J(p_rest) over the layer (Simpson).
        let top = h.rest.surface_height;
        let n = 4000;
        let dy = top / n as f64;
        let density = |k: usize| {
            let y = g.origin.y + k as f64 * dy;
            RHO0 / m.j_at_pressure(h.rest.pressure_at(&g, y))
        };
        let weight = |k: usize| match k {
            0 => 1.0,
            k if k == n => 1.0,
            k if k % 2 == 1 => 4.0,
            _ => 2.0,
        };
        let mass: f64 = (0..=n).map(|k| weight(k) * density(k)).sum::<f64>() * dy / 3.0;
        assert!(
            (mass - per_width).abs() < 1e-9 * per_width,
            "{eos:?}: {mass} vs {per_width}"
        );
        // Compressed: thinner than the same mass at rho0.
        assert!(top < per_width / RHO0, "{eos:?}: {top}");
        assert_eq!(h.rest.pressure_at(&g, g.origin.y + top + 1e-6), 0.0);
    }
}

#[test]
fn on_a_disordered_arrangement_the_rest_field_scores_the_floor() {
    let m = material(EosKind::Tait, 1.5e6);
    let (g, ps) = jittered(m, 2, 0.3);
    let n = ps.len();
    let mut h = Hydrostatic::new(&g, n);
    h.compute(&g, &ps.x, &ps.mass, &vec![Vec2::zeros(); n]);
    let rest = h.rest.pressure[..n].to_vec();
    let d = h.departure(&g, &ps.vol, &rest);
    assert!(d.floor_rel_rms > 1e-3, "{d:?}");
    assert!((d.rel_rms - d.floor_rel_rms).abs() < 1e-14, "{d:?}");
    assert!(d.excess_rel_rms < 1e-6, "{d:?}");
    // Noise of 2 % of rho0 g H on top of the rest field.
    let mut state = 11u64;
    let noisy: Vec<f64> = rest
        .iter()
        .map(|p| p + 0.02 * RHO0 * G * 0.4 * (2.0 * scene::uniform01(&mut state) - 1.0))
        .collect();
    let noisy_d = h.departure(&g, &ps.vol, &noisy);
    assert_eq!(noisy_d.floor_rel_rms, d.floor_rel_rms);
    assert!(noisy_d.rel_rms >= noisy_d.floor_rel_rms, "{noisy_d:?}");
    assert!(noisy_d.excess_rel_rms > 1e-3, "{noisy_d:?}");
    let recombined = (noisy_d.floor_rel_rms.powi(2) + noisy_d.excess_rel_rms.powi(2)).sqrt();
    assert!((recombined - noisy_d.rel_rms).abs() < 1e-12, "{noisy_d:?}");
}

#[test]
fn without_gravity_everything_is_zero() {
    let mut m = material(EosKind::Tait, 1.5e4);
    m.rho0 = RHO0;
    let mut sc = Scene::dam_break(m);
    sc.gravity = 0.0;
    sc.jitter = 0.3;
    let g = Geometry::from_scene(&sc);
    let ps = scene::seed(&sc);
    let mut h = Hydrostatic::new(&g, ps.len());
    h.compute(&g, &ps.x, &ps.mass, &vec![Vec2::zeros(); ps.len()]);
    assert!(h.rest.pressure.iter().all(|&p| p == 0.0));
    assert_eq!(h.rest.surface_height, 0.0);
    let d = h.departure(&g, &ps.vol, &vec![0.0; ps.len()]);
    assert_eq!(
        (d.rel_rms, d.floor_rel_rms, d.excess_rel_rms),
        (0.0, 0.0, 0.0)
    );
}
