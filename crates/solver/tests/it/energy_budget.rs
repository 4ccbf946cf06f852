//! A quadratic B-spline PIC dam break never gains energy beyond the
//! dt-scaled noise floor of explicit stepping (energy::injection_noise_floor).

use solver::*;

use crate::common;

#[test]
fn pic_dam_break_energy_stays_under_noise_floor() {
    let mut mat = Material::tait(1.5e4);
    mat.eos = EosKind::Power;
    mat.gamma = 7.0;
    mat.viscosity = 0.5;
    let mut scene = Scene::dam_break(mat);
    scene.t_end = 1.0;
    let g = scene.gravity;
    let height = scene.size[1];
    let mut s = common::solver(
        scene,
        common::method(ShapeKind::Bspline2, TransferKind::Pic, SchemeKind::Usf),
    );
    let mass: f64 = s.view().mass.iter().sum();
    let e0 = s.energy().total();
    let mut lowest = e0;
    let mut worst: f64 = 0.0;
    while !s.finished() {
        s.step().unwrap();
        let v = s.view();
        let e = v.energy.total();
        lowest = lowest.min(e);
        let floor = energy::injection_noise_floor(mass, g, height, v.dt);
        worst = worst.max((e - lowest) / floor);
        assert!(
            e - lowest <= floor,
            "step {}: injected {} > floor {floor}",
            v.step,
            e - lowest
        );
    }
    // The run did something: the column collapsed and PIC dissipated energy.
    assert!(s.energy().total() < 0.9 * e0);
    assert!(s.energy().dissipated > 0.0);
    eprintln!("worst injection / floor = {worst}");
}

/// The potential energy the particles lose in a step is gravity's work on
/// the grid's v^{n+1} (positions move with it): the budget's gravity term
/// has no time integration error, so a drift lives in the stress and
/// force terms (examples/energy_ledger.rs splits them). A settling column,
/// every transfer, with and without volume relaxation (which changes J only).
#[test]
fn potential_energy_change_is_gravitys_work_on_the_updated_grid() {
    for transfer in [TransferKind::Pic, TransferKind::Flip, TransferKind::Apic] {
        for relax in [false, true] {
            let mut material = Material::tait(1e5);
            material.viscosity = 0.5;
            let scene = common::box_scene([0.2, 0.4], [0.0, 0.0, 0.2, 0.2], material, 9.81);
            let mut method = common::method(ShapeKind::Bspline2, transfer, SchemeKind::Usl);
            if relax {
                method.remedies.volume_relaxation =
                    Some(solver::remedies::volume_relaxation::Settings { time: 0.05 });
            }
            let mut s = common::solver(scene, method);
            let gravity = Vec2::new(0.0, -9.81);
            let (mut lost, mut worst) = (0.0, 0.0f64);
            for _ in 0..400 {
                let before = s.energy().gravitational;
                s.step().unwrap();
                let v = s.view();
                let work: f64 = v
                    .grid
                    .active
                    .iter()
                    .map(|&n| {
                        v.grid.mass_raw[n as usize] * gravity.dot(&v.grid.velocity[n as usize])
                    })
                    .sum::<f64>()
                    * v.dt;
                let change = v.energy.gravitational - before;
                lost -= change;
                worst = worst.max((change + work).abs());
            }
            // The column settled by a visible amount ...
            assert!(lost > 1e-4, "{transfer:?} {relax}: lost {lost}");
            // ... and every step's change matched the work to round-off.
            assert!(
                worst < 1e-12 * s.energy().gravitational.abs().max(1.0),
                "{transfer:?} relax {relax}: {worst:e} (lost {lost:e})"
            );
        }
    }
}
