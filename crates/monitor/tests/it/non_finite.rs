//! `scene.on_nonfinite`: a particle whose state is not a finite number
//! stops the run ("stop", the default), or is deleted with every particle
//! it reached and logged as a `non_finite` event while the run goes on
//! ("delete", what Uintah's relocation does).

use crate::common;

use monitor::{EventKind, Rule};
use solver::*;

/// A resting water block (the baseline's power law) whose middle particle
/// has a velocity that is not a number, under `on_nonfinite`.
fn poisoned(on_nonfinite: OnLoss) -> Solver {
    let mut scene = Scene::dam_break(Material::new(1.5e4));
    scene.on_nonfinite = on_nonfinite;
    let cfg = SolverConfig {
        scene: scene.clone(),
        method: Method::baseline(),
        perturb: vec![],
    };
    let mut particles = scene::seed(&scene);
    let planted = particles.len() / 2;
    particles.v[planted].x = f64::NAN;
    Solver::with_particles(cfg, particles)
}

#[test]
fn a_non_finite_particle_stops_the_run_or_is_deleted_and_logged() {
    let mut s = poisoned(OnLoss::Stop);
    let mut m = common::fresh_monitor(&s);
    s.step().unwrap();
    let r = m.observe(&s.view());
    let reason = r
        .blow_out
        .clone()
        .expect("a non-finite state stops the run");
    assert!(reason.contains("non-finite state"), "{reason}");

    let mut s = poisoned(OnLoss::Delete);
    let mut m = common::fresh_monitor(&s);
    s.step().unwrap();
    let deleted = s.view().culled.len();
    assert!(deleted > 1, "the NaN reached the neighbours: {deleted}");
    for step in 1..=20 {
        let r = m.observe(&s.view());
        assert!(r.blow_out.is_none(), "step {step}: {:?}", r.blow_out);
        s.step().unwrap();
    }
    let logged: Vec<_> = m
        .events()
        .iter()
        .filter(|e| e.kind == EventKind::NonFinite)
        .collect();
    assert_eq!(logged.len(), 1);
    let e = logged[0];
    assert_eq!((e.first_step, e.n_particles), (1, deleted));
    assert!(e.rules.contains(Rule::NonFinite));
    assert_eq!(s.losses().escaped as usize, deleted);
}
