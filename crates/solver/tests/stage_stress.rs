//! Deformation bookkeeping: J = det F for both J updates, V = V0 J, and the
//! stress is -p(J) I + 2 mu dev(D) with the pressure of the EOS.

use solver::*;

mod common;

#[test]
fn j_tracks_det_f_for_both_updates() {
    for j_update in [JUpdate::Det, JUpdate::Exp] {
        let mut mat = Material::water(1.5e4);
        mat.viscosity = 0.5;
        let mut method = common::method(ShapeKind::Bspline2, TransferKind::Apic, SchemeKind::Usf);
        method.j_update = j_update;
        let mut s = common::solver(Scene::dam_break(mat.clone()), method);
        let mut j_min: f64 = 1.0;
        for _ in 0..1500 {
            s.step().unwrap();
        }
        let v = s.view();
        for p in 0..v.x.len() {
            let det = v.deformation[p].determinant();
            assert!(
                (det - v.j[p]).abs() < 1e-12,
                "{j_update:?}: det F {det} vs J {}",
                v.j[p]
            );
            assert!((v.volume[p] - v.volume0[p] * v.j[p]).abs() < 1e-15);
            assert_eq!(v.pressure[p], mat.pressure(v.j[p]));
            j_min = j_min.min(v.j[p]);
        }
        assert!(j_min < 1.0 && j_min > 0.5, "{j_update:?}: J min {j_min}");
    }
}

#[test]
fn perturbation_adds_dv_after_g2p_of_its_step() {
    let mut scene = common::box_scene([0.4, 0.4], [0.1, 0.1, 0.3, 0.3], Material::water(1e5), 0.0);
    scene.periodic = [true, true];
    let region = [0.15, 0.15, 0.2, 0.2];
    let cfg = SolverConfig {
        scene,
        method: common::method(ShapeKind::Bspline2, TransferKind::Pic, SchemeKind::Usf),
        perturb: vec![Perturb {
            step: 3,
            region,
            dv: [1.0, -0.5],
        }],
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
