//! Serial particle-grid sums on raw nodes, in particle order (deterministic
//! for any thread count), shared by XPIC, the null-space filter and the
//! multiphase drag.

// The loops walk the weights and the stencil rows in step.
#![allow(clippy::needless_range_loop)]

use crate::grid::Grid;
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
