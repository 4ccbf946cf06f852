//! A two-phase mixture is deterministic: bit-identical states for 1 and 2
//! threads, and a restart from its checkpoint continues bit for bit
//! (the explicit drag's step limit included); damaged checkpoints are refused.

use solver::multiphase::drag::{Drag, DragModel, DragUpdate};
use solver::*;

use crate::common;

fn mixture(update: DragUpdate) -> Mixture {
    let method = common::method(ShapeKind::Bspline2, TransferKind::Apic, SchemeKind::Usl);
    let solid = common::phase([0.02, 0.0, 0.08, 0.05], 2500.0, 0.6, method.clone(), |x| {
        Vec2::new(0.05 * (60.0 * x.y).sin(), 0.0)
    });
    let fluid = common::phase_under_gravity(
        [0.0, 0.02, 0.1, 0.09],
        1000.0,
        0.4,
        method,
        |x| Vec2::new(0.2 * (40.0 * x.x).sin(), -0.1),
        9.81,
    );
    let drag = Drag {
        coefficient: Drag::from_permeability(1e-3, 1e-8, 0.4),
        kozeny_carman: Some(0.4),
        model: DragModel::BangBangNode,
        update,
    };
    Mixture::new([solid, fluid], drag).unwrap()
}

fn run_in_pool(threads: usize, update: DragUpdate, steps: usize) -> u64 {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    pool.install(|| {
        let mut m = mixture(update);
        for _ in 0..steps {
            m.step().unwrap();
        }
        m.state_hash()
    })
}

#[test]
fn one_and_two_threads_give_the_same_bits() {
    for update in [
        DragUpdate::Explicit,
        DragUpdate::Implicit,
        DragUpdate::Exponential,
    ] {
        assert_eq!(
            run_in_pool(1, update, 300),
            run_in_pool(2, update, 300),
            "{update:?}"
        );
    }
}

#[test]
fn a_restart_from_a_checkpoint_continues_bit_for_bit() {
    for update in [DragUpdate::Explicit, DragUpdate::Exponential] {
        let mut a = mixture(update);
        for _ in 0..150 {
            a.step().unwrap();
        }
        let saved = a.checkpoint();
        for _ in 0..150 {
            a.step().unwrap();
        }
        let mut b = mixture(update);
        b.restore(&saved).unwrap();
        for _ in 0..150 {
            b.step().unwrap();
        }
        assert_eq!(a.state_hash(), b.state_hash(), "{update:?}");
        assert_eq!(a.time(), b.time());
        assert_eq!(a.energy(), b.energy());
        let mut damaged = saved.clone();
        let k = damaged.len() / 2;
        damaged[k] ^= 1;
        assert!(mixture(update).restore(&damaged).is_err());
        assert!(mixture(update).restore(&saved[..saved.len() - 9]).is_err());
    }
}

/// The pore pressure on the grid and the top load keep both promises: the
/// same bits on 1 and 2 threads, and a restart continues bit for bit.
#[test]
fn pore_pressure_and_load_are_deterministic_and_restart_bit_for_bit() {
    let build = || {
        mixture(DragUpdate::Exponential)
            .with_pore_pressure()
            .with_top_load(1e3, 0.002)
    };
    let hash_on = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            let mut m = build();
            for _ in 0..300 {
                m.step().unwrap();
            }
            m.state_hash()
        })
    };
    assert_eq!(hash_on(1), hash_on(2));
    let mut a = build();
    for _ in 0..150 {
        a.step().unwrap();
    }
    let saved = a.checkpoint();
    for _ in 0..150 {
        a.step().unwrap();
    }
    let mut b = build();
    b.restore(&saved).unwrap();
    for _ in 0..150 {
        b.step().unwrap();
    }
    assert_eq!(a.state_hash(), b.state_hash());
    assert_eq!(a.energy(), b.energy());
}
