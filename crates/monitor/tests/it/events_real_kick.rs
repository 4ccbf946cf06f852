//! A real kick: the problem statement's baseline (linear, FLIP, USF, fixed dt,
//! CFL 0.2) at small K (power law gamma 7, K = 15 kPa) is logged with its
//! step, region, Courant number and hallmark flags before it blows out.

use monitor::EventKind;
use solver::*;

use crate::common;

#[test]
fn baseline_small_k_kicks_then_blows_out() {
    let mut mat = Material::tait(1.5e4);
    mat.eos = EosKind::Power;
    let cfg = SolverConfig {
        scene: Scene::dam_break(mat),
        method: Method::baseline(),
        perturb: vec![],
    };
    let mut s = Solver::new(cfg).unwrap();
    let mut m = common::fresh_monitor(&s);
    let reason = loop {
        assert!(
            !s.finished(),
            "the baseline at 15 kPa is expected to blow up"
        );
        s.step().unwrap();
        if let Some(r) = m.observe(&s.view()).blow_out.clone() {
            break r;
        }
    };
    assert!(reason.contains("left the box"), "{reason}");
    let blow = m.events().last().unwrap();
    assert_eq!(blow.kind, EventKind::BlowOut);
    assert_eq!(blow.first_step, s.step_count());
    let kicks: Vec<_> = m
        .events()
        .iter()
        .filter(|e| e.kind == EventKind::Kick)
        .collect();
    assert!(!kicks.is_empty(), "kicks precede the blow-out");
    for e in &kicks {
        assert!(e.first_step < blow.first_step);
        assert!(e.courant > 0.0 && e.n_particles >= 4);
        assert!(
            e.jump_speed >= 0.02 || e.rules.contains(monitor::Rule::InjectionWindow),
            "{e:?}"
        );
        assert!(e.region.x_max > e.region.x_min && e.region.y_max > e.region.y_min);
        eprintln!(
            "kick {} step {} t {:.4} s region [{:.2}, {:.2}] x [{:.2}, {:.2}] a/g {:.0} jump {:.3} m/s Courant {:.2} quiescent {} deformed {} cause {:?} {:?} outcome {:?}",
            e.id, e.first_step, e.t, e.region.x_min, e.region.x_max, e.region.y_min, e.region.y_max,
            e.peak_accel_g, e.jump_speed, e.courant, e.quiescent_before, e.previously_deformed(),
            e.cause, e.evidence, e.outcome
        );
    }
    eprintln!(
        "blow-out at step {} t {:.4}: {reason} (Courant {:.2}, cause {:?} {:?})",
        blow.first_step, blow.t, blow.courant, blow.cause, blow.evidence
    );
    assert_eq!(blow.outcome, monitor::Outcome::BlowOut);
}
