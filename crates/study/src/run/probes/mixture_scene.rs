//! What the mixture checks read off a mixture and its scene.

use crate::study_file::MixtureSpec;
use solver::{Phase, Scene, Solver, Vec2};

/// Mass-weighted mean particle velocity of a phase.
pub fn mean_velocity(s: &Solver) -> Vec2 {
    let p = s.view();
    let (mut mv, mut m) = (Vec2::zeros(), 0.0);
    for (v, mass) in p.v.iter().zip(p.mass) {
        mv += *mass * v;
        m += mass;
    }
    if m > 0.0 {
        mv / m
    } else {
        Vec2::zeros()
    }
}

/// Total momentum and the sum of |m v| (its scale).
pub fn momentum_and_scale(s: &Solver) -> (Vec2, f64) {
    let p = s.view();
    p.v.iter()
        .zip(p.mass)
        .fold((Vec2::zeros(), 0.0), |(sum, scale), (v, m)| {
            (sum + *m * v, scale + m * v.norm())
        })
}

/// A fixed skeleton layer spanning the box's width in a box periodic in x
/// and y. Returns the layer's [y0, y1].
pub fn fixed_layer(scene: &Scene, spec: &MixtureSpec) -> Option<[f64; 2]> {
    let solids: Vec<_> = scene
        .bodies
        .iter()
        .filter(|b| b.phase == Some(Phase::Solid))
        .collect();
    let tol = 1e-12 * scene.size[0];
    let spans = |r: &[f64; 4]| {
        (r[0] - scene.origin[0]).abs() <= tol
            && (r[2] - scene.origin[0] - scene.size[0]).abs() <= tol
    };
    let [layer] = solids.as_slice() else {
        return None;
    };
    (spec.fixed_solid && scene.periodic == [true, true] && spans(&layer.rect))
        .then_some([layer.rect[1], layer.rect[3]])
}
