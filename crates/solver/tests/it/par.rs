//! The parallel helpers: fixed pieces, ordered folds and `keep_warm`.

use solver::par;
use std::sync::atomic::{AtomicUsize, Ordering};

fn pool(threads: usize) -> rayon::ThreadPool {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap()
}

/// A chunked fold as `measure` runs it (a sum, a count and a max per chunk,
/// combined in chunk order). The summed terms differ by many orders of
/// magnitude: any other summation order would change the last bits.
fn ordered_fold(n: usize) -> (f64, usize, f64) {
    let mut partials = vec![(0.0, 0, 0.0); par::chunk_count(n)];
    par::fold(
        n,
        &mut partials,
        (0.0, 0, f64::NEG_INFINITY),
        |acc, i| {
            let t = (i as f64 * 0.37).sin() * 10f64.powi((i % 13) as i32);
            acc.0 += t;
            acc.1 += (t > 0.0) as usize;
            acc.2 = acc.2.max(t);
        },
        |total, part| {
            total.0 += part.0;
            total.1 += part.1;
            total.2 = total.2.max(part.2);
        },
    )
}

/// The same fold term by term on one thread, chunk sums added in chunk order.
fn reference_fold(n: usize) -> (f64, usize, f64) {
    let mut total = (0.0, 0, f64::NEG_INFINITY);
    for c in 0..par::chunk_count(n) {
        let mut sum = 0.0;
        for i in c * par::CHUNK..((c + 1) * par::CHUNK).min(n) {
            let t = (i as f64 * 0.37).sin() * 10f64.powi((i % 13) as i32);
            sum += t;
            total.1 += (t > 0.0) as usize;
            total.2 = total.2.max(t);
        }
        total.0 += sum;
    }
    total
}

#[test]
fn folds_have_the_same_bits_for_any_thread_count_and_size() {
    for n in [
        1,
        1000,
        par::MIN_PARALLEL - 1,
        par::MIN_PARALLEL,
        3 * par::MIN_PARALLEL + 7,
    ] {
        let bits = |(s, c, m): (f64, usize, f64)| (s.to_bits(), c, m.to_bits());
        let reference = bits(reference_fold(n));
        let one = bits(pool(1).install(|| ordered_fold(n)));
        let two = bits(pool(2).install(|| ordered_fold(n)));
        let three = bits(pool(3).install(|| ordered_fold(n)));
        let outside = bits(ordered_fold(n));
        assert_eq!(one, reference, "n = {n}");
        assert_eq!(one, two, "n = {n}");
        assert_eq!(one, three, "n = {n}");
        assert_eq!(one, outside, "n = {n}");
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
