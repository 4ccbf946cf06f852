//! A monitor per phase of a two-phase mixture: the drag hands kinetic
//! energy from the fluid to the solid, and each phase's budget counts that
//! exchange, so neither monitor reads it as an injection. In a uniform
//! periodic mixture (fluid at 10 m/s through a solid at rest, tau = 0.01 s)
//! the solid gains far more kinetic energy than the injection floor, and no
//! event is raised on either phase.

use monitor::{Monitor, MonitorConfig};
use solver::multiphase::drag::{Drag, DragModel, DragUpdate};
use solver::*;

use crate::common;

fn phase(rho: f64, n: f64, v0: f64) -> Solver {
    let mut material = common::tait(1e5, 0.0);
    material.rho0 = rho;
    let mut scene = Scene::dam_break(material);
    scene.size = [0.1, 0.1];
    scene.bodies[0].rect = [0.0, 0.0, 0.1, 0.1];
    scene.bodies[0].fraction = n;
    scene.bodies[0].velocity = [v0, 0.0];
    scene.gravity = 0.0;
    scene.periodic = [true, true];
    Solver::new(SolverConfig {
        scene,
        method: common::method(ShapeKind::Bspline2, TransferKind::Apic),
        perturb: vec![],
    })
    .unwrap()
}

#[test]
fn drag_between_phases_is_no_injection() {
    let (rs, rf, tau) = (0.6 * 2500.0, 0.4 * 1000.0, 0.01);
    let drag = Drag {
        coefficient: rs * rf / (tau * (rs + rf)),
        kozeny_carman: None,
        model: DragModel::BangBangNode,
        update: DragUpdate::Exponential,
    };
    let mut mix = Mixture::new([phase(2500.0, 0.6, 0.0), phase(1000.0, 0.4, 10.0)], drag).unwrap();
    let mut monitors: Vec<Monitor> = (0..2)
        .map(|k| Monitor::new(MonitorConfig::default(), &mix.phase(k).view()))
        .collect();
    let dt = 1e-4;
    let ke0 = mix.phase(0).energy().kinetic;
    for _ in 0..300 {
        mix.step_with_dt(dt).unwrap();
        for (k, m) in monitors.iter_mut().enumerate() {
            let r = m.observe(&mix.phase(k).view());
            assert!(r.blow_out.is_none(), "phase {k}: {:?}", r.blow_out);
        }
    }
    let gained = mix.phase(0).energy().kinetic - ke0;
    let solid_mass: f64 = mix.phase(0).view().mass.iter().sum();
    let floor = 3.0 * solver::energy::injection_noise_floor(solid_mass, 9.81, 0.1, dt);
    assert!(
        gained > 100.0 * floor,
        "the solid gained {gained} J/m, floor {floor}"
    );
    for (k, m) in monitors.iter().enumerate() {
        assert!(m.events().is_empty(), "phase {k}: {:?}", m.events());
    }
}
