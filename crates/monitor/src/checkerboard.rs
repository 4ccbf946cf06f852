//! Checkerboard index of the cell-averaged pressure (docs/physics.md section 4):
//! CB = sum (L p)_c^2 / (64 sum (p_c - mean)^2) over interior cells (filled
//! cells whose 4 edge neighbours are filled), L the 5-point Laplacian.
//! 0 for any linear field, 1 for a pure zero-mean checkerboard.

use crate::geometry::Geometry;
use solver::Vec2;

/// Cell sums of a particle field.
#[derive(Clone, Debug)]
pub struct CellField {
    pub sum: Vec<f64>,
    pub count: Vec<u32>,
}

impl CellField {
    pub fn new(geom: &Geometry) -> Self {
        CellField {
            sum: vec![0.0; geom.cell_count()],
            count: vec![0; geom.cell_count()],
        }
    }

    pub fn accumulate(&mut self, geom: &Geometry, x: &[Vec2], values: &[f64]) {
        self.sum.fill(0.0);
        self.count.fill(0);
        for (xp, &v) in x.iter().zip(values) {
            let c = geom.cell_index(*xp);
            self.sum[c] += v;
            self.count[c] += 1;
        }
    }

    #[inline]
    pub fn mean(&self, c: usize) -> f64 {
        self.sum[c] / self.count[c].max(1) as f64
    }
}

/// CB over interior cells; None when there are no interior cells or the field is flat.
pub fn index(geom: &Geometry, field: &CellField) -> Option<f64> {
    let [nx, ny] = geom.cells;
    let filled = |i: usize, j: usize| field.count[i + j * nx] >= geom.filled_min();
    let interior = |i: usize, j: usize| {
        i > 0
            && j > 0
            && i + 1 < nx
            && j + 1 < ny
            && filled(i, j)
            && filled(i - 1, j)
            && filled(i + 1, j)
            && filled(i, j - 1)
            && filled(i, j + 1)
    };
    let (mut n, mut total) = (0usize, 0.0);
    for j in 0..ny {
        for i in 0..nx {
            if interior(i, j) {
                n += 1;
                total += field.mean(i + j * nx);
            }
        }
    }
    if n == 0 {
        return None;
    }
    let mean = total / n as f64;
    let (mut lap2, mut var) = (0.0, 0.0);
    for j in 0..ny {
        for i in 0..nx {
            if !interior(i, j) {
                continue;
            }
            let p = |a: usize, b: usize| field.mean(a + b * nx);
            let lap = p(i + 1, j) + p(i - 1, j) + p(i, j + 1) + p(i, j - 1) - 4.0 * p(i, j);
            lap2 += lap * lap;
            var += (p(i, j) - mean).powi(2);
        }
    }
    (var > 0.0).then(|| lap2 / (64.0 * var))
}

/// RMS over particles of (p_p - p_cell) / (rho0 g h): pressure spread inside cells.
pub fn intra_cell_spread(geom: &Geometry, field: &CellField, x: &[Vec2], values: &[f64]) -> f64 {
    let scale = geom.rho0 * geom.gravity.max(1e-300) * geom.cell;
    let n = x.len().max(1) as f64;
    let s: f64 = x
        .iter()
        .zip(values)
        .map(|(xp, &v)| ((v - field.mean(geom.cell_index(*xp))) / scale).powi(2))
        .sum();
    (s / n).sqrt()
}
