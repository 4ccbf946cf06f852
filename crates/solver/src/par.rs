//! Deterministic parallel reductions: particles are cut into fixed-size chunks
//! (independent of the thread count) and chunk results are combined in chunk
//! order, so any thread count gives the same bits.

use rayon::prelude::*;

/// Particles per reduction chunk.
pub const CHUNK: usize = 1024;

/// Below this many items a loop runs on one thread: handing work to a second
/// worker costs tens of microseconds on a small VM, more than ~16 000
/// particles' worth of a stage. Splitting never changes results (see above).
pub const MIN_PARALLEL: usize = 16 * CHUNK;

/// Fewest items per parallel work item for a loop over `n` items: all of them
/// below `MIN_PARALLEL`, else 2 chunks (small pieces balance best).
pub fn min_len(n: usize) -> usize {
    if n < MIN_PARALLEL {
        n.max(1)
    } else {
        2 * CHUNK
    }
}

/// `min_len` for a loop over the `CHUNK`-sized chunks of `n` particles.
pub fn min_chunks(n: usize) -> usize {
    min_len(n).div_ceil(CHUNK)
}

pub fn chunk_count(n: usize) -> usize {
    n.div_ceil(CHUNK).max(1)
}

/// Folds `item` over `0..n` chunk by chunk (each chunk from `init`) and
/// combines the chunk results in chunk order; `partials` holds one slot per
/// chunk (preallocated by the caller, so nothing is allocated here).
pub fn fold<T, F, C>(n: usize, partials: &mut [T], init: T, item: F, combine: C) -> T
where
    T: Copy + Send + Sync,
    F: Fn(&mut T, usize) + Sync,
    C: Fn(&mut T, &T),
{
    let chunks = chunk_count(n);
    partials[..chunks]
        .par_iter_mut()
        .with_min_len(min_chunks(n))
        .enumerate()
        .for_each(|(c, out)| {
            let mut acc = init;
            for i in c * CHUNK..((c + 1) * CHUNK).min(n) {
                item(&mut acc, i);
            }
            *out = acc;
        });
    let mut total = init;
    for part in &partials[..chunks] {
        combine(&mut total, part);
    }
    total
}

/// Sums `K` per-item values over `0..n` in a fixed order (see `fold`).
pub fn sum<const K: usize, F>(n: usize, partials: &mut [[f64; K]], item: F) -> [f64; K]
where
    F: Fn(usize) -> [f64; K] + Sync,
{
    let add = |acc: &mut [f64; K], v: &[f64; K]| {
        for k in 0..K {
            acc[k] += v[k];
        }
    };
    fold(n, partials, [0.0; K], |acc, i| add(acc, &item(i)), add)
}

/// Largest value of `item` over `0..n` (max is exact, so any order is deterministic).
pub fn max<F>(n: usize, item: F) -> f64
where
    F: Fn(usize) -> f64 + Sync + Send,
{
    (0..n)
        .into_par_iter()
        .with_min_len(min_len(n))
        .map(item)
        .reduce(|| f64::NEG_INFINITY, f64::max)
}
