//! Deterministic parallel reductions: particles are cut into fixed-size chunks
//! (independent of the thread count) and chunk results are combined in chunk
//! order, so any thread count gives the same bits.

use rayon::prelude::*;
use std::sync::atomic::{AtomicBool, Ordering};

/// Particles per reduction chunk.
pub const CHUNK: usize = 1024;

/// Below this many items a loop runs on one thread: handing work to a second
/// worker costs tens of microseconds on a small VM, more than ~16 000
/// particles' worth of a stage. Splitting never changes results (see above).
pub const MIN_PARALLEL: usize = 16 * CHUNK;

/// Items per parallel work item for a loop over `n` items: all of them on one
/// thread or below `MIN_PARALLEL`, else one chunk. Loops take it as both their
/// fewest and their most: with rayon's adaptive split alone a loop ended on
/// one piece of up to a quarter of the loop while the other thread waited,
/// fell asleep and took up to ~100 us to wake (see `keep_warm`).
pub fn piece_len(n: usize) -> usize {
    if !parallel(n) {
        n.max(1)
    } else {
        CHUNK
    }
}

/// Whether a loop over `n` items is worth splitting: more than one thread and
/// at least `MIN_PARALLEL` items.
pub fn parallel(n: usize) -> bool {
    n >= MIN_PARALLEL && rayon::current_num_threads() > 1
}

/// Splits an indexed parallel loop into pieces of exactly `len` items (the
/// last one shorter); `len` comes from `piece_len` or `piece_chunks`.
pub trait Pieces: IndexedParallelIterator + Sized {
    fn pieces(self, len: usize) -> rayon::iter::MaxLen<rayon::iter::MinLen<Self>> {
        self.with_min_len(len).with_max_len(len)
    }
}

impl<I: IndexedParallelIterator> Pieces for I {}

/// `piece_len` for a loop over the `CHUNK`-sized chunks of `n` particles.
pub fn piece_chunks(n: usize) -> usize {
    piece_len(n).div_ceil(CHUNK)
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
        .pieces(piece_chunks(n))
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

/// Largest value of `item` over `0..n` (max is exact, so any order is deterministic).
pub fn max<F>(n: usize, item: F) -> f64
where
    F: Fn(usize) -> f64 + Sync + Send,
{
    (0..n)
        .into_par_iter()
        .pieces(piece_len(n))
        .map(item)
        .reduce(|| f64::NEG_INFINITY, f64::max)
}

/// Runs `serial` on this thread while an idle worker of the pool spins, so
/// that the next parallel loop finds it awake: on this VM a worker idle for
/// more than a few microseconds falls asleep and joins the next loop 60-120
/// us late (`examples/wake_probe.rs`), a third of a large scene's stage.
/// Only for work with no parallel loop inside (a spinning worker takes no
/// part in one). Changes no result; on one thread or outside a pool it is
/// just `serial()`.
pub fn keep_warm<R: Send>(serial: impl FnOnce() -> R + Send) -> R {
    // Outside any pool a join would hand the work to the global pool and wait.
    if rayon::current_thread_index().is_none() || rayon::current_num_threads() < 2 {
        return serial();
    }
    let done = AtomicBool::new(false);
    // Set on drop, so that a panic in `serial` releases the spinning worker
    // (otherwise the join never returns and the panic never surfaces).
    struct Done<'a>(&'a AtomicBool);
    impl Drop for Done<'_> {
        fn drop(&mut self) {
            self.0.store(true, Ordering::Release);
        }
    }
    let (out, ()) = rayon::join(
        || {
            let _done = Done(&done);
            serial()
        },
        || {
            while !done.load(Ordering::Acquire) {
                std::hint::spin_loop();
            }
        },
    );
    out
}
