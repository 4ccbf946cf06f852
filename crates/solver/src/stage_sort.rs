//! Sort stage: shape weights per particle, a stable counting sort of particles
//! by their stencil's first node ("bin"), and the active-node set.

use crate::grid::Grid;
use crate::particles::Particles;
use crate::shape::{Shape, Weights1d};
use crate::StepError;
use rayon::prelude::*;

/// Particles grouped by stencil origin node, in ascending particle index per bin.
#[derive(Clone, Debug)]
pub struct Bins {
    /// `start[b]..start[b + 1]` indexes `order` for bin `b` (a node index).
    pub start: Vec<u32>,
    pub order: Vec<u32>,
    key: Vec<u32>,
}

const OUTSIDE: u32 = u32::MAX;

impl Bins {
    pub fn new(nodes: usize, particles: usize) -> Self {
        Bins {
            start: vec![0; nodes + 1],
            order: vec![0; particles],
            key: vec![0; particles],
        }
    }

    #[inline]
    pub fn of(&self, bin: usize) -> &[u32] {
        &self.order[self.start[bin] as usize..self.start[bin + 1] as usize]
    }
}

pub fn sort(
    particles: &Particles,
    grid: &mut Grid,
    shape: &Shape,
    weights: &mut [[Weights1d; 2]],
    bins: &mut Bins,
) -> Result<(), StepError> {
    let width = shape.width() as i64;
    let (h, origin, dims) = (grid.h, grid.origin, grid.dims);
    let pad = crate::grid::PAD as i64;
    weights
        .par_iter_mut()
        .zip(bins.key.par_iter_mut())
        .zip(particles.x.par_iter())
        .for_each(|((w, key), x)| {
            let r = (x - origin) / h;
            w[0] = shape.weights(r.x);
            w[1] = shape.weights(r.y);
            let (i, j) = (w[0].base + pad, w[1].base + pad);
            let inside = r.x.is_finite()
                && r.y.is_finite()
                && i >= 0
                && j >= 0
                && i + width <= dims[0] as i64
                && j + width <= dims[1] as i64;
            *key = if inside {
                (i + j * dims[0] as i64) as u32
            } else {
                OUTSIDE
            };
        });
    if let Some(p) = bins.key.iter().position(|&k| k == OUTSIDE) {
        return Err(StepError::OutsideGrid {
            id: particles.id[p],
            x: [particles.x[p].x, particles.x[p].y],
        });
    }
    // Stable counting sort: start[b + 1] counts, prefix sum, then place.
    bins.start.fill(0);
    for &k in &bins.key {
        bins.start[k as usize + 1] += 1;
    }
    for b in 1..bins.start.len() {
        bins.start[b] += bins.start[b - 1];
    }
    for (p, &k) in bins.key.iter().enumerate() {
        let slot = &mut bins.start[k as usize];
        bins.order[*slot as usize] = p as u32;
        *slot += 1;
    }
    // Placing advanced each start to the next bin's start: shift back by one.
    for b in (1..bins.start.len()).rev() {
        bins.start[b] = bins.start[b - 1];
    }
    bins.start[0] = 0;
    // `order` is sorted by bin, so occupied bins are the runs of equal keys.
    let key = &bins.key;
    let mut last = OUTSIDE;
    let occupied = bins.order.iter().filter_map(|&p| {
        let k = key[p as usize];
        (k != last).then(|| {
            last = k;
            k as usize
        })
    });
    grid.mark_active(occupied, width as usize);
    Ok(())
}
