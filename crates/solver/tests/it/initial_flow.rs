//! A body's initial flow (docs/physics.md section 7) reaches its particles
//! as the flow's velocity and gradient at their positions, with the
//! Taylor-Green pressure; an undefined flow is refused by its key.

use crate::common;

use solver::flows::Flow;
use solver::*;

fn taylor_green_scene(mode: u32) -> SolverConfig {
    let mut scene = common::box_scene([0.2, 0.2], [0.0, 0.0, 0.2, 0.2], Material::tait(1.5e6), 0.0);
    scene.bodies[0].flow = Some(Flow::TaylorGreen {
        amplitude: 0.01,
        mode,
    });
    SolverConfig {
        scene,
        method: common::method(ShapeKind::Bspline2, TransferKind::Apic, SchemeKind::Usl),
        perturb: vec![],
    }
}

#[test]
fn particles_start_with_the_flow_its_gradient_and_pressure() {
    let cfg = taylor_green_scene(2);
    let flow = cfg.scene.bodies[0].flow.unwrap();
    let rect = cfg.scene.bodies[0].rect;
    let s = Solver::new(cfg).unwrap();
    let v = s.view();
    assert_eq!(v.x.len(), 1600);
    let mut max_speed: f64 = 0.0;
    for p in 0..v.x.len() {
        let want = flow.velocity(v.x[p], rect, 0.0);
        assert_eq!(v.v[p], want, "particle {p}");
        max_speed = max_speed.max(want.norm());
        let p_want = flow.pressure(v.x[p], rect, 1000.0);
        assert!(
            (v.pressure[p] - p_want).abs() < 1e-9,
            "{} vs {p_want}",
            v.pressure[p]
        );
    }
    // The lattice reaches close to the vortex's peak speed U.
    assert!(max_speed > 0.0095 && max_speed <= 0.01, "{max_speed}");
}

#[test]
fn flows_that_do_not_apply_are_refused_by_key() {
    let mut cfg = taylor_green_scene(1);
    cfg.scene.bodies[0].rect = [0.0, 0.0, 0.2, 0.1];
    let e = Solver::new(cfg).err().unwrap();
    assert_eq!(e.key, "scene.body[0].flow.kind");
    let mut cfg = taylor_green_scene(0);
    cfg.scene.bodies[0].rect = [0.0, 0.0, 0.2, 0.2];
    assert_eq!(
        Solver::new(cfg).err().unwrap().key,
        "scene.body[0].flow.mode"
    );
}
