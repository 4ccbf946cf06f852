//! Surge front: the far edge of the furthest filled cell connected to the
//! column's base through filled cells (4-neighbours), so neither a stray
//! particle nor a droplet that lands ahead on the floor can move it. The base
//! is the bottom row under the initial column (the widest body, standing in
//! the lower-left corner).

use crate::checkerboard::CellField;
use crate::geometry::Geometry;

#[derive(Clone, Debug)]
pub struct Front {
    seen: Vec<bool>,
    stack: Vec<u32>,
}

impl Front {
    pub fn new(geom: &Geometry) -> Self {
        Front {
            seen: vec![false; geom.cell_count()],
            stack: Vec::with_capacity(geom.cell_count()),
        }
    }

    /// x of the front (metres from the box's left wall); None when no base cell is filled.
    pub fn position(&mut self, geom: &Geometry, field: &CellField) -> Option<f64> {
        let [nx, ny] = geom.cells;
        let filled = |c: usize| field.count[c] >= geom.filled_min();
        self.seen.fill(false);
        self.stack.clear();
        let base = ((geom.column_width / geom.cell).round() as usize).clamp(1, nx);
        for i in 0..base {
            if filled(i) {
                self.seen[i] = true;
                self.stack.push(i as u32);
            }
        }
        let mut furthest: Option<usize> = None;
        while let Some(c) = self.stack.pop() {
            let c = c as usize;
            let (i, j) = (c % nx, c / nx);
            furthest = Some(furthest.map_or(i, |f| f.max(i)));
            let mut visit = |n: usize| {
                if !self.seen[n] && filled(n) {
                    self.seen[n] = true;
                    self.stack.push(n as u32);
                }
            };
            if i > 0 {
                visit(c - 1);
            }
            if i + 1 < nx {
                visit(c + 1);
            }
            if j > 0 {
                visit(c - nx);
            }
            if j + 1 < ny {
                visit(c + nx);
            }
        }
        furthest.map(|i| (i + 1) as f64 * geom.cell)
    }
}

/// Dimensionless front Z = x / a and time T = t sqrt(2 g / a) (Martin & Moyce).
pub fn dimensionless(geom: &Geometry, x_front: f64, t: f64) -> (f64, f64) {
    let a = geom.column_width.max(1e-300);
    (x_front / a, t * (2.0 * geom.gravity / a).sqrt())
}
