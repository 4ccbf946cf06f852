//! Bit-identical state for 1 and 2 threads, and after a checkpoint restart;
//! corrupted checkpoints are refused.

use solver::remedies::{bulk_damping, j_bar, shifting, volume_relaxation, RemedySettings};
use solver::*;

use crate::common;

fn run_in_pool(threads: usize, cfg: &SolverConfig, steps: usize) -> u64 {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    pool.install(|| {
        let mut s = Solver::new(cfg.clone()).unwrap();
        for _ in 0..steps {
            s.step().unwrap();
        }
        s.state_hash()
    })
}

fn configs() -> Vec<SolverConfig> {
    let mut out = vec![];
    for (shape, transfer, scheme) in [
        (ShapeKind::Linear, TransferKind::Flip, SchemeKind::Usf),
        (ShapeKind::Bspline2, TransferKind::Apic, SchemeKind::Musl),
        (ShapeKind::Bspline3, TransferKind::Pic, SchemeKind::Usl),
        (ShapeKind::Gimp, TransferKind::Flip, SchemeKind::Usl),
        (ShapeKind::Cpdi, TransferKind::Apic, SchemeKind::Musl),
    ] {
        let mut mat = Material::tait(1.5e4);
        mat.viscosity = 0.5;
        out.push(SolverConfig {
            scene: Scene::dam_break(mat),
            method: common::method(shape, transfer, scheme),
            perturb: vec![],
        });
    }
    // A softening solid: the history variable xi is part of the state.
    let mut mat = Material::tait(1.5e4);
    mat.viscosity = 0.5;
    mat.shear_modulus = 1e4;
    mat.softening_strain = 0.02;
    out.push(SolverConfig {
        scene: Scene::dam_break(mat),
        method: common::method(ShapeKind::Bspline2, TransferKind::Apic, SchemeKind::Usl),
        perturb: vec![],
    });
    // The serial volumetric passes: J-bar with the linear fit, volume
    // consistency and bulk damping; and particle shifting.
    let mut mat = Material::tait(1.5e6);
    mat.viscosity = 0.5;
    out.push(SolverConfig {
        scene: Scene::dam_break(mat),
        method: Method {
            remedies: RemedySettings {
                j_bar: Some(j_bar::Settings {
                    fit: JBarFit::Linear,
                    ..Default::default()
                }),
                bulk_damping: Some(bulk_damping::Settings { coefficient: 0.3 }),
                volume_relaxation: Some(volume_relaxation::Settings { time: 0.01 }),
                shifting: Some(shifting::Settings {
                    time: 0.01,
                    ..Default::default()
                }),
                ..Default::default()
            },
            ..common::method(ShapeKind::Bspline2, TransferKind::Apic, SchemeKind::Usl)
        },
        perturb: vec![],
    });
    // The pressure-implicit step (its solve is serial; its particle update
    // parallel; its warm start is in the checkpoint): finite K, viscous,
    // with the drift corrected by velocity and IC(0), and the
    // incompressible limit with it corrected by position, MIC(0) and the
    // bilinear advection (the particles' moves are parallel too).
    let mut mat = Material::new(1.5e6);
    mat.viscosity = 0.5;
    out.push(SolverConfig {
        scene: Scene::dam_break(mat),
        method: Method {
            formulation: Formulation::PressureImplicit,
            projection: ProjectionSettings {
                drift: 0.1,
                drift_correction: DriftCorrection::Velocity,
                preconditioner: Preconditioner::Ic0,
                free_surface: FreeSurface::Ghost,
                ..Default::default()
            },
            ..common::method(ShapeKind::Linear, TransferKind::Flip, SchemeKind::Usl)
        },
        perturb: vec![],
    });
    out.push(SolverConfig {
        scene: Scene::dam_break(Material {
            k: f64::INFINITY,
            ..Material::new(1.0)
        }),
        method: Method {
            formulation: Formulation::PressureImplicit,
            projection: ProjectionSettings {
                drift: 0.3,
                drift_correction: DriftCorrection::Position,
                advection: Advection::Bilinear,
                free_surface: FreeSurface::GhostOrthogonal,
                drift_depth: 2,
                ..Default::default()
            },
            ..common::method(ShapeKind::Bspline2, TransferKind::Apic, SchemeKind::Usl)
        },
        perturb: vec![],
    });
    // The staggered projection, with its packing correction; and with the
    // material's density, the flux path, the midpoint rule and kept holes
    // (a checkpoint then carries the last step's fluid cells).
    let kept = ProjectionSettings {
        scheme: ProjectionScheme::Mac,
        face_density: FaceDensity::Material,
        advection: Advection::Flux,
        advection_step: AdvectionStep::Midpoint,
        holes: Holes::Kept,
        ..Default::default()
    };
    let plain = ProjectionSettings {
        scheme: ProjectionScheme::Mac,
        ..Default::default()
    };
    for projection in [plain, kept] {
        out.push(SolverConfig {
            scene: Scene::dam_break(Material::new(1.5e6)),
            method: Method {
                formulation: Formulation::PressureImplicit,
                projection,
                ..common::method(ShapeKind::Bspline2, TransferKind::Apic, SchemeKind::Usl)
            },
            perturb: vec![],
        });
    }
    out
}

#[test]
fn one_and_two_threads_give_identical_bits() {
    for cfg in configs() {
        let one = run_in_pool(1, &cfg, 400);
        let two = run_in_pool(2, &cfg, 400);
        let again = run_in_pool(2, &cfg, 400);
        assert_eq!(one, two, "{:?}", cfg.method);
        assert_eq!(two, again, "{:?}", cfg.method);
    }
}

/// Scenes under `par::MIN_PARALLEL` particles run each loop on one thread;
/// this one (20 000 particles) takes the parallel paths: coloured P2G tiles,
/// split particle and node loops, chunked sums.
#[test]
fn large_scene_takes_parallel_paths_with_identical_bits() {
    let configs = configs();
    let last = configs.len() - 1;
    for (_, cfg) in configs
        .into_iter()
        .enumerate()
        .filter(|(i, _)| *i < 2 || *i + 2 >= last)
    {
        let mut cfg = cfg;
        cfg.scene.cell = 0.004;
        let n = Solver::new(cfg.clone()).unwrap().particle_count();
        assert!(n >= solver::par::MIN_PARALLEL, "{n} particles");
        let one = run_in_pool(1, &cfg, 150);
        let two = run_in_pool(2, &cfg, 150);
        let three = run_in_pool(3, &cfg, 150);
        assert_eq!(one, two, "{:?}", cfg.method);
        assert_eq!(one, three, "{:?}", cfg.method);
    }
}

#[test]
fn restart_from_checkpoint_is_bit_identical() {
    for cfg in configs() {
        let mut a = Solver::new(cfg.clone()).unwrap();
        for _ in 0..200 {
            a.step().unwrap();
        }
        let bytes = a.checkpoint();
        for _ in 0..200 {
            a.step().unwrap();
        }
        let mut b = Solver::new(cfg.clone()).unwrap();
        b.restore(&bytes).unwrap();
        assert_eq!(b.step_count(), 200);
        for _ in 0..200 {
            b.step().unwrap();
        }
        assert_eq!(a.state_hash(), b.state_hash(), "{:?}", cfg.method);
        assert_eq!(a.time().to_bits(), b.time().to_bits());
        assert_eq!(a.energy(), b.energy());
    }
}

#[test]
fn corrupted_checkpoints_are_refused() {
    let cfg = configs().remove(0);
    let mut a = Solver::new(cfg.clone()).unwrap();
    a.step().unwrap();
    let bytes = a.checkpoint();
    let mut b = Solver::new(cfg.clone()).unwrap();
    let mut flipped = bytes.clone();
    flipped[100] ^= 1;
    assert!(matches!(
        b.restore(&flipped),
        Err(CheckpointError::Checksum { .. })
    ));
    assert!(b.restore(&bytes[..bytes.len() - 9]).is_err());
    let mut magic = bytes.clone();
    magic[0] = b'X';
    assert_eq!(b.restore(&magic), Err(CheckpointError::BadMagic));
    let mut other = cfg.clone();
    other.scene.bodies[0].rect[2] = 0.1;
    let mut c = Solver::new(other).unwrap();
    assert!(matches!(
        c.restore(&bytes),
        Err(CheckpointError::ParticleCount { .. })
    ));
    b.restore(&bytes).unwrap();
    assert_eq!(b.state_hash(), a.state_hash());
}
