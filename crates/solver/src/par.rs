//! Deterministic parallel reductions: particles are cut into fixed-size chunks
//! (independent of the thread count) and chunk results are combined in chunk
//! order, so any thread count gives the same bits.

use rayon::prelude::*;

/// Particles per reduction chunk.
pub const CHUNK: usize = 1024;

/// Fewest particles one parallel work item takes. Waking a second worker
/// costs more than a few thousand particles' work on a small scene, so those
/// run on one thread; the split never changes results (see above).
pub const MIN_PARTICLES: usize = 2 * CHUNK;

/// The same in chunks of `CHUNK`.
pub const MIN_CHUNKS: usize = MIN_PARTICLES / CHUNK;

pub fn chunk_count(n: usize) -> usize {
    n.div_ceil(CHUNK).max(1)
}

/// Sums `K` per-item values over `0..n` in a fixed order; `partials` holds one
/// slot per chunk (preallocated by the caller, so nothing is allocated here).
pub fn sum<const K: usize, F>(n: usize, partials: &mut [[f64; K]], item: F) -> [f64; K]
where
    F: Fn(usize) -> [f64; K] + Sync,
{
    let chunks = chunk_count(n);
    partials[..chunks]
        .par_iter_mut()
        .with_min_len(MIN_CHUNKS)
        .enumerate()
        .for_each(|(c, out)| {
            let mut acc = [0.0; K];
            for i in c * CHUNK..((c + 1) * CHUNK).min(n) {
                let v = item(i);
                for k in 0..K {
                    acc[k] += v[k];
                }
            }
            *out = acc;
        });
    let mut total = [0.0; K];
    for part in &partials[..chunks] {
        for k in 0..K {
            total[k] += part[k];
        }
    }
    total
}

/// Largest value of `item` over `0..n` (max is exact, so any order is deterministic).
pub fn max<F>(n: usize, item: F) -> f64
where
    F: Fn(usize) -> f64 + Sync + Send,
{
    (0..n)
        .into_par_iter()
        .with_min_len(MIN_PARTICLES)
        .map(item)
        .reduce(|| f64::NEG_INFINITY, f64::max)
}
