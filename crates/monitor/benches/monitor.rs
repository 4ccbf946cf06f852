//! Criterion benchmarks of the monitor on the default dam break (3 200
//! particles, linear/FLIP) after 200 steps: the per-step observation and the
//! field metrics (checkerboard, hydrostatic departure, front). Run with
//! `cargo bench -p kick-monitor`.

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use monitor::{Monitor, MonitorConfig};
use solver::{ShapeKind, Solver, SolverConfig, TransferKind};

fn monitor(c: &mut Criterion) {
    // This thread becomes the one worker of a one-thread global pool, as
    // `kick bench --threads 1` runs inside its pool: parallel loops called
    // from outside any pool would each wait on a hand-off to a worker.
    let _ = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .use_current_thread()
        .build_global();
    monitor_in_pool(c);
}

fn monitor_in_pool(c: &mut Criterion) {
    let cfg = SolverConfig::benchmark_dam_break(ShapeKind::Linear, TransferKind::Flip, 0.01);
    let mut solver = Solver::new(cfg).expect("dam break config");
    let mut monitor = Monitor::new(MonitorConfig::default(), &solver.view());
    for _ in 0..200 {
        solver.step().expect("dam break step");
        monitor.observe(&solver.view());
    }
    let view = solver.view();
    let mut group = c.benchmark_group("monitor");
    group.throughput(Throughput::Elements(solver.particle_count() as u64));
    group.bench_function("observe", |b| b.iter(|| monitor.observe(&view).max_accel_g));
    group.bench_function("field_metrics", |b| b.iter(|| monitor.field_metrics(&view)));
    group.finish();
}

criterion_group!(benches, monitor);
criterion_main!(benches);
