//! Local acceleration outliers: a_p = |v_p(n) - v_p(n-1)| / dt and the robust
//! score z_p = (a_p - median) / (1.4826 MAD + 0.1 g) over the particles in a
//! window of cells around p. Window statistics are computed per tile of
//! `tile` x `tile` cells (the window spans the tile plus `half` cells on each
//! side), only for tiles holding a candidate, and cached for the step.

use crate::cells::CellBins;
use crate::geometry::Geometry;
use crate::stats::median_and_mad;

/// Most values a window's median and MAD are estimated from.
pub const MAX_SAMPLES: usize = 128;

#[derive(Clone, Debug)]
pub struct WindowStats {
    stamp: Vec<u64>,
    median: Vec<f64>,
    scale: Vec<f64>,
    values: Vec<f64>,
}

impl WindowStats {
    pub fn new(geom: &Geometry, particles: usize) -> Self {
        WindowStats {
            stamp: vec![0; geom.cell_count()],
            median: vec![0.0; geom.cell_count()],
            scale: vec![1.0; geom.cell_count()],
            values: Vec::with_capacity(particles),
        }
    }

    /// z of particle `p` (in cell `cell`) at step `step` (>= 1).
    pub fn z(
        &mut self,
        geom: &Geometry,
        bins: &CellBins,
        accel: &[f64],
        (tile, half): (usize, usize),
        p: usize,
        step: u64,
    ) -> f64 {
        let cell = bins.cell_of_particle(p);
        let nx = geom.cells[0];
        let tile = tile.max(1);
        // Tiles are indexed by their first cell.
        let (ti, tj) = ((cell % nx) / tile * tile, (cell / nx) / tile * tile);
        let key = ti + tj * nx;
        if self.stamp[key] != step {
            let (median, mad) = self.window(geom, bins, accel, (ti, tj, tile), half);
            self.stamp[key] = step;
            self.median[key] = median;
            self.scale[key] = 1.4826 * mad + 0.1 * geom.gravity.max(1e-3);
        }
        (accel[p] - self.median[key]) / self.scale[key]
    }

    fn window(
        &mut self,
        geom: &Geometry,
        bins: &CellBins,
        accel: &[f64],
        (ti, tj, tile): (usize, usize, usize),
        half: usize,
    ) -> (f64, f64) {
        let [nx, ny] = geom.cells;
        let (j0, j1) = (tj.saturating_sub(half), (tj + tile - 1 + half).min(ny - 1));
        let (i0, i1) = (ti.saturating_sub(half), (ti + tile - 1 + half).min(nx - 1));
        let total: usize = (j0..=j1)
            .flat_map(|j| (i0..=i1).map(move |i| i + j * nx))
            .map(|c| bins.particles(c).len())
            .sum();
        // A fixed stride keeps at most MAX_SAMPLES values: same estimate, bounded cost.
        let stride = total.div_ceil(MAX_SAMPLES).max(1);
        self.values.clear();
        // Every stride-th particle in window order (a countdown, not k % stride).
        let mut skip = 0;
        for j in j0..=j1 {
            for i in i0..=i1 {
                for &q in bins.particles(i + j * nx) {
                    if skip == 0 {
                        self.values.push(accel[q as usize]);
                        skip = stride - 1;
                    } else {
                        skip -= 1;
                    }
                }
            }
        }
        median_and_mad(&mut self.values)
    }
}
