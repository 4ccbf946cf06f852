//! `method.quadrature = "mixed"` (docs/physics.md section 5): in cells full
//! of material the internal force is integrated at fixed points, so it no
//! longer depends on how the material points are arranged there.

use crate::common;

use solver::*;

/// A box filled with fluid at one uniform pressure (J = 0.98, linear EOS:
/// p = 2 kPa), its material points jittered by 0.3 of their spacing, no
/// gravity: the largest nodal acceleration after the stress and one P2G,
/// over the scale p / (rho0 h) = 40 m/s^2.
fn uniform_pressure_push(quadrature: QuadratureKind, periodic: bool) -> f64 {
    let mut material = Material::tait(1e5);
    material.eos = EosKind::Linear;
    let mut scene = common::box_scene([1.0, 1.0], [0.0, 0.0, 1.0, 1.0], material, 0.0);
    scene.cell = 0.05;
    scene.periodic = [periodic; 2];
    let method = Method {
        quadrature,
        ..common::method(ShapeKind::Bspline2, TransferKind::Pic, SchemeKind::Usl)
    };
    let mut ps = solver::scene::seed(&scene);
    let mut state = 11u64;
    let spacing = scene.cell / scene.ppc as f64;
    for p in 0..ps.len() {
        let jx = solver::scene::uniform01(&mut state) - 0.5;
        let jy = solver::scene::uniform01(&mut state) - 0.5;
        ps.x[p] += Vec2::new(jx, jy) * (0.6 * spacing);
        ps.j[p] = 0.98;
        ps.f[p] = Mat2::identity() * 0.98f64.sqrt();
        ps.vol[p] = ps.vol0[p] * 0.98;
    }
    let cfg = SolverConfig {
        scene,
        method,
        perturb: vec![],
    };
    let mut s = Solver::with_particles(cfg, ps);
    // Zero grid velocity: the stress stage sets sigma = -p I and leaves J.
    s.run_stage(Stage::Sort).unwrap();
    s.run_stage(Stage::Stress).unwrap();
    s.run_stage(Stage::P2g).unwrap();
    s.run_stage(Stage::Grid).unwrap();
    let v = s.view();
    assert!(
        (v.pressure[0] - 2000.0).abs() < 1e-6,
        "p = {}",
        v.pressure[0]
    );
    let g = &v.grid;
    let max = g
        .active
        .iter()
        .map(|&n| g.acceleration[n as usize].norm())
        .fold(0.0, f64::max);
    max / 40.0
}

#[test]
fn a_uniform_pressure_pushes_no_node_of_a_full_region_however_its_points_lie() {
    for periodic in [true, false] {
        let particles = uniform_pressure_push(QuadratureKind::Particles, periodic);
        let mixed = uniform_pressure_push(QuadratureKind::Mixed, periodic);
        // The material points' own quadrature sees their disorder.
        assert!(
            particles > 0.05,
            "periodic {periodic}: particles {particles}"
        );
        assert!(mixed < 1e-12, "periodic {periodic}: mixed {mixed}");
    }
}

#[test]
fn mixed_integration_is_refused_for_gimp_mls_and_several_materials() {
    let water = Material::tait(1.5e6);
    let scene = || common::box_scene([0.4, 0.4], [0.0, 0.0, 0.2, 0.2], water.clone(), 9.81);
    let base = common::method(ShapeKind::Bspline2, TransferKind::Apic, SchemeKind::Usl);
    let refusals = [
        (
            scene(),
            Method {
                quadrature: QuadratureKind::Mixed,
                shape: ShapeKind::Gimp,
                ..base.clone()
            },
        ),
        (
            scene(),
            Method {
                quadrature: QuadratureKind::Mixed,
                force: ForceKind::Mls,
                ..base.clone()
            },
        ),
        (
            {
                let mut two = scene();
                let mut oil = water.clone();
                oil.name = "oil".into();
                two.materials.push(oil);
                two
            },
            Method {
                quadrature: QuadratureKind::Mixed,
                ..base.clone()
            },
        ),
    ];
    for (scene, method) in refusals {
        let e = common::refusal(scene, method).expect("refused");
        assert_eq!(e.key, "method.quadrature", "{e}");
    }
    let accepted = Method {
        quadrature: QuadratureKind::Mixed,
        ..base
    };
    assert!(common::refusal(scene(), accepted).is_none());
}
