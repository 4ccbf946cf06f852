//! A column initialised in discrete hydrostatic equilibrium stays at rest, with
//! particle pressure close to docs/physics.md's clamped mass-above reference.

use solver::*;

use crate::common;

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

/// The dam-break column of docs/physics.md section 1 (0.8 m tank), Tait 1.5 MPa.
fn dam_break_scene(initial: InitialState) -> Scene {
    let mut mat = Material::tait(1.5e6);
    mat.eos = EosKind::Tait;
    mat.viscosity = 0.5;
    let mut scene = common::box_scene([0.8, 0.6], [0.0, 0.0, 0.2, 0.4], mat, 9.81);
    scene.initial = initial;
    scene.t_end = 0.05;
    scene
}

#[test]
fn a_gated_column_stands_hydrostatic_at_rest_until_the_gate_is_lifted() {
    let method = common::method(ShapeKind::Bspline2, TransferKind::Apic, SchemeKind::Usl);
    let mut s = common::solver(
        dam_break_scene(InitialState::HydrostaticGate),
        method.clone(),
    );
    let v = s.view();
    let reference = reference_pressure(&v);
    let x_max = v.x.iter().map(|x| x.x).fold(f64::MIN, f64::max);
    let speed = common::max_speed(&v);
    let all = relative_rms(&v, &reference, |_| true);
    eprintln!("gated: x_max {x_max:.5} m, speed {speed:.1e}, pressure rel RMS {all:.4}");
    // Behind the gate at x = 0.2 m (the last particle column sits l / 2 inside it).
    assert!(x_max < 0.2 - 0.2 * v.scene.cell, "x_max {x_max}");
    assert_eq!(speed, 0.0);
    assert!(all < 0.005, "relative RMS {all}");

    // Relaxed without the gate the column has already begun to slump, and its
    // pressure is nowhere near hydrostatic: what the gate is for.
    let open = common::solver(dam_break_scene(InitialState::Hydrostatic), method);
    let v = open.view();
    let open_rms = relative_rms(&v, &reference_pressure(&v), |_| true);
    let open_x = v.x.iter().map(|x| x.x).fold(f64::MIN, f64::max);
    eprintln!("no gate: x_max {open_x:.5} m, pressure rel RMS {open_rms:.4}");
    assert!(open_x > 0.2 && open_rms > 0.2);

    // Lifted at t = 0: the column collapses.
    while !s.finished() {
        s.step().unwrap();
    }
    let x_max = s.view().x.iter().map(|x| x.x).fold(f64::MIN, f64::max);
    assert!(
        x_max > 0.2 + s.view().scene.cell,
        "front after 0.05 s: {x_max}"
    );
}

#[test]
fn a_gate_off_the_cell_lines_is_refused() {
    let mut scene = dam_break_scene(InitialState::HydrostaticGate);
    scene.bodies[0].rect[2] = 0.205;
    let err = common::refusal(scene, Method::baseline()).unwrap();
    assert_eq!(err.key, "scene.initial");
    assert!(err.message.contains("right edge"), "{}", err.message);
}
