//! XPIC(m) (Hammerquist & Nairn 2017): XPIC(1) is PIC, and on the 2 x 2
//! lattice with linear shapes a checkerboard velocity V = S u comes back as
//! (1 - (15/16)^m) V: PIC keeps 1/16 of it, large m nearly all.

use crate::common;

use solver::*;

const H: f64 = 0.1;

/// A periodic 8 x 8-cell box filled at 2 x 2 ppc, no gravity, a nearly
/// stress-free material and a tiny step, particles moving with the grid
/// checkerboard u_i = (-1)^(i + j) e_x interpolated: V = S u.
fn checkerboard(transfer: TransferKind, order: u32) -> Solver {
    let mut material = Material::tait(1.0);
    material.viscosity = 0.0;
    let mut scene = common::box_scene([0.8, 0.8], [0.0, 0.0, 0.8, 0.8], material, 0.0);
    scene.cell = H;
    scene.periodic = [true, true];
    let method = Method {
        dt_value: Some(1e-9),
        xpic_order: order,
        ..common::method(ShapeKind::Linear, transfer, SchemeKind::Usl)
    };
    let cfg = SolverConfig {
        scene: scene.clone(),
        method,
        perturb: vec![],
    };
    let mut ps = solver::scene::seed(&scene);
    for (x, v) in ps.x.iter().zip(ps.v.iter_mut()) {
        *v = common::lattice_checkerboard(*x, H);
    }
    Solver::with_particles(cfg, ps)
}

#[test]
fn xpic_keeps_one_minus_fifteen_sixteenths_to_the_m_of_a_checkerboard() {
    for (transfer, order) in [
        (TransferKind::Pic, 1),
        (TransferKind::Xpic, 1),
        (TransferKind::Xpic, 2),
        (TransferKind::Xpic, 5),
    ] {
        let mut s = checkerboard(transfer, order);
        let before: Vec<f64> = s.view().v.iter().map(|v| v.x).collect();
        assert!(
            before.iter().all(|v| (v.abs() - 0.25).abs() < 1e-12),
            "|S u| = 1/4 on the lattice"
        );
        s.step().unwrap();
        let kept = 1.0 - (15.0f64 / 16.0).powi(order as i32);
        let v = s.view();
        for (p, v0) in before.iter().enumerate() {
            let ratio = v.v[p].x / v0;
            assert!(
                (ratio - kept).abs() < 1e-6,
                "{transfer:?}({order}) particle {p}: kept {ratio}, expected {kept}"
            );
            assert!(v.v[p].y.abs() < 1e-9);
        }
    }
}

#[test]
fn xpic_one_is_pic_up_to_round_off() {
    let run = |transfer: TransferKind| {
        let mut mat = Material::tait(1.5e5);
        mat.viscosity = 0.5;
        let method = Method {
            xpic_order: 1,
            ..common::method(ShapeKind::Bspline2, transfer, SchemeKind::Usl)
        };
        let mut s = common::solver(Scene::dam_break(mat), method);
        for _ in 0..200 {
            s.step().unwrap();
        }
        s
    };
    let (pic, xpic) = (run(TransferKind::Pic), run(TransferKind::Xpic));
    let (a, b) = (pic.view(), xpic.view());
    let worst =
        a.x.iter()
            .zip(b.x)
            .map(|(p, q)| (p - q).norm())
            .fold(0.0, f64::max);
    let fastest = a.v.iter().map(|v| v.norm()).fold(0.0, f64::max);
    assert!(fastest > 0.1, "{fastest}");
    assert!(worst < 1e-12, "positions differ by {worst} m");
}
