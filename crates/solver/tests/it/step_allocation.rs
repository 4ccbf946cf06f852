//! The step loop allocates nothing (counted by a global allocator), for every
//! shape, transfer and scheme, and under the pressure-implicit step, on one
//! thread and on two.
//!
//! Steps run inside `pool.install`, so every allocation of a step happens on a
//! worker of that pool; only those are counted. Other threads are not the
//! step's: the test harness, a worker of rayon's global pool (started by
//! `Solver::new`) that comes up late and registers its queues while counting,
//! or a worker of the previous pool freeing its queues on exit.

use solver::*;
use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

use crate::common;

struct Counting;

static COUNTING: AtomicBool = AtomicBool::new(false);
static ALLOCATIONS: AtomicUsize = AtomicUsize::new(0);

thread_local! {
    /// Set on the workers of the pool that runs the steps, while they run.
    static STEP_WORKER: Cell<bool> = const { Cell::new(false) };
}

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        if COUNTING.load(Ordering::Relaxed) && STEP_WORKER.with(Cell::get) {
            ALLOCATIONS.fetch_add(1, Ordering::Relaxed);
        }
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) }
    }
}

#[global_allocator]
static GLOBAL: Counting = Counting;

#[test]
fn step_does_not_allocate() {
    for threads in [1, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .start_handler(|_| STEP_WORKER.with(|w| w.set(true)))
            .exit_handler(|_| STEP_WORKER.with(|w| w.set(false)))
            .build()
            .unwrap();
        let mut configs = vec![];
        for shape in common::RUN_SHAPES {
            for transfer in common::TRANSFERS {
                for scheme in common::SCHEMES {
                    let mut mat = Material::tait(1.5e4);
                    mat.viscosity = 0.5;
                    configs.push(SolverConfig {
                        scene: Scene::dam_break(mat),
                        method: common::method(shape, transfer, scheme),
                        perturb: vec![Perturb::at_step(30, [0.0, 0.0, 0.05, 0.05], [0.1, 0.0])],
                    });
                }
                // The pressure-implicit step (its own order: one scheme),
                // compressible with the drift corrected by velocity (IC(0),
                // the shapes' advection, the ghost surface), and
                // incompressible with it corrected by position (MIC(0), the
                // bilinear advection, the orthogonal ghost surface, the
                // drift read two cells deep).
                // (CPDI's weights are not per-axis: it is explicit only.)
                let implicit_ks = if shape == ShapeKind::Cpdi { 0 } else { 2 };
                for (k, drift_correction, preconditioner, advection, free_surface, drift_depth) in [
                    (
                        1.5e6,
                        DriftCorrection::Velocity,
                        Preconditioner::Ic0,
                        Advection::Shape,
                        FreeSurface::Ghost,
                        0,
                    ),
                    (
                        f64::INFINITY,
                        DriftCorrection::Position,
                        Preconditioner::Mic0,
                        Advection::Bilinear,
                        FreeSurface::GhostOrthogonal,
                        2,
                    ),
                ]
                .into_iter()
                .take(implicit_ks)
                {
                    let mut mat = Material::tait(1.5e6);
                    mat.k = k;
                    mat.viscosity = 0.5;
                    configs.push(SolverConfig {
                        scene: Scene::dam_break(mat),
                        method: Method {
                            formulation: Formulation::PressureImplicit,
                            projection: ProjectionSettings {
                                drift_correction,
                                preconditioner,
                                advection,
                                free_surface,
                                drift_depth,
                                ..Default::default()
                            },
                            ..common::method(shape, transfer, SchemeKind::Usl)
                        },
                        perturb: vec![],
                    });
                }
                // The staggered projection, with its packing correction;
                // and with the flux path and kept holes.
                if shape == ShapeKind::Bspline2 && transfer != TransferKind::Xpic {
                    for (advection, advection_step, holes) in [
                        (Advection::Shape, AdvectionStep::Euler, Holes::Air),
                        (Advection::Flux, AdvectionStep::Midpoint, Holes::Kept),
                    ] {
                        configs.push(SolverConfig {
                            scene: Scene::dam_break(Material::tait(1.5e6)),
                            method: Method {
                                formulation: Formulation::PressureImplicit,
                                projection: ProjectionSettings {
                                    scheme: ProjectionScheme::Mac,
                                    advection,
                                    advection_step,
                                    holes,
                                    ..Default::default()
                                },
                                ..common::method(shape, transfer, SchemeKind::Usl)
                            },
                            perturb: vec![],
                        });
                    }
                }
            }
        }
        for cfg in configs {
            let label = format!("{:?}", cfg.method);
            let mut s = Solver::new(cfg).unwrap();
            pool.install(|| {
                // Warm-up: first steps, and every worker started (one
                // spawned late would set up its queues while counting).
                for _ in 0..5 {
                    s.step().unwrap();
                }
                pool.broadcast(|_| ());
                ALLOCATIONS.store(0, Ordering::SeqCst);
                COUNTING.store(true, Ordering::SeqCst);
                for _ in 0..50 {
                    s.step().unwrap();
                }
                COUNTING.store(false, Ordering::SeqCst);
            });
            let n = ALLOCATIONS.load(Ordering::SeqCst);
            assert_eq!(n, 0, "{threads} threads {label}: {n} allocations");
        }
    }
}
