//! `[method.pic_damping] time = tau`: the FLIP/PIC blend of each step is
//! 1 - min(dt / tau, 1) (docs/physics.md section 5), bit for bit the same
//! as the constant blend it stands for; refused where it makes no sense.

use crate::common;

use solver::remedies::pic_damping;
use solver::*;

const DT: f64 = 2e-4;

fn dam(method: Method) -> Solver {
    let mut mat = Material::tait(1.5e4);
    mat.viscosity = 0.5;
    common::solver(Scene::dam_break(mat), method)
}

/// FLIP at `alpha`, with PIC damping of time `tau` (None: off).
fn flip(alpha: f64, tau: Option<f64>) -> Method {
    let mut method = Method {
        flip_alpha: alpha,
        dt: DtMode::Fixed,
        dt_value: Some(DT),
        ..common::method(ShapeKind::Bspline2, TransferKind::Flip, SchemeKind::Usl)
    };
    method.remedies.pic_damping = tau.map(|time| pic_damping::Settings { time });
    method
}

fn hash_after(method: Method, steps: usize) -> u64 {
    let mut s = dam(method);
    for _ in 0..steps {
        s.step().unwrap();
    }
    s.state_hash()
}

#[test]
fn the_blend_is_one_minus_dt_over_tau() {
    // dt / tau = 1/4 exactly: the blend is FLIP 0.75.
    let damped = hash_after(flip(1.0, Some(4.0 * DT)), 200);
    assert_eq!(damped, hash_after(flip(0.75, None), 200));
    assert_ne!(damped, hash_after(flip(1.0, None), 200), "it changes FLIP");
}

#[test]
fn tau_at_or_below_dt_is_pic() {
    let pic = Method {
        transfer: TransferKind::Pic,
        ..flip(1.0, None)
    };
    assert_eq!(hash_after(flip(1.0, Some(DT)), 100), hash_after(pic, 100));
}

#[test]
fn refused_unless_flip_with_its_blend_left_at_one() {
    let scene = Scene::dam_break(Material::tait(1.5e4));
    let apic = Method {
        transfer: TransferKind::Apic,
        ..flip(1.0, Some(0.01))
    };
    let blended = flip(0.9, Some(0.01));
    // Off is None: a zero or negative time is out of range.
    let negative = flip(1.0, Some(-1.0));
    let zero = flip(1.0, Some(0.0));
    for (method, key) in [
        (apic, "method.pic_damping"),
        (blended, "method.pic_damping"),
        (negative, "method.pic_damping.time"),
        (zero, "method.pic_damping.time"),
    ] {
        let err = common::refusal(scene.clone(), method).expect("refused");
        assert_eq!(err.key, key, "{err:?}");
    }
}
