//! How long an idle rayon worker takes to join a parallel loop after the
//! caller ran serial work for `gap` microseconds: a loop of 26 pieces of 15 us
//! each, after each gap, timed on one and two threads. On the 2-core VM of
//! the README a gap of 10 us or more made the two-thread loop 30-60 us
//! slower than after no gap: the other worker had fallen asleep and joined
//! the loop some 60-120 us late. `par::keep_warm` avoids that.
//! Run with `cargo run --release -p kick-solver --example wake_probe`.

use rayon::prelude::*;
use std::time::Instant;

fn spin(us: f64) {
    let t = Instant::now();
    while t.elapsed().as_secs_f64() * 1e6 < us {}
}

fn main() {
    const PIECES: usize = 26;
    const PIECE_US: f64 = 15.0;
    const REPEATS: usize = 300;
    for threads in [1, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("rayon pool");
        pool.install(|| {
            for gap in [0.0, 10.0, 20.0, 50.0, 300.0] {
                let mut busy = 0.0;
                for _ in 0..REPEATS {
                    spin(gap);
                    let t = Instant::now();
                    (0..PIECES)
                        .into_par_iter()
                        .with_max_len(1)
                        .for_each(|_| spin(PIECE_US));
                    busy += t.elapsed().as_secs_f64();
                }
                let ideal = (PIECES as f64 * PIECE_US / threads as f64).ceil();
                println!(
                    "threads {threads}, gap {gap:>5} us: loop {:.1} us (ideal {ideal})",
                    busy / REPEATS as f64 * 1e6
                );
            }
        });
    }
}
