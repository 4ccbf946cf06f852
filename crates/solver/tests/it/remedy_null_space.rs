//! Null-space filter (Gritton & Berzins 2017), its defining property: the
//! W-orthogonal projection onto the span of the shape functions. A velocity
//! field S u comes back unchanged (where PIC keeps 1/16 of a lattice
//! checkerboard), a second pass changes nothing, and what it removes is
//! invisible to the grid (S^T W z = 0: PIC of it is zero). Measured through
//! FLIP steps of a stress-free, gravity-free periodic box with a tiny dt, so
//! FLIP's increment is nil and the filter is all that acts.

use crate::common;

use solver::remedies::null_space_filter;
use solver::*;

const H: f64 = 0.1;

fn config(shape: ShapeKind, transfer: TransferKind, filter: bool, jitter: f64) -> SolverConfig {
    let mut material = Material::tait(1.0);
    material.viscosity = 0.0;
    let mut scene = common::box_scene([0.8, 0.8], [0.0, 0.0, 0.8, 0.8], material, 0.0);
    scene.cell = H;
    scene.periodic = [true, true];
    scene.jitter = jitter;
    scene.seed = 7;
    let mut method = Method {
        dt_value: Some(1e-12),
        ..common::method(shape, transfer, SchemeKind::Usl)
    };
    method.remedies.null_space_filter = filter.then(null_space_filter::Settings::default);
    SolverConfig {
        scene,
        method,
        perturb: vec![],
    }
}

fn solver_with(cfg: SolverConfig, v: impl Fn(usize, Vec2) -> Vec2) -> Solver {
    let mut ps = solver::scene::seed(&cfg.scene);
    for p in 0..ps.len() {
        ps.v[p] = v(p, ps.x[p]);
    }
    Solver::with_particles(cfg, ps)
}

/// A reproducible velocity in [-1, 1]^2 per particle.
fn noise(p: usize) -> Vec2 {
    let mut z = (p as u64 + 1).wrapping_mul(0x9E37_79B9_7F4A_7C15);
    let mut next = || {
        z ^= z >> 31;
        z = z.wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z ^= z >> 29;
        (z >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    };
    Vec2::new(next(), next())
}

#[test]
fn a_velocity_in_the_span_of_the_shapes_is_kept_where_pic_keeps_a_sixteenth() {
    for (transfer, filter, kept) in [
        (TransferKind::Flip, true, 1.0),
        (TransferKind::Pic, false, 1.0 / 16.0),
    ] {
        let cfg = config(ShapeKind::Linear, transfer, filter, 0.0);
        let mut s = solver_with(cfg, |_, x| common::lattice_checkerboard(x, H));
        let before: Vec<Vec2> = s.view().v.to_vec();
        s.step().unwrap();
        for (p, v0) in before.iter().enumerate() {
            let v = s.view().v[p];
            assert!(
                (v.x - kept * v0.x).abs() < 1e-9 && v.y.abs() < 1e-9,
                "{transfer:?} filter {filter}, particle {p}: {v} from {v0}"
            );
        }
    }
}

#[test]
fn the_filter_is_a_projection_that_removes_only_what_the_grid_cannot_see() {
    for shape in [ShapeKind::Linear, ShapeKind::Bspline2, ShapeKind::Bspline3] {
        // Disordered particles (none across the periodic seam), random velocities.
        let cfg = config(shape, TransferKind::Flip, true, 0.2);
        let mut s = solver_with(cfg.clone(), |p, _| noise(p));
        let w: Vec<Vec2> = s.view().v.to_vec();
        let x0: Vec<Vec2> = s.view().x.to_vec();
        s.step().unwrap();
        let f: Vec<Vec2> = s.view().v.to_vec();
        let removed: f64 = w.iter().zip(&f).map(|(a, b)| (a - b).norm()).sum();
        assert!(
            removed > 1e-2 * w.len() as f64,
            "{shape:?}: nothing removed"
        );
        // Momentum is kept (partition of unity on S^T W).
        let mass = s.view().mass.to_vec();
        let momentum = |v: &[Vec2]| -> Vec2 { v.iter().zip(&mass).map(|(v, m)| *m * v).sum() };
        assert!(
            (momentum(&w) - momentum(&f)).norm() < 1e-10 * mass.iter().sum::<f64>(),
            "{shape:?}"
        );
        // A second pass changes nothing (the particles moved by 1e-12 s x |v|).
        s.step().unwrap();
        for (p, f0) in f.iter().enumerate() {
            let v = s.view().v[p];
            assert!(
                (v - f0).norm() < 1e-8,
                "{shape:?} particle {p}: {v} then {f0}"
            );
        }
        // What it removed, z = w - f, has no grid momentum: PIC returns ~0.
        let pic = config(shape, TransferKind::Pic, false, 0.2);
        let mut z = solver_with(pic, |p, _| w[p] - f[p]);
        assert_eq!(z.view().x, &x0[..]);
        z.step().unwrap();
        let largest = z.view().v.iter().map(|v| v.norm()).fold(0.0, f64::max);
        assert!(
            largest < 1e-8,
            "{shape:?}: PIC of the removed part {largest}"
        );
    }
}

#[test]
fn the_filter_needs_flip() {
    for transfer in [TransferKind::Pic, TransferKind::Apic, TransferKind::Xpic] {
        let cfg = config(ShapeKind::Bspline2, transfer, true, 0.0);
        let err = Solver::new(cfg).err().expect("refused");
        assert_eq!(err.key, "method.null_space_filter", "{err}");
        assert!(
            format!("{err}").contains("method.null_space_filter"),
            "{err}"
        );
    }
}
