//! A quadratic B-spline PIC dam break never gains energy beyond the
//! dt-scaled noise floor of explicit stepping (energy::injection_noise_floor).

use solver::*;

mod common;

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
