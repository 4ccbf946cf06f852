//! Pore pressure on the grid (`pore_pressure.rs`): a saturated mixture at
//! rest is in balance (grains and water fill every node, J = 1, p = 0), and
//! the top load's ramp.

mod common;

use solver::drag::{Drag, DragModel, DragUpdate};
use solver::pore_pressure::ramp_share;
use solver::{Mixture, SchemeKind, ShapeKind, TransferKind, Vec2};

#[test]
fn a_saturated_mixture_at_rest_stays_at_rest_with_zero_pore_pressure() {
    for shape in [ShapeKind::Linear, ShapeKind::Bspline2] {
        let method = common::method(shape, TransferKind::Apic, SchemeKind::Usl);
        let full = [0.0, 0.0, 0.1, 0.1];
        let solid = common::phase(full, 2650.0, 0.6, method.clone(), |_| Vec2::zeros());
        let fluid = common::phase(full, 1000.0, 0.4, method.clone(), |_| Vec2::zeros());
        let drag = Drag {
            coefficient: 1e5,
            kozeny_carman: None,
            model: DragModel::BangBangNode,
            update: DragUpdate::Exponential,
        };
        let mut mix = Mixture::new([solid, fluid], drag)
            .unwrap()
            .with_pore_pressure();
        assert_eq!(
            mix.pore_fluid().unwrap().k,
            1e5,
            "the fluid's EOS moves to the grid"
        );
        for _ in 0..100 {
            mix.step().unwrap();
        }
        for k in 0..2 {
            let v = mix.phase(k).view();
            let speed = v.v.iter().map(|v| v.norm()).fold(0.0, f64::max);
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
