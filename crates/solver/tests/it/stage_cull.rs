//! `on_escape` / `on_inversion = "delete"`: the particles concerned are
//! deleted at the end of the step, in id order, counted in number and mass,
//! and a checkpoint taken after a deletion restores bit for bit.

use crate::common;

use solver::particles::Particles;
use solver::*;

/// A resting block and, far from it, one cell of particles thrown at
/// 1000 m/s with a 1 ms step: it leaves the 1 m box within one step.
fn thrown(on_escape: OnLoss) -> Solver {
    let material = Material::tait(1e5);
    let mut scene = common::box_scene([1.0, 1.0], [0.1, 0.1, 0.3, 0.3], material, 0.0);
    scene.bodies.push(Body {
        rect: [0.6, 0.6, 0.61, 0.61],
        material: String::new(),
        velocity: [1000.0, 0.0],
        fraction: 1.0,
        phase: None,
        flow: None,
    });
    scene.on_escape = on_escape;
    let method = Method {
        dt_value: Some(1e-3),
        ..common::method(ShapeKind::Linear, TransferKind::Flip, SchemeKind::Usf)
    };
    common::solver(scene, method)
}

#[test]
fn an_escaped_particle_is_deleted_and_counted() {
    let mut kept = thrown(OnLoss::Stop);
    let mut s = thrown(OnLoss::Delete);
    let n0 = s.particle_count();
    let block = n0 - 4;
    let thrown_mass: f64 = s.view().mass[block..].iter().sum();
    kept.step().unwrap();
    s.step().unwrap();
    // Under "stop" the four particles are outside the box for the monitor to see.
    assert_eq!(kept.view().n_outside, 4);
    let v = s.view();
    assert_eq!(v.n_outside, 0);
    assert_eq!(s.particle_count(), block);
    assert_eq!(v.n_initial, n0);
    assert_eq!(v.culled.len(), 4);
    assert!(v
        .culled
        .iter()
        .all(|c| c.reason == CullReason::Escaped && c.x.x > 1.0));
    let ids: Vec<u32> = v.culled.iter().map(|c| c.id).collect();
    assert_eq!(ids, (block as u32..n0 as u32).collect::<Vec<_>>());
    let l = s.losses();
    assert_eq!((l.escaped, l.inverted), (4, 0));
    assert_eq!(l.mass_escaped, thrown_mass);
    assert_eq!(l.t_first, Some(1e-3));
    // The block is untouched by the deletion: same state as under "stop".
    let kv = kept.view();
    assert_eq!(v.x, &kv.x[..block]);
    assert_eq!(v.id, &kv.id[..block]);
    // The next step runs (nothing left outside the grid) and deletes nothing more.
    s.step().unwrap();
    assert!(s.view().culled.is_empty());
    assert_eq!(s.losses().count(), 4);
}

#[test]
fn a_checkpoint_after_a_deletion_restores_bit_for_bit() {
    let mut s = thrown(OnLoss::Delete);
    s.step().unwrap();
    let bytes = s.checkpoint();
    let mut restored = thrown(OnLoss::Delete);
    restored.restore(&bytes).unwrap();
    assert_eq!(restored.particle_count(), s.particle_count());
    assert_eq!(restored.losses(), s.losses());
    assert_eq!(restored.state_hash(), s.state_hash());
    for _ in 0..5 {
        s.step().unwrap();
        restored.step().unwrap();
    }
    assert_eq!(restored.state_hash(), s.state_hash());
    assert_eq!(restored.view().id, s.view().id);
    // A checkpoint of another scene's particle count is refused.
    let mut other = common::solver(
        common::box_scene([1.0, 1.0], [0.1, 0.1, 0.2, 0.2], Material::tait(1e5), 0.0),
        common::method(ShapeKind::Linear, TransferKind::Flip, SchemeKind::Usf),
    );
    assert!(matches!(
        other.restore(&bytes),
        Err(CheckpointError::ParticleCount { .. })
    ));
}

#[test]
fn an_inverted_particle_is_deleted_under_delete() {
    // Converging flow v_x = -k (x - x_c) with k dt = 1.5: J = 1 - k dt < 0 in one step.
    let material = Material::tait(1e5);
    let mut scene = common::box_scene([1.0, 1.0], [0.3, 0.3, 0.7, 0.7], material, 0.0);
    scene.on_inversion = OnLoss::Delete;
    let mut s = seeded_linear_usf(scene, 1e-3, |particles| {
        for (x, v) in particles.x.iter().zip(particles.v.iter_mut()) {
            v.x = -1500.0 * (x.x - 0.5);
        }
    });
    let n0 = s.particle_count();
    s.step().unwrap();
    let v = s.view();
    assert!(v.j.iter().all(|&j| j > 0.0), "no inverted particle is left");
    let l = s.losses();
    assert!(l.inverted > 0, "some particle inverted");
    assert_eq!(l.escaped, 0);
    assert_eq!(s.particle_count() as u64 + l.inverted, n0 as u64);
    assert!(v.culled.iter().all(|c| c.reason == CullReason::Inverted));
    assert!(v.id.windows(2).all(|w| w[0] < w[1]), "ids stay in order");
}

/// Under `on_inversion = "delete"` a particle that inverts in the stress
/// stage carries no stress (under USF it would push its neighbours in that
/// very step before being deleted); under "stop" its stress is kept for the
/// monitor to see.
#[test]
fn an_inverting_particle_carries_no_stress_under_delete() {
    let stress_of_inverted = |on_inversion: OnLoss| {
        let mut scene =
            common::box_scene([1.0, 1.0], [0.3, 0.3, 0.7, 0.7], Material::new(1e5), 0.0);
        scene.on_inversion = on_inversion;
        let cfg = SolverConfig {
            scene: scene.clone(),
            method: common::method(ShapeKind::Linear, TransferKind::Flip, SchemeKind::Usf),
            perturb: vec![],
        };
        let mut ps = solver::scene::seed(&scene);
        let victim = ps.len() / 3;
        ps.f[victim] = Mat2::new(-0.1, 0.0, 0.0, 1.0);
        ps.j[victim] = -0.1;
        let mut s = Solver::with_particles(cfg, ps);
        s.run_stage(Stage::Sort).unwrap();
        s.run_stage(Stage::Stress).unwrap();
        let v = s.view();
        (v.stress[victim], v.pressure[victim], v.stress[victim + 1])
    };
    let (kept, p_kept, _) = stress_of_inverted(OnLoss::Stop);
    assert!(kept.norm() > 1e5 && p_kept != 0.0, "{kept}");
    let (dropped, p_dropped, neighbour) = stress_of_inverted(OnLoss::Delete);
    assert_eq!(dropped, Mat2::zeros());
    assert_eq!(p_dropped, 0.0);
    assert_eq!(
        neighbour,
        Mat2::zeros(),
        "a particle at J = 1 has no stress either way"
    );
}

/// A resting block whose middle particle has a velocity that is not a
/// number, under `on_nonfinite` (linear USF, dt 1e-4 s).
fn poisoned(on_nonfinite: OnLoss) -> (Solver, u32) {
    let material = Material::tait(1e5);
    let mut scene = common::box_scene([1.0, 1.0], [0.1, 0.1, 0.5, 0.5], material, 9.81);
    scene.on_nonfinite = on_nonfinite;
    let mut id = 0;
    let s = seeded_linear_usf(scene, 1e-4, |particles| {
        let planted = particles.len() / 2;
        particles.v[planted].x = f64::NAN;
        id = particles.id[planted];
    });
    (s, id)
}

/// `scene` seeded, its particles changed by `edit`, on linear FLIP USF at
/// a fixed step `dt`.
fn seeded_linear_usf(scene: Scene, dt: f64, edit: impl FnOnce(&mut Particles)) -> Solver {
    let method = Method {
        dt_value: Some(dt),
        ..common::method(ShapeKind::Linear, TransferKind::Flip, SchemeKind::Usf)
    };
    let mut particles = scene::seed(&scene);
    edit(&mut particles);
    let cfg = SolverConfig {
        scene,
        method,
        perturb: vec![],
    };
    Solver::with_particles(cfg, particles)
}

/// Under "stop" the NaN spreads through the planted particle's nodes to
/// its neighbours and stays for the monitor to see. Under
/// `on_nonfinite = "delete"` every particle it reached is deleted at the
/// end of that step and counted as escaped (Uintah's relocation drops a
/// position no patch holds), and the rest steps on finite.
#[test]
fn non_finite_particles_are_deleted_under_on_nonfinite_delete() {
    let (mut kept, _) = poisoned(OnLoss::Stop);
    let n0 = kept.particle_count();
    kept.step().unwrap();
    let reached = kept.view().n_nonfinite;
    assert!(reached > 1, "the NaN reached the neighbours: {reached}");
    assert_eq!(kept.particle_count(), n0);
    let (mut s, id) = poisoned(OnLoss::Delete);
    s.step().unwrap();
    let v = s.view();
    assert_eq!(v.n_nonfinite, 0);
    assert_eq!(v.culled.len(), reached);
    assert!(v.culled.iter().all(|c| c.reason == CullReason::NonFinite));
    assert!(v.culled.iter().any(|c| c.id == id));
    let l = s.losses();
    assert_eq!((l.escaped, l.inverted), (reached as u64, 0));
    assert_eq!(s.particle_count(), n0 - reached);
    assert!(v.energy.total().is_finite());
    for _ in 0..5 {
        s.step().unwrap();
        assert!(s.view().culled.is_empty(), "what is left stays finite");
        assert!(s.view().energy.total().is_finite());
    }
}
