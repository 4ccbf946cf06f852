//! Per-stage criterion benchmarks on the default dam break (3 200 particles)
//! after 100 steps, for linear/FLIP and quadratic/APIC. Before each timed run
//! of a stage the particle state is restored from a checkpoint (untimed, into
//! the same buffers), so stages that move or deform particles do not drift.
//! One rayon thread. Run with `cargo bench -p kick-solver`.

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use solver::{ShapeKind, Solver, SolverConfig, Stage, TransferKind};
use std::time::{Duration, Instant};

fn dam_break(shape: ShapeKind, transfer: TransferKind) -> Solver {
    let cfg = SolverConfig::benchmark_dam_break(shape, transfer, 0.01);
    let mut solver = Solver::new(cfg).expect("dam break config");
    for _ in 0..100 {
        solver.step().expect("dam break step");
    }
    solver
}

fn stages(c: &mut Criterion) {
    // This thread becomes the one worker of a one-thread global pool, as
    // `kick bench --threads 1` runs inside its pool: parallel loops called
    // from outside any pool would each wait on a hand-off to a worker.
    let _ = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .use_current_thread()
        .build_global();
    stages_in_pool(c);
}

fn stages_in_pool(c: &mut Criterion) {
    for (shape, transfer, name) in [
        (ShapeKind::Linear, TransferKind::Flip, "linear_flip"),
        (ShapeKind::Bspline2, TransferKind::Apic, "bspline2_apic"),
    ] {
        let mut solver = dam_break(shape, transfer);
        let snapshot = solver.checkpoint();
        let mut group = c.benchmark_group(name);
        group.throughput(Throughput::Elements(solver.particle_count() as u64));
        let mut timed = |name: &str, run: &dyn Fn(&mut Solver)| {
            group.bench_function(name, |b| {
                b.iter_custom(|iters| {
                    let mut total = Duration::ZERO;
                    for _ in 0..iters {
                        solver.restore(&snapshot).expect("snapshot");
                        let t = Instant::now();
                        run(&mut solver);
                        total += t.elapsed();
                    }
                    total
                })
            });
        };
        for stage in Stage::ALL {
            timed(stage.name(), &|s| s.run_stage(stage).expect("stage"));
        }
        timed("step", &|s| s.step().expect("step"));
        group.finish();
    }
}

criterion_group!(benches, stages);
criterion_main!(benches);
