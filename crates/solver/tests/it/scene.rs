//! Seeding (src/scene.rs): the ensemble jitter moves each position by at most
//! `jitter` h per axis, differently per seed, and not at all when it is 0.

use crate::common;

use common::*;
use solver::*;

fn positions(jitter: f64, seed: u64) -> Vec<Vec2> {
    let mut scene = box_scene([0.4, 0.4], [0.0, 0.0, 0.2, 0.3], Material::new(1e5), 9.81);
    scene.jitter = jitter;
    scene.seed = seed;
    let s = solver(scene, Method::baseline());
    s.view().x.to_vec()
}

#[test]
fn jitter_moves_positions_by_at_most_jitter_h_and_depends_on_the_seed() {
    let exact = positions(0.0, 0);
    assert_eq!(
        exact,
        positions(0.0, 7),
        "no jitter: the seed is irrelevant"
    );
    let h = 0.01;
    for jitter in [1e-9, 1e-3] {
        let a = positions(jitter, 1);
        let b = positions(jitter, 2);
        assert_eq!(a, positions(jitter, 1), "same seed, same positions");
        let mut largest = 0.0f64;
        for ((p, q), e) in a.iter().zip(&b).zip(&exact) {
            for axis in 0..2 {
                let d = (p[axis] - e[axis]).abs();
                assert!(d <= jitter * h * (1.0 + 1e-12) + 1e-17, "{d}");
                largest = largest.max(d);
            }
            assert_ne!(p, q, "another seed moves every particle differently");
        }
        // Uniform in [-1, 1] jitter h: the largest of thousands of draws is near the bound.
        assert!(largest > 0.9 * jitter * h, "{largest}");
    }
}
