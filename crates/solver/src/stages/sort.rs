//! Sort stage: each particle's stencil (first node and offset), a stable counting sort of particles
//! by their stencil's first node ("bin"), the occupied tiles the P2G scatter
//! walks, and the active-node set.

use crate::grid::Grid;
use crate::par::Pieces;
use crate::particles::Particles;
use crate::shapes::{Shape, Stencil};
use crate::StepError;
use rayon::prelude::*;

/// Bins per tile side. A tile's scatter writes its bins' stencils, at most
/// `TILE + 3` nodes wide, so tiles two apart never share a node (colouring).
pub const TILE: usize = 8;

/// Particles grouped by stencil origin node, in ascending particle index per
/// bin, and the occupied tiles grouped by colour.
#[derive(Clone, Debug)]
pub struct Bins {
    /// `start[b]..start[b + 1]` indexes `order` for bin `b` (a node index).
    pub start: Vec<u32>,
    pub order: Vec<u32>,
    /// Tiles per axis over the padded node grid.
    pub tiles: [usize; 2],
    /// Occupied tile indices (`tx + ty * tiles[0]`) of each colour
    /// `(tx % 2) + 2 (ty % 2)`, ascending.
    pub by_colour: [Vec<u32>; 4],
}

const OUTSIDE: u32 = u32::MAX;

impl Bins {
    pub fn new(dims: [usize; 2], particles: usize) -> Self {
        let tiles = [dims[0].div_ceil(TILE), dims[1].div_ceil(TILE)];
        let n_tiles = tiles[0] * tiles[1];
        Bins {
            start: vec![0; dims[0] * dims[1] + 1],
            order: vec![0; particles],
            tiles,
            by_colour: std::array::from_fn(|_| Vec::with_capacity(n_tiles)),
        }
    }

    /// The particles of bins `first..last` (one contiguous run of `order`).
    #[inline]
    pub fn of_range(&self, first: usize, last: usize) -> &[u32] {
        &self.order[self.start[first] as usize..self.start[last] as usize]
    }
}

pub fn sort(
    particles: &Particles,
    grid: &mut Grid,
    shape: &Shape,
    stencils: &mut [Stencil],
    bins: &mut Bins,
) -> Result<(), StepError> {
    let width = shape.reach() as i64;
    let (inv_h, origin, dims) = (1.0 / grid.h, grid.origin, grid.dims);
    let pad = crate::grid::PAD as i64;
    stencils
        .par_iter_mut()
        .zip(particles.x.par_iter().zip(particles.f.par_iter()))
        .pieces(crate::par::piece_len(particles.len()))
        .for_each(|(st, (x, f))| {
            let r = (x - origin) * inv_h;
            let (bx, fx) = shape.locate(r.x);
            let (by, fy) = shape.locate(r.y);
            // Saturating: a non-finite position locates at i64::MAX (refused below, never a panic).
            let (i, j) = (bx.saturating_add(pad), by.saturating_add(pad));
            let inside = r.x.is_finite()
                && r.y.is_finite()
                && i >= 0
                && j >= 0
                && i.saturating_add(width) <= dims[0] as i64
                && j.saturating_add(width) <= dims[1] as i64;
            st.node = if inside {
                (i + j * dims[0] as i64) as u32
            } else {
                OUTSIDE
            };
            st.frac = [fx, fy];
            st.half = shape.half_widths(f);
            st.domain = shape.domain(f);
        });
    let stencils = &*stencils;
    crate::par::keep_warm(|| {
        if let Some(p) = stencils.iter().position(|st| st.node == OUTSIDE) {
            return Err(StepError::OutsideGrid {
                id: particles.id[p],
                x: [particles.x[p].x, particles.x[p].y],
            });
        }
        counting_sort(bins, stencils);
        mark_tiles(bins, dims);
        let start = &bins.start;
        grid.mark_active(|b| start[b + 1] > start[b], width as usize);
        Ok(())
    })
}

/// Stable counting sort of particle indices by key.
fn counting_sort(bins: &mut Bins, stencils: &[Stencil]) {
    bins.start.fill(0);
    for st in stencils {
        bins.start[st.node as usize + 1] += 1;
    }
    for b in 1..bins.start.len() {
        bins.start[b] += bins.start[b - 1];
    }
    for (p, st) in stencils.iter().enumerate() {
        let slot = &mut bins.start[st.node as usize];
        bins.order[*slot as usize] = p as u32;
        *slot += 1;
    }
    // Placing advanced each start to the next bin's start: shift back by one.
    let last = bins.start.len() - 1;
    bins.start.copy_within(0..last, 1);
    bins.start[0] = 0;
}

/// Lists the tiles holding a particle, by colour, in ascending tile order.
fn mark_tiles(bins: &mut Bins, dims: [usize; 2]) {
    for list in &mut bins.by_colour {
        list.clear();
    }
    let [tiles_x, tiles_y] = bins.tiles;
    for ty in 0..tiles_y {
        for tx in 0..tiles_x {
            let (x0, x1) = (tx * TILE, ((tx + 1) * TILE).min(dims[0]));
            let used = (ty * TILE..((ty + 1) * TILE).min(dims[1])).any(|j| {
                let row = j * dims[0];
                bins.start[row + x1] > bins.start[row + x0]
            });
            if used {
                bins.by_colour[(tx % 2) + 2 * (ty % 2)].push((tx + ty * tiles_x) as u32);
            }
        }
    }
}
