//! J <= 0 (or det F <= 0 under the exp J update, which keeps J > 0) is caught
//! at the step it first appears, as an `inversion` event that stops the run;
//! never carried on silently.

use crate::common;

use monitor::{EventKind, Rule};
use solver::*;

/// A block slammed into the floor at 30 m/s with a time step 10x the
/// advective limit: some particle inverts within a few steps.
fn slam(j_update: JUpdate, gamma: f64) -> Solver {
    slam_with(j_update, gamma, OnLoss::Stop)
}

fn slam_with(j_update: JUpdate, gamma: f64, on_loss: OnLoss) -> Solver {
    let mut material = Material::new(1e3);
    material.gamma = gamma;
    let mut scene = Scene::dam_break(material);
    scene.bodies[0].rect = [0.2, 0.0, 0.4, 0.2];
    scene.bodies[0].velocity = [0.0, -30.0];
    // "keep" is for inversions only: an escape then stops the run.
    scene.on_escape = if on_loss == OnLoss::Keep {
        OnLoss::Stop
    } else {
        on_loss
    };
    scene.on_inversion = on_loss;
    let method = Method {
        dt_value: Some(3e-3),
        j_update,
        ..Method::baseline()
    };
    Solver::new(SolverConfig {
        scene,
        method,
        perturb: vec![],
    })
    .unwrap()
}

#[test]
fn an_inversion_stops_the_run_at_its_first_step() {
    // gamma 1 and 7.5 make the pressure or the stored energy non-finite at
    // J <= 0: still an inversion, not a non-finite state.
    for (j_update, gamma) in [
        (JUpdate::Det, 7.0),
        (JUpdate::Exp, 7.0),
        (JUpdate::Det, 1.0),
        (JUpdate::Det, 7.5),
    ] {
        let mut s = slam(j_update, gamma);
        let mut m = common::fresh_monitor(&s);
        let mut first_inverted = None;
        let mut stopped = None;
        for _ in 0..50 {
            s.step().unwrap();
            let v = s.view();
            let inverted =
                v.j.iter()
                    .zip(v.deformation)
                    .any(|(j, f)| *j <= 0.0 || f.determinant() <= 0.0);
            if inverted && first_inverted.is_none() {
                first_inverted = Some(v.step);
            }
            let r = m.observe(&v);
            if let Some(reason) = &r.blow_out {
                stopped = Some((v.step, reason.clone()));
                break;
            }
        }
        let first = first_inverted
            .unwrap_or_else(|| panic!("{j_update:?} gamma {gamma}: no particle inverted"));
        let (step, reason) =
            stopped.unwrap_or_else(|| panic!("{j_update:?} gamma {gamma}: not stopped"));
        assert_eq!(
            step, first,
            "{j_update:?} gamma {gamma}: stopped at the first inverted step"
        );
        assert!(
            reason.contains("inversion"),
            "{j_update:?} gamma {gamma}: {reason}"
        );
        let e = m.events().last().unwrap();
        assert_eq!(e.kind, EventKind::Inversion, "{e:?}");
        assert!(e.rules.contains(Rule::Inversion));
        assert_eq!(e.cause, monitor::Cause::Inversion);
        assert_eq!(e.outcome, monitor::Outcome::Inverted);
        assert!(e.is_kick());
        assert!(e.n_particles >= 1);
        if j_update == JUpdate::Exp {
            assert!(
                s.view().j.iter().all(|j| *j > 0.0),
                "exp keeps J > 0: det F caught it"
            );
        }
    }
}

#[test]
fn under_delete_inverted_and_escaped_particles_are_logged_and_the_run_goes_on() {
    let mut s = slam_with(JUpdate::Det, 7.0, OnLoss::Delete);
    let mut m = common::fresh_monitor(&s);
    let n0 = s.particle_count() as u64;
    let mut stop = None;
    for _ in 0..50 {
        s.step().unwrap();
        let v = s.view();
        assert!(
            v.j.iter().all(|j| *j > 0.0),
            "no inverted particle is carried on"
        );
        let r = m.observe(&v);
        assert_eq!(r.particles_lost, v.losses.count());
        if let Some(reason) = &r.blow_out {
            stop = Some((reason.clone(), r.mass_lost_fraction));
            break;
        }
    }
    let l = s.losses();
    assert!(l.inverted > 0, "the slam inverts particles: {l:?}");
    assert_eq!(s.particle_count() as u64 + l.count(), n0);
    // Every deleted particle is counted in an event of its kind.
    let counted = |kind: EventKind| -> u64 {
        m.events()
            .iter()
            .filter(|e| e.kind == kind)
            .map(|e| e.n_particles as u64)
            .sum()
    };
    assert_eq!(counted(EventKind::Inversion), l.inverted);
    assert_eq!(counted(EventKind::BlowOut), l.escaped);
    let e = m
        .events()
        .iter()
        .find(|e| e.kind == EventKind::Inversion)
        .unwrap();
    assert_eq!(e.cause, monitor::Cause::Inversion);
    assert!(!e.particles.is_empty());
    // The run stops only past lost_mass_limit (10 %), and then says so.
    match stop {
        Some((reason, lost)) => {
            assert!(reason.contains("lost_mass_limit"), "{reason}");
            assert!(lost > 0.1, "{lost}");
        }
        None => assert!(l.mass() <= 0.1 * m.initial_mass(), "{l:?}"),
    }
}

/// Under `on_inversion = "keep"` (Uintah's Water model before 2015-08-03)
/// an inverted particle stays with its EOS evaluated at its J (gamma 7: a
/// finite tension, K (J^-7 - 1)), an `inversion` event is logged, and the
/// run goes on past the step it inverted at (here to the next, where the
/// slam's particles leave the box).
#[test]
fn under_keep_an_inverted_particle_stays_and_the_run_goes_on() {
    // A slower slam: a particle inverts against the floor at the first
    // step, before any leaves the box.
    let mut cfg = slam_with(JUpdate::Det, 7.0, OnLoss::Keep).config().clone();
    cfg.scene.bodies[0].velocity = [0.0, -5.0];
    let mut s = Solver::new(cfg).unwrap();
    let mut m = common::fresh_monitor(&s);
    let mut first_inverted = None;
    let mut steps_after = 0;
    for _ in 0..50 {
        s.step().unwrap();
        let v = s.view();
        let r = m.observe(&v);
        if let Some(p) = v.j.iter().position(|j| *j <= 0.0) {
            let material = &v.materials[0];
            let want = material.pressure(v.j[p]);
            assert!(want.is_finite() && want < 0.0, "J {}: p {want}", v.j[p]);
            assert_eq!(
                v.pressure[p].to_bits(),
                want.to_bits(),
                "the EOS at J {}",
                v.j[p]
            );
            first_inverted.get_or_insert(v.step);
        }
        if first_inverted.is_some_and(|f| v.step > f) {
            steps_after += 1;
        }
        if let Some(reason) = &r.blow_out {
            // What stops it is what the kept particle did, not the inversion.
            assert!(!reason.contains("inversion"), "{reason}");
            break;
        }
    }
    assert!(first_inverted.is_some(), "the slam inverts a particle");
    assert!(steps_after >= 1, "the run went on after the inversion");
    let e = m
        .events()
        .iter()
        .find(|e| e.kind == EventKind::Inversion)
        .expect("an inversion event");
    assert_eq!(e.cause, monitor::Cause::Inversion);
    assert!(!e.particles.is_empty());
}

#[test]
fn keep_is_refused_for_particles_that_leave_the_box() {
    let mut s = slam(JUpdate::Det, 7.0).config().clone();
    s.scene.on_escape = OnLoss::Keep;
    let err = Solver::new(s).err().expect("refused");
    assert_eq!(err.key, "scene.on_escape");
}
