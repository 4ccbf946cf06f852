//! Particle shifting (docs/physics.md section 5): a lattice is a fixed point
//! up to the walls and the free surface, a slit the grid cannot see closes
//! while the surface stays within 0.1 l, and the combinations that make no sense are
//! refused. Without gravity and with J = 1 the water stays at rest, so the
//! shifting is the only thing that moves the particles.

use crate::common;

use solver::grid::Grid;
use solver::particles::Particles;
use solver::remedies::shifting;
use solver::*;

/// Water in the bottom-left of a walled box, on the seeding lattice
/// (2 x 2 per cell of 1 cm), no gravity: it touches the left, bottom and
/// right walls and has a free surface on top.
fn pool(shift_time: f64) -> (Scene, Method) {
    let scene = common::box_scene([0.3, 0.3], [0.0, 0.0, 0.3, 0.1], Material::tait(1e5), 0.0);
    let mut method = common::method(ShapeKind::Bspline2, TransferKind::Pic, SchemeKind::Usl);
    method.remedies.shifting = Some(shifting::Settings {
        time: shift_time,
        ..Default::default()
    });
    (scene, method)
}

/// The seeding spacing l = h / ppc.
const L: f64 = 0.005;

/// A solver over particles seeded and then edited by the test.
fn solver_with(scene: Scene, method: Method, ps: Particles) -> Solver {
    let cfg = SolverConfig {
        scene,
        method,
        perturb: vec![],
    };
    Solver::with_particles(cfg, ps)
}

fn max_y(x: &[Vec2]) -> f64 {
    x.iter().map(|p| p.y).fold(f64::MIN, f64::max)
}

#[test]
fn a_lattice_is_a_fixed_point_up_to_the_walls_and_the_surface() {
    for share in [0.75, 0.25] {
        lattice_stays(share);
    }
}

fn lattice_stays(share: f64) {
    let (scene, mut method) = pool(1e-3);
    method.remedies.shifting.as_mut().unwrap().surface_share = share;
    let mut s = common::solver(scene, method);
    let before = s.view().x.to_vec();
    for _ in 0..50 {
        s.step().unwrap();
    }
    let after = s.view().x;
    let worst = before
        .iter()
        .zip(after)
        .map(|(a, b)| (a - b).norm())
        .fold(0.0, f64::max);
    // l = 5 mm; round-off of a concentration of exactly 1.
    assert!(
        worst < 1e-14,
        "surface share {share}: largest move {worst} m"
    );
}

/// The spread (max - min) of the concentration over the fine nodes well
/// inside the pool (two cells from every edge).
fn spread(x: &[Vec2], vol0: f64) -> f64 {
    let grid = Grid::new(Vec2::zeros(), 0.01, [30, 30], [false, false]);
    let mut ps = Particles::default();
    for &p in x {
        ps.push(p, Vec2::zeros(), 1.0, vol0, 0);
    }
    let mut scratch = shifting::Scratch::new(&grid, 2);
    shifting::concentration(&ps, &grid, &mut scratch);
    let (mut lo, mut hi) = (f64::MAX, f64::MIN);
    for j in 4..=16 {
        for i in 4..=56 {
            let c = scratch.concentration(i, j);
            lo = lo.min(c);
            hi = hi.max(c);
        }
    }
    hi - lo
}

#[test]
fn a_slit_the_grid_cannot_see_closes_and_the_surface_stays() {
    let (scene, method) = pool(0.02);
    let mut ps = solver::scene::seed(&scene);
    let vol0 = ps.vol0[0];
    // Open a slit: the line of particles at x = 0.1525 moves onto its left
    // neighbours' line, x = 0.1475, leaving a gap of 2 l next to a doubled line.
    for p in 0..ps.len() {
        if (ps.x[p].x - 0.1525).abs() < 1e-9 {
            ps.x[p].x = 0.1475;
        }
    }
    let top0 = max_y(&ps.x);
    let mut s = solver_with(scene, method, ps);
    let spread0 = spread(s.view().x, vol0);
    assert!(spread0 > 0.5, "the slit shows on the fine grid: {spread0}");
    let mut spreads = vec![spread0];
    for _ in 0..16 {
        for _ in 0..100 {
            s.step().unwrap();
            let top = max_y(s.view().x);
            // Never outward along the grid mass's normal; near the slit that
            // normal leans, so the top may rise a little (0.085 l measured).
            assert!(top - top0 < 0.1 * L, "the surface rose by {} m", top - top0);
        }
        spreads.push(spread(s.view().x, vol0));
    }
    assert!(spreads.windows(2).all(|w| w[1] < w[0]), "{spreads:?}");
    assert!(spreads[16] < 0.3 * spread0, "spread {spreads:?}");
    // Velocities are untouched: the water is still at rest.
    assert!(s.view().v.iter().all(|v| v.norm() < 1e-12));
}

/// The particles in the band next to the right wall (x > 0.29 m).
fn band_count(x: &[Vec2]) -> usize {
    x.iter().filter(|p| p.x > 0.29).count()
}

/// The pool with every other row of the band next to the right wall taken
/// out (20 of its 40 particles), run for `steps` with the surface test at
/// `share`; returns the band's count and how far the top rose (m).
fn depleted_band(share: f64, steps: usize) -> (usize, f64) {
    let (scene, mut method) = pool(0.02);
    method.remedies.shifting.as_mut().unwrap().surface_share = share;
    let mut ps = solver::scene::seed(&scene);
    let keep: Vec<usize> = (0..ps.len())
        .filter(|&p| ps.x[p].x < 0.29 || ((ps.x[p].y / L) as usize).is_multiple_of(2))
        .collect();
    let mut thinned = Particles::default();
    for p in keep {
        thinned.push(ps.x[p], Vec2::zeros(), ps.mass[p], ps.vol0[p], 0);
    }
    ps = thinned;
    assert_eq!(band_count(&ps.x), 20);
    let top0 = max_y(&ps.x);
    let mut s = solver_with(scene, method, ps);
    for _ in 0..steps {
        s.step().unwrap();
    }
    (band_count(s.view().x), max_y(s.view().x) - top0)
}

#[test]
fn a_depleted_band_at_a_wall_refills_when_the_surface_test_tells_it_from_a_surface() {
    // At 0.75 the band's nodes (about half full) count as a surface, whose
    // outward direction is into the band: no particle enters it.
    let (locked, _) = depleted_band(0.75, 1600);
    assert_eq!(locked, 20);
    // At 0.25 only near-empty nodes make a surface: the band refills (37 of
    // 40 measured) and the top stays within 0.1 l.
    let (refilled, rise) = depleted_band(0.25, 1600);
    assert!(refilled >= 35, "{refilled} particles in the band");
    assert!(rise < 0.1 * L, "the surface rose by {rise} m");
}

#[test]
fn refused_where_it_makes_no_sense() {
    let (scene, method) = pool(0.05);
    let mut periodic = scene.clone();
    periodic.periodic = [true, false];
    let err = common::refusal(periodic, method.clone()).expect("periodic refused");
    assert_eq!(err.key, "method.shifting");
    let mut solid = scene.clone();
    solid.materials[0].shear_modulus = 1e4;
    let err = common::refusal(solid, method.clone()).expect("solid refused");
    assert_eq!(err.key, "method.shifting");
    // Off is None: a zero or negative time is out of range.
    for time in [-1.0, 0.0] {
        let (_, bad) = pool(time);
        let err = common::refusal(scene.clone(), bad).expect("time refused");
        assert_eq!(err.key, "method.shifting.time", "{time}");
    }
    let mut no_surface = method;
    no_surface.remedies.shifting.as_mut().unwrap().surface_share = 0.0;
    let err = common::refusal(scene, no_surface).expect("share 0 refused");
    assert_eq!(err.key, "method.shifting.surface_share");
}
