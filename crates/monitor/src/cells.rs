//! Particles binned by cell (stable counting sort), reused every step.

use crate::geometry::Geometry;
use solver::Vec2;

#[derive(Clone, Debug)]
pub struct CellBins {
    start: Vec<u32>,
    order: Vec<u32>,
    key: Vec<u32>,
}

impl CellBins {
    pub fn new(geom: &Geometry, particles: usize) -> Self {
        CellBins {
            start: vec![0; geom.cell_count() + 1],
            order: vec![0; particles],
            key: vec![0; particles],
        }
    }

    pub fn rebuild(&mut self, geom: &Geometry, x: &[Vec2]) {
        self.start.fill(0);
        // Fewer particles than at t = 0 once some were deleted.
        let keys = &mut self.key[..x.len()];
        for (k, xp) in keys.iter_mut().zip(x) {
            *k = geom.cell_index(*xp) as u32;
            self.start[*k as usize + 1] += 1;
        }
        for c in 1..self.start.len() {
            self.start[c] += self.start[c - 1];
        }
        for (p, &k) in keys.iter().enumerate() {
            let slot = &mut self.start[k as usize];
            self.order[*slot as usize] = p as u32;
            *slot += 1;
        }
        for c in (1..self.start.len()).rev() {
            self.start[c] = self.start[c - 1];
        }
        self.start[0] = 0;
    }

    #[inline]
    pub fn particles(&self, cell: usize) -> &[u32] {
        &self.order[self.start[cell] as usize..self.start[cell + 1] as usize]
    }

    #[inline]
    pub fn cell_of_particle(&self, p: usize) -> usize {
        self.key[p] as usize
    }
}
