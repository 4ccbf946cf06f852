//! Pore pressure on the grid (`pore_pressure.rs`): a saturated mixture at
//! rest is in balance (grains and water fill every node, J = 1, p = 0), the
//! volume constraint acts only where grains and water overfill a node, and
//! the top load's ramp.

mod common;

use solver::drag::{Drag, DragModel, DragUpdate};
use solver::pore_pressure::ramp_share;
use solver::{Mixture, SchemeKind, ShapeKind, TransferKind, Vec2};

#[test]
fn a_saturated_mixture_at_rest_stays_at_rest_with_zero_pore_pressure() {
    for shape in [ShapeKind::Linear, ShapeKind::Bspline2] {
        let mut mix = saturated_at_rest(shape).with_pore_pressure();
        assert_eq!(
            mix.pore_fluid().unwrap().k,
            1e5,
            "the fluid's EOS moves to the grid"
        );
        for _ in 0..100 {
            mix.step().unwrap();
        }
        for k in 0..2 {
            let speed = max_speed(&mix, k);
            assert!(speed < 1e-12, "{shape:?} phase {k}: {speed}");
        }
        let p = mix
            .phase(1)
            .view()
            .pressure
            .iter()
            .map(|p| p.abs())
            .fold(0.0, f64::max);
        assert!(p < 1e-6, "{shape:?}: pore pressure {p}");
    }
}

#[test]
fn the_load_ramps_smoothly_from_zero_to_full() {
    assert_eq!(ramp_share(0.0, 0.01), 0.0);
    assert!((ramp_share(0.005, 0.01) - 0.5).abs() < 1e-15);
    assert_eq!(ramp_share(0.01, 0.01), 1.0);
    assert_eq!(ramp_share(0.5, 0.01), 1.0);
    assert_eq!(ramp_share(0.0, 0.0), 1.0, "a step without a ramp");
    let mut last = 0.0;
    for i in 0..=100 {
        let s = ramp_share(i as f64 * 1e-4, 0.01);
        assert!(s >= last);
        last = s;
    }
}

/// Grains (n_s = 0.6) and water (n_f = 0.4) at rest filling the periodic box.
fn saturated_at_rest(shape: ShapeKind) -> Mixture {
    let method = common::method(shape, TransferKind::Apic, SchemeKind::Usl);
    let full = [0.0, 0.0, 0.1, 0.1];
    let solid = common::phase(full, 2650.0, 0.6, method.clone(), |_| Vec2::zeros());
    let fluid = common::phase(full, 1000.0, 0.4, method, |_| Vec2::zeros());
    Mixture::new([solid, fluid], bang_bang()).unwrap()
}

fn max_speed(mix: &Mixture, phase: usize) -> f64 {
    let v = mix.phase(phase).view();
    v.v.iter().map(|u| u.norm()).fold(0.0, f64::max)
}

fn bang_bang() -> Drag {
    Drag {
        coefficient: 1e5,
        kozeny_carman: None,
        model: DragModel::BangBangNode,
        update: DragUpdate::Exponential,
    }
}

/// Grains and water that just fill every node (n_s + n_f = 1): the volume
/// constraint exerts nothing, the mixture stays at rest, and the fluid keeps
/// its own EOS (the constraint is not the pore pressure).
#[test]
fn the_volume_constraint_leaves_a_just_saturated_mixture_at_rest() {
    for shape in [ShapeKind::Linear, ShapeKind::Bspline2] {
        let mut mix = saturated_at_rest(shape).with_volume_constraint();
        assert!(mix.pore_fluid().is_none(), "the fluid keeps its own EOS");
        for _ in 0..100 {
            mix.step().unwrap();
        }
        for k in 0..2 {
            let speed = max_speed(&mix, k);
            assert!(speed < 1e-12, "{shape:?} phase {k}: {speed}");
        }
    }
}

/// Water seeded at n_f = 0.7 into a fixed block of grains at n_s = 0.6 (a
/// node holds 1.3 times its room): the constraint drives the water out
/// of the block, symmetrically, with zero net momentum; without it the
/// water at its own J = 1 stays at rest.
#[test]
fn the_volume_constraint_drives_water_out_of_overfilled_grains() {
    let method = common::method(ShapeKind::Bspline2, TransferKind::Apic, SchemeKind::Usl);
    let block = [0.03, 0.03, 0.07, 0.07];
    for constrained in [false, true] {
        let solid = common::phase(block, 2650.0, 0.6, method.clone(), |_| Vec2::zeros());
        let fluid = common::phase(block, 1000.0, 0.7, method.clone(), |_| Vec2::zeros());
        let mut mix = Mixture::new([solid, fluid], bang_bang())
            .unwrap()
            .fix_solid();
        if constrained {
            mix = mix.with_volume_constraint();
        }
        for _ in 0..20 {
            mix.step().unwrap();
        }
        let v = mix.phase(1).view();
        let outward: f64 =
            v.x.iter()
                .zip(v.v)
                .map(|(x, u)| (x - Vec2::new(0.05, 0.05)).dot(u))
                .sum();
        let momentum = v.v.iter().fold(Vec2::zeros(), |a, u| a + u);
        let speed = max_speed(&mix, 1);
        if constrained {
            assert!(
                outward > 0.0 && speed > 1e-3,
                "outward {outward}, speed {speed}"
            );
            assert!(
                momentum.norm() < 1e-9 * speed * v.v.len() as f64,
                "{momentum:?}"
            );
        } else {
            assert!(speed < 1e-12, "unconstrained: {speed}");
        }
    }
}
