//! Serial particle-grid sums on raw nodes, in particle order (deterministic
//! for any thread count), shared by XPIC, the null-space filter and the
//! multiphase drag.

// The loops walk the weights and the stencil rows in step.
#![allow(clippy::needless_range_loop)]

use crate::grid::{Grid, PAD};
use crate::particles::Vec2;
use crate::shapes::{Shape, Stencil};

/// out_p = sum_i N_ip field_i for every particle.
pub fn gather<const W: usize>(
    field: &[Vec2],
    stencils: &[Stencil],
    shape: &Shape,
    nx: usize,
    out: &mut [Vec2],
) {
    for (p, st) in stencils.iter().enumerate() {
        out[p] = interpolate::<W>(field, st, shape, nx);
    }
}

/// sum_i N_ip field_i for one particle's stencil.
#[inline]
pub fn interpolate<const W: usize>(field: &[Vec2], st: &Stencil, shape: &Shape, nx: usize) -> Vec2 {
    let (wx, _) = shape.stencil_weights::<W>(st.frac[0], st.half[0]);
    let (wy, _) = shape.stencil_weights::<W>(st.frac[1], st.half[1]);
    let mut sum = Vec2::zeros();
    for c in 0..W {
        let row = st.node as usize + c * nx;
        for a in 0..W {
            sum += (wx[a] * wy[c]) * field[row + a];
        }
    }
    sum
}

/// The bilinear element's interpolation of a nodal field at x over the
/// corners of x's cell (clamped into the box): its integral of the
/// divergence over a cell is the cell-centre divergence times h^2.
#[inline]
pub fn bilinear(field: &[Vec2], grid: &Grid, x: Vec2) -> Vec2 {
    let r = (x - grid.origin) / grid.h;
    let corner = |v: f64, axis: usize| {
        let last = grid.cells[axis] - 1;
        let i = if v.is_finite() {
            (v.floor().max(0.0) as usize).min(last)
        } else {
            0
        };
        (i, (v - i as f64).clamp(0.0, 1.0))
    };
    let ((i, fx), (j, fy)) = (corner(r.x, 0), corner(r.y, 1));
    let n = grid.index(i + PAD, j + PAD);
    let up = n + grid.dims[0];
    (1.0 - fy) * ((1.0 - fx) * field[n] + fx * field[n + 1])
        + fy * ((1.0 - fx) * field[up] + fx * field[up + 1])
}

/// out_i = sum_p m_p N_ip q_p on the raw active nodes (S^T W q; no folds).
pub fn scatter_mass_weighted<const W: usize>(
    q: &[Vec2],
    mass: &[f64],
    stencils: &[Stencil],
    shape: &Shape,
    grid: &Grid,
    out: &mut [Vec2],
) {
    let nx = grid.dims[0];
    for &n in &grid.active {
        out[n as usize] = Vec2::zeros();
    }
    for (p, st) in stencils.iter().enumerate() {
        let (wx, _) = shape.stencil_weights::<W>(st.frac[0], st.half[0]);
        let (wy, _) = shape.stencil_weights::<W>(st.frac[1], st.half[1]);
        let mq = mass[p] * q[p];
        for c in 0..W {
            let row = st.node as usize + c * nx;
            for a in 0..W {
                out[row + a] += (wx[a] * wy[c]) * mq;
            }
        }
    }
}

/// out_i = sum_p N_ip q_p on the raw active nodes (no folds), e.g. the nodal
/// volume sum_p N_ip V_p.
pub fn scatter_scalar<const W: usize>(
    q: &[f64],
    stencils: &[Stencil],
    shape: &Shape,
    grid: &Grid,
    out: &mut [f64],
) {
    let nx = grid.dims[0];
    for &n in &grid.active {
        out[n as usize] = 0.0;
    }
    for (p, st) in stencils.iter().enumerate() {
        let (wx, _) = shape.stencil_weights::<W>(st.frac[0], st.half[0]);
        let (wy, _) = shape.stencil_weights::<W>(st.frac[1], st.half[1]);
        for c in 0..W {
            let row = st.node as usize + c * nx;
            for a in 0..W {
                out[row + a] += (wx[a] * wy[c]) * q[p];
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Exact for a linear field, and a cell's boundary flux of it (the
    /// integral of its divergence) is h^2 times the bilinear element's
    /// centre divergence: the property the pressure-implicit step's
    /// `advection = "bilinear"` rests on.
    #[test]
    fn the_bilinear_interpolation_is_exact_for_linear_fields_and_keeps_the_cell_flux() {
        let h = 0.1;
        let grid = Grid::new(Vec2::new(-0.3, 0.2), h, [6, 5], [false; 2]);
        let n = grid.dims[0] * grid.dims[1];
        let linear = |x: Vec2| Vec2::new(0.3 + 2.0 * x.x - 0.7 * x.y, -1.1 + 0.4 * x.x + 1.3 * x.y);
        let field: Vec<Vec2> = (0..n).map(|i| linear(grid.position(i))).collect();
        for &(a, b) in &[(0.01, 0.013), (0.29, 0.47), (0.5, 0.05), (0.123, 0.377)] {
            let x = grid.origin + Vec2::new(a, b);
            assert!((bilinear(&field, &grid, x) - linear(x)).norm() < 1e-12);
        }
        // Any nodal field: the flux through the cell's four edges (Simpson's
        // rule is exact for the linear edge profiles) against D u h^2.
        let wavy: Vec<Vec2> = (0..n)
            .map(|i| {
                let p = grid.position(i);
                Vec2::new((7.0 * p.x).sin() * p.y, (5.0 * p.y).cos() + p.x * p.x)
            })
            .collect();
        let (ci, cj) = (2usize, 3usize);
        let corner = |di: usize, dj: usize| wavy[grid.index(ci + di + PAD, cj + dj + PAD)];
        let lo = grid.origin + h * Vec2::new(ci as f64, cj as f64);
        let at = |s: f64, t: f64| bilinear(&wavy, &grid, lo + h * Vec2::new(s, t));
        let simpson = |f: &dyn Fn(f64) -> f64| h * (f(0.0) + 4.0 * f(0.5) + f(1.0)) / 6.0;
        let flux = simpson(&|t| at(1.0, t).x) - simpson(&|t| at(0.0, t).x)
            + simpson(&|s| at(s, 1.0).y)
            - simpson(&|s| at(s, 0.0).y);
        let (u00, u10, u01, u11) = (corner(0, 0), corner(1, 0), corner(0, 1), corner(1, 1));
        let centre_divergence =
            (-u00.x + u10.x - u01.x + u11.x - u00.y - u10.y + u01.y + u11.y) / (2.0 * h);
        assert!((flux - centre_divergence * h * h).abs() < 1e-14, "{flux}");
    }
}
