//! `Solver::set_method`: a run restarted from a checkpoint can continue
//! with changed remedies (the counterfactual replay's need). Switching to
//! the method it already has changes no bit; switching to another method
//! after a restart gives the same bits as switching in the uninterrupted
//! run; a method the solver cannot run is refused and leaves it as it was.

use crate::common;

use solver::remedies::{j_bar, shifting, RemedySettings};
use solver::*;

fn scene() -> Scene {
    common::box_scene(
        [0.4, 0.3],
        [0.0, 0.0, 0.1, 0.2],
        Material::tait(1.5e5),
        9.81,
    )
}

fn plain() -> Method {
    common::method(ShapeKind::Bspline2, TransferKind::Apic, SchemeKind::Usl)
}

fn remedied() -> Method {
    Method {
        remedies: RemedySettings {
            j_bar: Some(j_bar::Settings {
                fit: JBarFit::Linear,
                ..Default::default()
            }),
            shifting: Some(shifting::Settings::default()),
            ..Default::default()
        },
        ..plain()
    }
}

fn steps(s: &mut Solver, n: usize) {
    for _ in 0..n {
        s.step().unwrap();
    }
}

#[test]
fn switching_method_mid_run_is_deterministic_and_restart_safe() {
    let mut straight = common::solver(scene(), plain());
    steps(&mut straight, 40);
    let checkpoint = straight.checkpoint();
    let mut same = straight.clone();

    // The method it already has: the run goes on bit for bit.
    same.set_method(plain()).unwrap();
    steps(&mut straight, 40);
    steps(&mut same, 40);
    assert_eq!(same.state_hash(), straight.state_hash());

    // Switched to the remedies at step 40, in the run and after a restart.
    let mut switched = common::solver(scene(), plain());
    steps(&mut switched, 40);
    switched.set_method(remedied()).unwrap();
    steps(&mut switched, 40);
    let mut restarted = common::solver(scene(), plain());
    restarted.restore(&checkpoint).unwrap();
    restarted.set_method(remedied()).unwrap();
    steps(&mut restarted, 40);
    assert_eq!(restarted.state_hash(), switched.state_hash());
    assert_ne!(switched.state_hash(), straight.state_hash());
    let keys: Vec<&str> = switched.remedy_energy().map(|(k, _)| k).collect();
    assert_eq!(keys, ["j_bar", "shifting"]);
    assert!(switched.remedy_energy().any(|(_, e)| e.total() != 0.0));
}

#[test]
fn a_method_it_cannot_run_is_refused_and_changes_nothing() {
    let mut s = common::solver(scene(), plain());
    steps(&mut s, 5);
    let before = s.state_hash();
    let flip_only = Method {
        remedies: RemedySettings {
            null_space_filter: Some(Default::default()),
            ..Default::default()
        },
        ..plain()
    };
    let err = s.set_method(flip_only).unwrap_err();
    assert_eq!(err.key, "method.null_space_filter");
    let err = s
        .set_method(Method {
            shape: ShapeKind::Linear,
            ..plain()
        })
        .unwrap_err();
    assert_eq!(err.key, "method.shape");
    assert_eq!(s.config().method, plain());
    steps(&mut s, 5);
    let mut again = common::solver(scene(), plain());
    steps(&mut again, 10);
    assert_eq!(s.state_hash(), again.state_hash());
    assert_ne!(before, s.state_hash());
}

#[test]
fn switching_the_materials_constants_is_restart_safe_and_changes_the_step() {
    // A CFL step taken every step, so the sound speed sets it.
    let dynamic = || Method {
        dt: DtMode::Dynamic,
        ..plain()
    };
    let mut straight = common::solver(scene(), dynamic());
    steps(&mut straight, 30);
    let checkpoint = straight.checkpoint();
    let before_dt = straight.next_dt();

    // The same constants: nothing moves.
    let mut same = straight.clone();
    same.set_materials(straight.config().scene.materials.clone())
        .unwrap();
    assert_eq!(same.next_dt(), before_dt);
    steps(&mut same, 20);
    let mut reference = straight.clone();
    steps(&mut reference, 20);
    assert_eq!(same.state_hash(), reference.state_hash());

    // Four times the bulk modulus: twice the sound speed, about half the
    // step; after a restart, the same bits as in the run.
    let stiffer = |s: &Solver| {
        let mut m = s.config().scene.materials.clone();
        m[0].k *= 4.0;
        m
    };
    let mut switched = straight.clone();
    switched.set_materials(stiffer(&straight)).unwrap();
    let ratio = switched.next_dt() / before_dt;
    assert!((0.45..0.6).contains(&ratio), "dt ratio {ratio}");
    let mut restarted = common::solver(scene(), dynamic());
    restarted.restore(&checkpoint).unwrap();
    restarted.set_materials(stiffer(&restarted)).unwrap();
    steps(&mut switched, 20);
    steps(&mut restarted, 20);
    assert_eq!(restarted.state_hash(), switched.state_hash());
    assert_ne!(switched.state_hash(), reference.state_hash());

    // Another material, another density or a constant out of range:
    // refused, nothing changed.
    let mut renamed = straight.config().scene.materials.clone();
    renamed[0].name = "oil".into();
    assert_eq!(
        straight.set_materials(renamed).unwrap_err().key,
        "materials"
    );
    // A density: the particles' masses came from it.
    let mut denser = straight.config().scene.materials.clone();
    denser[0].rho0 *= 1.01;
    assert_eq!(straight.set_materials(denser).unwrap_err().key, "materials");
    let mut infinite = straight.config().scene.materials.clone();
    infinite[0].k = f64::INFINITY;
    assert!(straight.set_materials(infinite).is_err());
    assert_eq!(straight.next_dt(), before_dt);
}
