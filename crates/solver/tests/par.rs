//! The parallel helpers: fixed pieces, ordered sums and `keep_warm`.

use solver::par;
use std::sync::atomic::{AtomicUsize, Ordering};

fn pool(threads: usize) -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap()
}

/// An ordered sum whose terms differ by many orders of magnitude: any other
/// summation order would change the last bits.
fn ordered_sum(n: usize) -> f64 {
    let mut partials = vec![[0.0f64; 1]; par::chunk_count(n)];
    let [s] = par::sum(n, &mut partials, |i| {
        [(i as f64 * 0.37).sin() * 10f64.powi((i % 13) as i32)]
    });
    s
}

#[test]
fn sums_have_the_same_bits_for_any_thread_count_and_size() {
    for n in [
        1,
        1000,
        par::MIN_PARALLEL - 1,
        par::MIN_PARALLEL,
        3 * par::MIN_PARALLEL + 7,
    ] {
        let one = pool(1).install(|| ordered_sum(n));
        let two = pool(2).install(|| ordered_sum(n));
        let three = pool(3).install(|| ordered_sum(n));
        let outside = ordered_sum(n);
        assert_eq!(one.to_bits(), two.to_bits(), "n = {n}");
        assert_eq!(one.to_bits(), three.to_bits(), "n = {n}");
        assert_eq!(one.to_bits(), outside.to_bits(), "n = {n}");
    }
}

#[test]
fn piece_length_splits_only_large_loops_on_several_threads() {
    let big = 4 * par::MIN_PARALLEL;
    assert_eq!(pool(1).install(|| par::piece_len(big)), big);
    assert_eq!(pool(2).install(|| par::piece_len(big)), par::CHUNK);
    assert_eq!(pool(2).install(|| par::piece_len(100)), 100);
    assert!(pool(2).install(|| par::parallel(big)));
    assert!(!pool(1).install(|| par::parallel(big)));
}

#[test]
fn keep_warm_returns_the_serial_result_and_releases_the_worker() {
    for threads in [1, 2, 3] {
        let calls = AtomicUsize::new(0);
        let out = pool(threads).install(|| {
            let mut total = 0u64;
            for k in 0..200u64 {
                total += par::keep_warm(|| {
                    calls.fetch_add(1, Ordering::Relaxed);
                    k * k
                });
            }
            total
        });
        assert_eq!(out, (0..200u64).map(|k| k * k).sum::<u64>());
        assert_eq!(calls.load(Ordering::Relaxed), 200, "{threads} threads");
    }
    // Outside any pool: run in place.
    assert_eq!(par::keep_warm(|| 7), 7);
}
