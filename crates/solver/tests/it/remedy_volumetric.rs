//! The defining property of each volumetric remedy (docs/physics.md section 5),
//! on a disordered block whose J varies from particle to particle: the
//! stress stage runs with a zero grid velocity, so F and J change only by
//! the remedy.

#![allow(clippy::needless_range_loop)]

use crate::common;

use solver::remedies::{
    cell_dilatation, j_bar, pressure_smoothing, volume_relaxation, RemedySettings,
};
use solver::*;

/// A block of 2 x 2 ppc at h = 0.05 with jittered positions and J = 1 +
/// a x + noise (F = J^(1/2) I, V = V0 J), linear EOS (p = K (1 - J)).
fn disordered(method: Method, noise: f64) -> (Solver, Vec<f64>) {
    let mut material = Material::tait(1e5);
    material.eos = EosKind::Linear;
    let mut scene = common::box_scene([1.0, 1.0], [0.2, 0.2, 0.8, 0.8], material, 0.0);
    scene.cell = 0.05;
    let cfg = SolverConfig {
        scene: scene.clone(),
        method,
        perturb: vec![],
    };
    let mut ps = solver::scene::seed(&scene);
    let mut state = 7u64;
    for p in 0..ps.len() {
        let jx = solver::scene::uniform01(&mut state) - 0.5;
        let jy = solver::scene::uniform01(&mut state) - 0.5;
        ps.x[p] += Vec2::new(jx, jy) * 0.02;
        let j = 1.0 + 0.05 * ps.x[p].x + noise * (solver::scene::uniform01(&mut state) - 0.5);
        ps.j[p] = j;
        ps.f[p] = Mat2::identity() * j.sqrt();
        ps.vol[p] = ps.vol0[p] * j;
    }
    let j0 = ps.j.clone();
    (Solver::with_particles(cfg, ps), j0)
}

fn apply(s: &mut Solver) {
    s.run_stage(Stage::Sort).unwrap();
    s.run_stage(Stage::Stress).unwrap();
}

fn method(shape: ShapeKind) -> Method {
    common::method(shape, TransferKind::Pic, SchemeKind::Usl)
}

/// `method(shape)` with its remedies set by `set`.
fn with(shape: ShapeKind, set: impl FnOnce(&mut RemedySettings)) -> Method {
    let mut m = method(shape);
    set(&mut m.remedies);
    m
}

fn j_bar(blend: f64) -> Option<j_bar::Settings> {
    Some(j_bar::Settings {
        blend,
        ..Default::default()
    })
}

fn cell_dilatation(blend: f64) -> Option<cell_dilatation::Settings> {
    Some(cell_dilatation::Settings {
        blend,
        ..Default::default()
    })
}

#[test]
fn cell_dilatation_makes_j_and_p_constant_per_cell_and_keeps_the_volume() {
    let (mut s, _) = disordered(
        with(ShapeKind::Linear, |r| {
            r.cell_dilatation = cell_dilatation(1.0)
        }),
        0.02,
    );
    let before: f64 = s.view().volume.iter().sum();
    apply(&mut s);
    let v = s.view();
    let after: f64 = v.volume.iter().sum();
    assert!((after / before - 1.0).abs() < 1e-14, "{before} -> {after}");
    let cell = |x: Vec2| ((x.x / 0.05) as usize, (x.y / 0.05) as usize);
    let mut per_cell = std::collections::BTreeMap::new();
    for p in 0..v.x.len() {
        let (j, pr) = per_cell
            .entry(cell(v.x[p]))
            .or_insert((v.j[p], v.pressure[p]));
        assert_eq!(*j, v.j[p], "J constant in a cell");
        assert_eq!(*pr, v.pressure[p], "p constant in a cell");
        assert!((v.deformation[p].determinant() / v.j[p] - 1.0).abs() < 1e-14);
    }
    assert!(per_cell.len() > 100);
}

#[test]
fn cell_dilatation_leaves_a_cell_with_an_inverted_particle_alone() {
    let (s0, _) = disordered(
        with(ShapeKind::Linear, |r| {
            r.cell_dilatation = cell_dilatation(1.0)
        }),
        0.0,
    );
    // The lattice at J = 1 with one particle inverted: its cell keeps its own J values.
    let cfg = s0.config().clone();
    let mut ps = solver::scene::seed(&cfg.scene);
    let victim = ps.len() / 2;
    ps.j[victim] = -0.1;
    ps.f[victim] = Mat2::new(-0.1, 0.0, 0.0, 1.0);
    let x_v = ps.x[victim];
    let mates: Vec<usize> = (0..ps.len())
        .filter(|&p| ((ps.x[p] - x_v) / 0.05).map(|c| c.abs()).max() < 0.5)
        .collect();
    let mut s = Solver::with_particles(cfg, ps);
    apply(&mut s);
    let v = s.view();
    assert_eq!(v.j[victim], -0.1, "the inversion stays visible");
    for p in mates {
        assert!(v.j[p] == 1.0 || p == victim, "cell mate {p}: J {}", v.j[p]);
    }
}

#[test]
fn j_bar_conserves_mass_weighted_volume_and_blends() {
    for shape in [ShapeKind::Linear, ShapeKind::Bspline2, ShapeKind::Bspline3] {
        let (mut s, j0) = disordered(with(shape, |r| r.j_bar = j_bar(1.0)), 0.02);
        let mj = |v: &StateView| -> f64 { v.mass.iter().zip(v.j).map(|(m, j)| m * j).sum() };
        let before = mj(&s.view());
        apply(&mut s);
        let v = s.view();
        let after = mj(&v);
        assert!(
            (after / before - 1.0).abs() < 1e-13,
            "{shape:?}: {before} -> {after}"
        );
        let changed = v.j.iter().zip(&j0).filter(|(a, b)| a != b).count();
        assert!(changed > v.j.len() / 2, "{shape:?}: the noise is averaged");
        // Blend 1/2: halfway between the particle's J and the full average.
        let (mut half, _) = disordered(with(shape, |r| r.j_bar = j_bar(0.5)), 0.02);
        apply(&mut half);
        let h = half.view();
        for p in 0..h.j.len() {
            let expected = 0.5 * j0[p] + 0.5 * v.j[p];
            assert!((h.j[p] - expected).abs() < 1e-14, "{shape:?} particle {p}");
        }
    }
}

#[test]
fn pressure_smoothing_conserves_mass_weighted_pressure_and_keeps_a_linear_field_inside() {
    for shape in [ShapeKind::Linear, ShapeKind::Bspline2] {
        // On the undisturbed lattice with J linear in x, p = K (1 - J) is linear.
        let mut s = lattice(
            with(shape, |r| {
                r.pressure_smoothing = Some(pressure_smoothing::Settings {})
            }),
            |x| 1.0 - 0.01 * x.x,
        );
        let k = s.config().scene.materials[0].k;
        let raw: Vec<f64> = s.view().j.iter().map(|j| k * (1.0 - j)).collect();
        apply(&mut s);
        let v = s.view();
        let mp = |p: &[f64]| -> f64 { v.mass.iter().zip(p).map(|(m, p)| m * p).sum() };
        assert!((mp(v.pressure) / mp(&raw) - 1.0).abs() < 1e-13, "{shape:?}");
        let (mut inside, mut edge) = (0.0f64, 0.0f64);
        // Full stencils two deep: the particle's nodes and their particles.
        let reach = 0.05 * if shape == ShapeKind::Linear { 2.0 } else { 3.0 };
        for p in 0..v.x.len() {
            let x = v.x[p];
            let err = (v.pressure[p] - raw[p]).abs() / (k * 0.01 * 0.05);
            let interior =
                x.x > 0.2 + reach && x.x < 0.8 - reach && x.y > 0.2 + reach && x.y < 0.8 - reach;
            if interior {
                inside = inside.max(err);
            } else {
                edge = edge.max(err);
            }
        }
        // Linear fields are kept where the stencil is full; at the edges they are not.
        assert!(
            inside < 1e-9,
            "{shape:?}: interior error {inside} (K a h units)"
        );
        eprintln!("{shape:?}: largest change at the block's edge {edge:.3} K a h");
    }
}

/// `carry = false` (of `j_bar` or `cell_dilatation`): the averaged J sets
/// this step's pressure (and volume), while each particle keeps its own J
/// and F.
#[test]
fn averaged_j_can_set_the_stress_without_being_carried() {
    for use_j_bar in [true, false] {
        let set = |carry: bool| {
            with(ShapeKind::Bspline2, |r| {
                if use_j_bar {
                    r.j_bar = Some(j_bar::Settings {
                        carry,
                        ..Default::default()
                    });
                } else {
                    r.cell_dilatation = Some(cell_dilatation::Settings {
                        carry,
                        ..Default::default()
                    });
                }
            })
        };
        let (mut carried, j0) = disordered(set(true), 0.02);
        let (mut own, _) = disordered(set(false), 0.02);
        apply(&mut carried);
        apply(&mut own);
        let (c, o) = (carried.view(), own.view());
        let f0: Vec<Mat2> = j0.iter().map(|j| Mat2::identity() * j.sqrt()).collect();
        for p in 0..o.j.len() {
            // The stress stage's own update (L = 0) rounds J = det F once.
            assert!(
                (o.j[p] - j0[p]).abs() < 1e-15,
                "own J kept: {} vs {}",
                o.j[p],
                j0[p]
            );
            assert!((o.deformation[p] - f0[p]).norm() < 1e-15, "own F kept");
            assert_eq!(o.pressure[p], c.pressure[p], "pressure from the average");
            assert_eq!(o.volume[p], c.volume[p], "volume from the average");
        }
        assert!(c.j.iter().zip(&j0).filter(|(a, b)| a != b).count() > c.j.len() / 2);
    }
}

/// `average_increment`: J-bar of this step's ratio J_new / J_old leaves a
/// field at rest alone, where J-bar of J smooths it (the zero grid velocity
/// here makes every ratio 1).
#[test]
fn j_bar_of_the_increment_leaves_a_field_at_rest_alone() {
    let (mut s, j0) = disordered(
        with(ShapeKind::Bspline2, |r| {
            r.j_bar = Some(j_bar::Settings {
                average_increment: true,
                ..Default::default()
            })
        }),
        0.02,
    );
    apply(&mut s);
    let v = s.view();
    for p in 0..v.j.len() {
        assert!(
            (v.j[p] - j0[p]).abs() < 1e-15,
            "{p}: {} vs {}",
            v.j[p],
            j0[p]
        );
    }
}

/// The undisturbed lattice block (h = 0.05, linear EOS) with J = `j(x)`
/// (F = J^(1/2) I, V = V0 J).
fn lattice(method: Method, j: impl Fn(Vec2) -> f64) -> Solver {
    let mut material = Material::tait(1e5);
    material.eos = EosKind::Linear;
    let mut scene = common::box_scene([1.0, 1.0], [0.2, 0.2, 0.8, 0.8], material, 0.0);
    scene.cell = 0.05;
    let mut ps = solver::scene::seed(&scene);
    for p in 0..ps.len() {
        let jp = j(ps.x[p]);
        ps.j[p] = jp;
        ps.f[p] = Mat2::identity() * jp.sqrt();
        ps.vol[p] = ps.vol0[p] * jp;
    }
    let cfg = SolverConfig {
        scene,
        method,
        perturb: vec![],
    };
    Solver::with_particles(cfg, ps)
}

/// The lattice block after one J-bar pass of the given fit; returns the
/// positions, the J before and the J after.
fn lattice_j_bar(
    shape: ShapeKind,
    fit: JBarFit,
    j: impl Fn(Vec2) -> f64,
) -> (Vec<Vec2>, Vec<f64>, Vec<f64>) {
    let method = with(shape, |r| {
        r.j_bar = Some(j_bar::Settings {
            fit,
            ..Default::default()
        })
    });
    let mut s = lattice(method, j);
    let (x, j0) = (s.view().x.to_vec(), s.view().j.to_vec());
    apply(&mut s);
    let after = s.view().j.to_vec();
    (x, j0, after)
}

/// `j_bar_fit = "linear"`: a linear J field (the hydrostatic one) is a fixed
/// point up to the block's edges and corners, where the mean of the
/// constant fit bends it; sum m J is conserved for a disordered block.
#[test]
fn j_bar_linear_fit_keeps_a_linear_field_to_the_edges_and_conserves_volume() {
    let linear_j = |x: Vec2| 1.0 + 0.01 * x.x - 0.02 * x.y;
    for shape in [ShapeKind::Linear, ShapeKind::Bspline2, ShapeKind::Bspline3] {
        let worst = |fit| {
            let (_, j0, j1) = lattice_j_bar(shape, fit, linear_j);
            j0.iter()
                .zip(&j1)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0f64, f64::max)
        };
        let (linear, constant) = (worst(JBarFit::Linear), worst(JBarFit::Constant));
        // In units of J's change over a cell (0.02 x 0.05 = 1e-3).
        assert!(linear < 1e-12, "{shape:?}: linear fit moved J by {linear}");
        assert!(
            constant > 1e-5,
            "{shape:?}: the constant fit bends the edges ({constant})"
        );

        let (mut s, _) = disordered(
            with(shape, |r| {
                r.j_bar = Some(j_bar::Settings {
                    fit: JBarFit::Linear,
                    ..Default::default()
                })
            }),
            0.02,
        );
        let mj = |v: &StateView| -> f64 { v.mass.iter().zip(v.j).map(|(m, j)| m * j).sum() };
        let before = mj(&s.view());
        apply(&mut s);
        let after = mj(&s.view());
        assert!(
            (after / before - 1.0).abs() < 1e-13,
            "{shape:?}: {before} -> {after}"
        );
    }
}

/// Both fits take a particle checkerboard on the lattice out of J wherever
/// the stencils are full two deep: the weighted mean and the weighted first
/// moment of the checkerboard vanish over a full support.
#[test]
fn j_bar_linear_fit_removes_a_lattice_checkerboard() {
    let checker = |x: Vec2| {
        let (i, j) = (((x.x - 0.2) / 0.025) as i64, ((x.y - 0.2) / 0.025) as i64);
        1.0 + 0.01 * if (i + j) % 2 == 0 { 1.0 } else { -1.0 }
    };
    for shape in [ShapeKind::Linear, ShapeKind::Bspline2, ShapeKind::Bspline3] {
        let reach = 0.05
            * if shape == ShapeKind::Bspline3 {
                4.0
            } else {
                3.0
            };
        let (x, _, j1) = lattice_j_bar(shape, JBarFit::Linear, checker);
        let mut inside = 0.0f64;
        for p in 0..x.len() {
            let interior = x[p].x > 0.2 + reach
                && x[p].x < 0.8 - reach
                && x[p].y > 0.2 + reach
                && x[p].y < 0.8 - reach;
            if interior {
                inside = inside.max((j1[p] - 1.0).abs());
            }
        }
        assert!(inside < 1e-12, "{shape:?}: checkerboard left {inside}");
    }
}

/// A lattice block resting in the box's lower-left corner, its particles
/// moved towards the corner by the factor `squeeze` while J stays 1 (as if
/// J had drifted from the packing), after one step's stages with a
/// relaxation time below dt (full blend) and no gravity: positions, J.
fn squeezed_block(squeeze: f64, shape: ShapeKind) -> (Vec<Vec2>, Vec<f64>) {
    let mut material = Material::tait(1e5);
    material.eos = EosKind::Linear;
    let mut scene = common::box_scene([1.0, 1.0], [0.0, 0.0, 0.6, 0.6], material, 0.0);
    scene.cell = 0.05;
    let cfg = SolverConfig {
        scene: scene.clone(),
        method: with(shape, |r| {
            r.volume_relaxation = Some(volume_relaxation::Settings { time: 1e-12 })
        }),
        perturb: vec![],
    };
    let mut ps = solver::scene::seed(&scene);
    for x in ps.x.iter_mut() {
        *x *= squeeze;
    }
    let mut s = Solver::with_particles(cfg, ps);
    for stage in Stage::ALL {
        s.run_stage(stage).unwrap();
    }
    let v = s.view();
    (v.x.to_vec(), v.j.to_vec())
}

/// Volume consistency: J follows the packing. Particles packed as their J
/// says keep J = 1, at the walls too (the folded mass counts the mirror
/// images); particles squeezed together with J = 1 get J = squeeze^2 where
/// their stencil is inside the material, and keep J near the free edges.
#[test]
fn volume_consistency_sets_j_from_how_closely_particles_pack() {
    for shape in [ShapeKind::Linear, ShapeKind::Bspline2, ShapeKind::Bspline3] {
        // A stencil's nodes and their supports: a full node mass needs the
        // material this deep.
        let reach = 0.05
            * match shape {
                ShapeKind::Linear => 2.0,
                ShapeKind::Bspline2 => 3.0,
                _ => 4.0,
            };
        let (x, j) = squeezed_block(1.0, shape);
        let (mut inside, mut wall) = (0usize, 0.0f64);
        for p in 0..x.len() {
            let near_free_edge = x[p].x > 0.6 - reach || x[p].y > 0.6 - reach;
            if !near_free_edge {
                inside += 1;
                wall = wall.max((j[p] - 1.0).abs());
            }
        }
        assert!(inside > 200, "{shape:?}: {inside}");
        assert!(
            wall < 1e-12,
            "{shape:?}: consistent packing moved J by {wall}"
        );

        let squeeze = 0.98;
        let (x, j) = squeezed_block(squeeze, shape);
        let (mut worst, mut kept) = (0.0f64, 0usize);
        for p in 0..x.len() {
            let top = 0.6 * squeeze;
            if x[p].x < top - reach && x[p].y < top - reach {
                worst = worst.max((j[p] / (squeeze * squeeze) - 1.0).abs());
            } else if j[p] == 1.0 {
                kept += 1;
            }
        }
        // The squeezed lattice no longer matches the grid: its aliasing
        // leaves a residue of order (1 - squeeze)^2 or smaller.
        eprintln!("{shape:?}: squeezed J off the packing by {worst:.2e}");
        assert!(worst < 1e-3, "{shape:?}: J off the packing by {worst}");
        assert!(kept > 0, "{shape:?}: J kept at the free edges");
    }
}

/// Blends and relaxation times out of range (off is None: 0 is out of
/// range too), and the combinations that contradict each other, are refused
/// by key: two averagings of J, the increment averaged but not carried, and
/// a relaxation that an uncarried average would undo.
#[test]
fn out_of_range_and_contradicting_volumetric_settings_are_refused() {
    let scene = common::box_scene([1.0, 1.0], [0.2, 0.2, 0.8, 0.8], Material::tait(1e5), 9.81);
    let shape = ShapeKind::Bspline2;
    let relax = |time| Some(volume_relaxation::Settings { time });
    let uncarried_j_bar = Some(j_bar::Settings {
        carry: false,
        ..Default::default()
    });
    let uncarried_cell = Some(cell_dilatation::Settings {
        carry: false,
        ..Default::default()
    });
    let mut cases = vec![];
    for blend in [0.0, -0.5, 1.5, f64::NAN] {
        cases.push((
            with(shape, |r| r.j_bar = j_bar(blend)),
            "method.j_bar.blend",
        ));
        cases.push((
            with(shape, |r| r.cell_dilatation = cell_dilatation(blend)),
            "method.cell_dilatation.blend",
        ));
    }
    for time in [0.0, -1.0, f64::INFINITY] {
        cases.push((
            with(shape, |r| r.volume_relaxation = relax(time)),
            "method.volume_relaxation.time",
        ));
    }
    cases.extend([
        (
            with(shape, |r| {
                r.j_bar = j_bar(1.0);
                r.cell_dilatation = cell_dilatation(1.0);
            }),
            "method.j_bar",
        ),
        (
            with(shape, |r| {
                r.j_bar = Some(j_bar::Settings {
                    carry: false,
                    average_increment: true,
                    ..Default::default()
                })
            }),
            "method.j_bar.average_increment",
        ),
        (
            with(shape, |r| {
                r.j_bar = uncarried_j_bar.clone();
                r.volume_relaxation = relax(0.1);
            }),
            "method.volume_relaxation",
        ),
        (
            with(shape, |r| {
                r.cell_dilatation = uncarried_cell.clone();
                r.volume_relaxation = relax(0.1);
            }),
            "method.volume_relaxation",
        ),
    ]);
    for (method, key) in cases {
        let err = common::refusal(scene.clone(), method.clone())
            .unwrap_or_else(|| panic!("{key}: accepted {:?}", method.remedies));
        assert_eq!(err.key, key, "{err:?}");
    }
    // Each of them alone (and carried averages with the relaxation) runs.
    for method in [
        with(shape, |r| r.j_bar = uncarried_j_bar.clone()),
        with(shape, |r| r.cell_dilatation = uncarried_cell.clone()),
        with(shape, |r| {
            r.j_bar = j_bar(0.5);
            r.volume_relaxation = relax(0.1);
        }),
        with(shape, |r| {
            r.cell_dilatation = cell_dilatation(0.5);
            r.volume_relaxation = relax(0.1);
        }),
    ] {
        assert!(common::refusal(scene.clone(), method).is_none());
    }
}
