//! A column initialised in discrete hydrostatic equilibrium stays at rest, with
//! particle pressure close to docs/physics.md's clamped mass-above reference.

use solver::*;

mod common;

/// docs/physics.md section 4: p_h = (g / h) sum_{q in strip} m_q clamp((y_q - y_p) / l + 1/2, 0, 1).
fn reference_pressure(v: &StateView) -> Vec<f64> {
    let h = v.scene.cell;
    let l = h / v.scene.ppc as f64;
    let g = v.scene.gravity;
    let strip = |x: f64| ((x - v.scene.origin[0]) / h).floor() as i64;
    (0..v.x.len())
        .map(|p| {
            let s = strip(v.x[p].x);
            let above: f64 = (0..v.x.len())
                .filter(|&q| strip(v.x[q].x) == s)
                .map(|q| v.mass[q] * ((v.x[q].y - v.x[p].y) / l + 0.5).clamp(0.0, 1.0))
                .sum();
            g / h * above
        })
        .collect()
}

fn relative_rms(v: &StateView, reference: &[f64], keep: impl Fn(usize) -> bool) -> f64 {
    let (mut num, mut den) = (0.0, 0.0);
    for p in (0..v.x.len()).filter(|&p| keep(p)) {
        num += v.volume[p] * (v.pressure[p] - reference[p]).powi(2);
        den += v.volume[p] * reference[p].powi(2);
    }
    (num / den).sqrt()
}

#[test]
fn hydrostatic_column_stays_at_rest() {
    let mut mat = Material::tait(1.5e6);
    mat.eos = EosKind::Tait;
    mat.viscosity = 0.5;
    let mut scene = common::box_scene([0.2, 0.6], [0.0, 0.0, 0.2, 0.4], mat, 9.81);
    scene.initial = InitialState::Hydrostatic;
    scene.t_end = 1.0;
    let mut s = common::solver(
        scene,
        common::method(ShapeKind::Bspline2, TransferKind::Pic, SchemeKind::Usf),
    );
    let mut vmax: f64 = 0.0;
    while !s.finished() {
        s.step().unwrap();
        let v = s.view();
        vmax = v.v.iter().map(|u| u.norm()).fold(vmax, f64::max);
    }
    let v = s.view();
    let reference = reference_pressure(&v);
    let h = v.scene.cell;
    let far_from_walls = |p: usize| {
        let x = v.x[p];
        x.x > 2.0 * h && x.x < 0.2 - 2.0 * h && x.y > 2.0 * h
    };
    let interior = relative_rms(&v, &reference, far_from_walls);
    let all = relative_rms(&v, &reference, |_| true);
    eprintln!("max speed {vmax:.3e} m/s, pressure rel RMS interior {interior:.4}, all {all:.4}");
    assert!(vmax < 1e-2, "max speed {vmax}");
    assert!(interior < 0.02, "interior relative RMS {interior}");
    assert!(all < 0.10, "overall relative RMS {all}");
}
