//! Node-based bang-bang drag between two phases (docs/physics.md section 6).
//!
//! A uniform periodic mixture (solid n = 0.6 of rho 2500, fluid n = 0.4 of
//! rho 1000; each phase's particles carry their partial volume) with the
//! fluid moving at dv0 through the solid at rest: the relative velocity
//! follows the exponential update's exact exp(-t/tau) at any dt, the
//! implicit (backward Euler) update's (1 + dt/tau)^-n and the explicit
//! update's (1 - dt/tau)^n, with tau = rs rf / [B (rs + rf)]; total momentum
//! is kept and the kinetic energy lost is the drag's dissipation. In a
//! non-uniform mixture the drag is action against reaction at every node and
//! total momentum is kept to round-off. Fluid falling under gravity through
//! a fixed skeleton reaches Darcy's flux q = k rho_f g / mu.

use solver::multiphase::drag::{Drag, DragModel, DragUpdate};
use solver::remedies::volume_relaxation;
use solver::*;

use crate::common;

const RHO_S: f64 = 2500.0;
const RHO_F: f64 = 1000.0;
const N_S: f64 = 0.6;
const N_F: f64 = 0.4;
const TAU: f64 = 0.01;
const DV0: f64 = 0.1;

fn drag_coefficient() -> f64 {
    let (rs, rf) = (N_S * RHO_S, N_F * RHO_F);
    rs * rf / (TAU * (rs + rf))
}

fn uniform_mixture(update: DragUpdate, method: &Method) -> Mixture {
    uniform_mixture_tau(update, method, 1.0)
}

/// The uniform mixture with tau scaled by `tau_scale`.
fn uniform_mixture_tau(update: DragUpdate, method: &Method, tau_scale: f64) -> Mixture {
    uniform_mixture_with(update, method, tau_scale, None)
}

fn uniform_mixture_with(
    update: DragUpdate,
    method: &Method,
    tau_scale: f64,
    kozeny_carman: Option<f64>,
) -> Mixture {
    uniform_mixture_of(
        DragModel::BangBangNode,
        update,
        method,
        tau_scale,
        kozeny_carman,
    )
}

fn uniform_mixture_of(
    model: DragModel,
    update: DragUpdate,
    method: &Method,
    tau_scale: f64,
    kozeny_carman: Option<f64>,
) -> Mixture {
    let full = [0.0, 0.0, 0.1, 0.1];
    let solid = common::phase(full, RHO_S, N_S, method.clone(), |_| Vec2::zeros());
    let fluid = common::phase(full, RHO_F, N_F, method.clone(), |_| Vec2::new(DV0, 0.0));
    let drag = Drag {
        coefficient: drag_coefficient() / tau_scale,
        kozeny_carman,
        model,
        update,
    };
    Mixture::new([solid, fluid], drag).unwrap()
}

/// A drag of coefficient B without Kozeny-Carman.
fn drag(coefficient: f64, model: DragModel, update: DragUpdate) -> Drag {
    Drag {
        coefficient,
        kozeny_carman: None,
        model,
        update,
    }
}

fn mean_velocity(s: &Solver) -> Vec2 {
    let v = s.view();
    let m: f64 = v.mass.iter().sum();
    v.v.iter().zip(v.mass).map(|(v, m)| *m * v).sum::<Vec2>() / m
}

fn methods() -> Vec<Method> {
    vec![
        common::method(ShapeKind::Linear, TransferKind::Flip, SchemeKind::Usf),
        common::method(ShapeKind::Bspline2, TransferKind::Apic, SchemeKind::Usl),
    ]
}

/// Runs to 3 tau at dt = ratio tau, checking every step against `law(n)`
/// (the relative velocity over dv0) within `tol`, momentum and energy.
fn decay(update: DragUpdate, ratio: f64, law: impl Fn(f64) -> f64, tol: f64) {
    decay_of(DragModel::BangBangNode, update, ratio, law, tol)
}

fn decay_of(model: DragModel, update: DragUpdate, ratio: f64, law: impl Fn(f64) -> f64, tol: f64) {
    for method in methods() {
        let mut mix = uniform_mixture_of(model, update, &method, 1.0, None);
        let p0 = mix.momentum();
        let e0 = mix.energy().total();
        let phase_e0 = [0, 1].map(|k| mix.phase(k).energy().total());
        let dt = ratio * TAU;
        let steps = (3.0 / ratio).ceil() as usize;
        for n in 1..=steps {
            mix.step_with_dt(dt).unwrap();
            let rel = mean_velocity(mix.phase(1)) - mean_velocity(mix.phase(0));
            let expected = DV0 * law(n as f64);
            assert!(
                (rel.x - expected).abs() <= tol * DV0 && rel.y.abs() < 1e-12,
                "{update:?} dt/tau {ratio} step {n}: {} against {expected} ({:?})",
                rel.x,
                method.shape
            );
            let dp = (mix.momentum() - p0).norm() / p0.norm();
            assert!(
                dp < 1e-12,
                "{update:?} dt/tau {ratio}: momentum moved by {dp}"
            );
            let de = (mix.energy().total() - e0).abs() / e0;
            assert!(de < 1e-9, "{update:?} dt/tau {ratio}: energy off by {de}");
            // Each phase's budget closes alone (the drag's exchange counted in it).
            for (k, e0k) in phase_e0.iter().enumerate() {
                let dk = (mix.phase(k).energy().total() - e0k).abs() / e0;
                assert!(
                    dk < 1e-9,
                    "{update:?} dt/tau {ratio}: phase {k} off by {dk}"
                );
            }
        }
        assert!(mix.drag_dissipated() > 0.0);
        assert_eq!(
            mix.last_coupling().nodes,
            100,
            "every node of the 10 x 10 periodic grid"
        );
    }
}

#[test]
fn exponential_update_follows_exp_of_minus_t_over_tau_at_any_dt() {
    for ratio in [0.01, 0.1, 1.0, 5.0] {
        decay(DragUpdate::Exponential, ratio, |n| (-n * ratio).exp(), 1e-9);
    }
}

#[test]
fn implicit_update_is_backward_euler_and_within_one_percent_at_small_dt() {
    for ratio in [0.01, 0.1, 1.0, 5.0] {
        decay(
            DragUpdate::Implicit,
            ratio,
            |n| (1.0 + ratio).powf(-n),
            1e-9,
        );
    }
    // Against the exact decay: within 1 % of dv0 at dt = 0.01 tau, not at dt = tau
    // (0.5 against exp(-1) = 0.37 after one step).
    decay(DragUpdate::Implicit, 0.01, |n| (-n * 0.01).exp(), 0.01);
    let one_step = 1.0 / 2.0 - (-1.0f64).exp();
    assert!(one_step > 0.01);
}

#[test]
fn explicit_update_follows_one_minus_dt_over_tau_to_the_n() {
    for ratio in [0.01, 0.1, 1.5] {
        decay(DragUpdate::Explicit, ratio, |n| (1.0 - ratio).powf(n), 1e-9);
    }
    decay(DragUpdate::Explicit, 0.01, |n| (-n * 0.01).exp(), 0.01);
}

#[test]
fn explicit_drag_beyond_two_tau_grows_and_the_time_step_stays_below_it() {
    let method = common::method(ShapeKind::Linear, TransferKind::Flip, SchemeKind::Usf);
    let mut mix = uniform_mixture(DragUpdate::Explicit, &method);
    for _ in 0..5 {
        mix.step_with_dt(2.5 * TAU).unwrap();
    }
    // (1 - 2.5)^5 = -7.6.
    let rel = mean_velocity(mix.phase(1)) - mean_velocity(mix.phase(0));
    assert!(rel.x.abs() > 5.0 * DV0, "unstable beyond 2 tau: {}", rel.x);
    // The limit 2 / k = 2 tau is measured by the coupling and, with the CFL
    // number as safety, bounds the step once below the phases' own (tau =
    // 1e-4 s here, their CFL step about 2e-4 s).
    let tau = 0.01 * TAU;
    let mut mix = uniform_mixture_tau(DragUpdate::Explicit, &method, 0.01);
    // The first step already obeys the limit (probed at set-up).
    assert!((mix.next_dt() / (0.2 * 2.0 * tau) - 1.0).abs() < 1e-12);
    let mut implicit = uniform_mixture_tau(DragUpdate::Implicit, &method, 0.01);
    let cfl_dt = implicit.next_dt();
    mix.step_with_dt(0.01 * tau).unwrap();
    let limit = mix.last_coupling().stable_dt;
    assert!((limit / (2.0 * tau) - 1.0).abs() < 1e-9, "{limit}");
    assert!(0.2 * limit < cfl_dt);
    assert_eq!(mix.next_dt(), 0.2 * limit);
    implicit.step_with_dt(0.01 * tau).unwrap();
    assert_eq!(
        implicit.next_dt(),
        cfl_dt,
        "no limit on the implicit update"
    );
}

/// A fluid blob crossing a solid block in a periodic box with swirling
/// velocities: at every node the two drag forces cancel to round-off and the
/// total momentum of both phases is kept.
#[test]
fn drag_is_action_against_reaction_at_every_node() {
    let cases = [
        (DragModel::BangBangNode, DragUpdate::Explicit),
        (DragModel::BangBangNode, DragUpdate::Implicit),
        (DragModel::BangBangNode, DragUpdate::Exponential),
        (DragModel::SvfNode, DragUpdate::Explicit),
        (DragModel::SvfNode, DragUpdate::Implicit),
        (DragModel::SvfNode, DragUpdate::Exponential),
        (DragModel::SvfCapped, DragUpdate::Explicit),
        (DragModel::SvfCapped, DragUpdate::Implicit),
        (DragModel::SvfCapped, DragUpdate::Exponential),
        (DragModel::BangBangParticle, DragUpdate::Explicit),
        (DragModel::SvfParticle, DragUpdate::Explicit),
    ];
    for method in methods() {
        for (model, update) in cases {
            let solid = common::phase([0.02, 0.02, 0.07, 0.06], RHO_S, N_S, method.clone(), |x| {
                Vec2::new(0.05 * (60.0 * x.y).sin(), -0.02)
            });
            let fluid = common::phase([0.04, 0.03, 0.09, 0.08], RHO_F, N_F, method.clone(), |x| {
                Vec2::new(0.2 + 0.1 * (50.0 * x.y).cos(), 0.1 * (40.0 * x.x).sin())
            });
            let drag = drag(drag_coefficient(), model, update);
            let mut mix = Mixture::new([solid, fluid], drag).unwrap();
            let p0 = mix.momentum();
            for _ in 0..200 {
                let dt = mix.next_dt().min(0.05 * TAU);
                mix.step_with_dt(dt).unwrap();
                let c = mix.last_coupling();
                assert!(c.nodes > 0);
                assert!(c.momentum_residual < 1e-14, "{model:?} {update:?}: {c:?}");
            }
            let dp = (mix.momentum() - p0).norm() / p0.norm();
            assert!(
                dp < 1e-12,
                "{update:?} {:?}: momentum moved by {dp}",
                method.shape
            );
            assert!(mix.drag_dissipated() > 0.0, "{model:?} {update:?}");
        }
    }
}

/// In the uniform mixture every node is shared whole, so the SVF and
/// particle-based models follow their update's law like the node-based one
/// (the particle-based one's particles carry the grid's velocity there).
#[test]
fn every_model_follows_its_update_law_in_the_uniform_mixture() {
    for ratio in [0.1, 1.0] {
        for model in [DragModel::SvfNode, DragModel::SvfCapped] {
            decay_of(
                model,
                DragUpdate::Exponential,
                ratio,
                |n| (-n * ratio).exp(),
                1e-9,
            );
            decay_of(
                model,
                DragUpdate::Implicit,
                ratio,
                |n| (1.0 + ratio).powf(-n),
                1e-9,
            );
        }
    }
    for ratio in [0.01, 0.1, 1.5] {
        for model in [DragModel::BangBangParticle, DragModel::SvfParticle] {
            decay_of(
                model,
                DragUpdate::Explicit,
                ratio,
                |n| (1.0 - ratio).powf(n),
                1e-9,
            );
        }
    }
}

#[test]
fn the_particle_based_model_is_explicit_only() {
    let method = common::method(ShapeKind::Linear, TransferKind::Flip, SchemeKind::Usf);
    let full = [0.0, 0.0, 0.1, 0.1];
    for model in [DragModel::BangBangParticle, DragModel::SvfParticle] {
        for update in [DragUpdate::Implicit, DragUpdate::Exponential] {
            let solid = common::phase(full, RHO_S, N_S, method.clone(), |_| Vec2::zeros());
            let fluid = common::phase(full, RHO_F, N_F, method.clone(), |_| Vec2::zeros());
            let drag = drag(drag_coefficient(), model, update);
            let e = Mixture::new([solid, fluid], drag).err().expect("refused");
            assert_eq!(e.key, "drag.update", "{e:?}");
        }
    }
}

#[test]
fn phases_over_different_grids_are_refused() {
    let method = common::method(ShapeKind::Linear, TransferKind::Flip, SchemeKind::Usf);
    let a = common::phase([0.0, 0.0, 0.1, 0.1], RHO_S, N_S, method.clone(), |_| {
        Vec2::zeros()
    });
    let mut material = Material::tait(1e5);
    material.rho0 = RHO_F;
    let scene = common::box_scene([0.2, 0.1], [0.0, 0.0, 0.1, 0.1], material, 0.0);
    let b = common::solver(scene, method);
    let drag = drag(1.0, DragModel::BangBangNode, DragUpdate::Implicit);
    let err = Mixture::new([a, b], drag).err().unwrap();
    assert_eq!(err.key, "scene");
}

/// The volume relaxation reads a phase's grid density as the whole node's:
/// refused in a mixture.
#[test]
fn volume_relaxation_is_refused_in_a_mixture() {
    let method = common::method(ShapeKind::Bspline2, TransferKind::Apic, SchemeKind::Usl);
    let mut relaxed = method.clone();
    relaxed.remedies.volume_relaxation = Some(volume_relaxation::Settings { time: 0.1 });
    let a = common::phase([0.0, 0.0, 0.1, 0.1], RHO_S, N_S, method, |_| Vec2::zeros());
    let b = common::phase([0.0, 0.0, 0.1, 0.1], RHO_F, N_F, relaxed, |_| Vec2::zeros());
    let drag = drag(1.0, DragModel::BangBangNode, DragUpdate::Implicit);
    let err = Mixture::new([a, b], drag).err().unwrap();
    assert_eq!(err.key, "method.volume_relaxation");
}

/// Kozeny-Carman: at the reference porosity the coefficient is B0; at
/// porosity 0.4 with n0 = 0.3 it is B0 (0.3 / 0.4) (0.6 / 0.7)^2, and the
/// decay follows that tau. B = n^2 mu / k.
#[test]
fn kozeny_carman_scales_the_coefficient_with_the_nodal_porosity() {
    let b = Drag::from_permeability(1e-3, 1e-10, 0.4);
    assert!((b / 1.6e6 - 1.0).abs() < 1e-15, "{b}");
    let method = common::method(ShapeKind::Linear, TransferKind::Flip, SchemeKind::Usf);
    for (n0, factor) in [(N_F, 1.0), (0.3, (0.3 / 0.4) * (0.6f64 / 0.7).powi(2))] {
        let mut mix = uniform_mixture_with(DragUpdate::Exponential, &method, 1.0, Some(n0));
        let dt = 0.1 * TAU;
        for n in 1..=30 {
            mix.step_with_dt(dt).unwrap();
            let rel = mean_velocity(mix.phase(1)) - mean_velocity(mix.phase(0));
            let expected = DV0 * (-(n as f64) * dt * factor / TAU).exp();
            assert!(
                (rel.x - expected).abs() < 1e-9 * DV0,
                "n0 {n0}: {} against {expected}",
                rel.x
            );
        }
    }
    let bad = Drag {
        coefficient: 1.0,
        kozeny_carman: Some(1.0),
        model: DragModel::BangBangNode,
        update: DragUpdate::Implicit,
    };
    let full = [0.0, 0.0, 0.1, 0.1];
    let a = common::phase(full, RHO_S, N_S, method.clone(), |_| Vec2::zeros());
    let b = common::phase(full, RHO_F, N_F, method, |_| Vec2::zeros());
    assert_eq!(
        Mixture::new([a, b], bad).err().unwrap().key,
        "drag.kozeny_carman"
    );
}

/// A body's volume fraction scales its particles' mass and volume (and 1
/// leaves them as they were); outside (0, 1] it is refused by key.
#[test]
fn body_fraction_scales_mass_and_volume() {
    let full = [0.0, 0.0, 0.1, 0.1];
    let mut material = Material::tait(1e5);
    material.rho0 = RHO_F;
    let mut scene = common::box_scene([0.1, 0.1], full, material, 9.81);
    let one = scene::seed(&scene);
    scene.bodies[0].fraction = N_F;
    let part = scene::seed(&scene);
    assert_eq!(one.len(), part.len());
    for p in 0..one.len() {
        assert_eq!(one.mass[p], 1000.0 * 0.005 * 0.005);
        assert_eq!(part.mass[p], one.mass[p] * N_F);
        assert_eq!(part.vol0[p], one.vol0[p] * N_F);
    }
    for bad in [0.0, -0.1, 1.5, f64::NAN] {
        scene.bodies[0].fraction = bad;
        let err = SolverConfig {
            scene: scene.clone(),
            method: Method::baseline(),
            perturb: vec![],
        }
        .validate()
        .err()
        .unwrap();
        assert_eq!(err.key, "scene.body[0].fraction", "{bad}");
    }
}

/// Darcy under gravity: fluid (n = 0.4) falling through a fixed skeleton in a
/// periodic box reaches the steady flux q = n v_f = k rho_f g / mu (unit
/// hydraulic gradient) with B = n^2 mu / k; the skeleton does not move.
#[test]
fn fluid_through_a_fixed_skeleton_reaches_darcy_flux() {
    let (mu, k) = (1e-3, 1e-9);
    let g = 9.81;
    let full = [0.0, 0.0, 0.1, 0.1];
    for method in methods() {
        for update in [DragUpdate::Implicit, DragUpdate::Exponential] {
            let solid = common::phase(full, RHO_S, N_S, method.clone(), |_| Vec2::zeros());
            let fluid =
                common::phase_under_gravity(full, RHO_F, N_F, method.clone(), |_| Vec2::zeros(), g);
            let drag = drag(
                Drag::from_permeability(mu, k, N_F),
                DragModel::BangBangNode,
                update,
            );
            let mut mix = Mixture::new([solid, fluid], drag).unwrap().fix_solid();
            let x0: Vec<Vec2> = mix.phase(0).view().x.to_vec();
            // tau = n rho_f / B = 0.0025 s: 40 tau.
            for _ in 0..1000 {
                mix.step_with_dt(1e-4).unwrap();
            }
            let q = N_F * mean_velocity(mix.phase(1)).y;
            let darcy = -k * RHO_F * g / mu;
            assert!(
                (q / darcy - 1.0).abs() < 1e-9,
                "{update:?}: q {q} against {darcy}"
            );
            assert_eq!(mix.phase(0).view().x, &x0[..], "the skeleton stays");
            assert!(mix.drag_dissipated() > 0.0);
        }
    }
}
