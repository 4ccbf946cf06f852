//! The pressure operator A = alpha + G^T M'^-1 G + S over the fluid cells
//! (module docs of `projection`): the divergence D at a cell centre, the
//! nodal force G p, the right-hand side with the drift target, and the
//! checkerboard control S.

use super::{remove_mean, Scratch, AIR, CORNERS, HOURGLASS};
use crate::config::{DriftCorrection, Material, ProjectionSettings};
use crate::grid::{Grid, FULL_NODE_SHARE};

use crate::particles::Vec2;

/// The 2 x 2 alternating sum of a node's cells (SW - SE - NW + NE).
#[inline]
pub(super) fn alternating(quad: &[u32; 4], x: &[f64]) -> f64 {
    quad.iter()
        .zip(HOURGLASS)
        .map(|(&u, sign)| sign * x[u as usize])
        .sum()
}

/// D u at a cell: (1 / 2h) sum over the corners of w (sx, sy) . u, with
/// the corners' weights w (1 but under `ghost_orthogonal`).
#[inline]
pub(super) fn divergence(corners: &[u32; 4], weights: &[f64; 4], u: &[Vec2], h: f64) -> f64 {
    let mut sum = 0.0;
    for ((&n, (_, _, sx, sy)), w) in corners.iter().zip(CORNERS).zip(weights) {
        let v = u[n as usize];
        sum += w * (sx * v.x + sy * v.y);
    }
    sum / (2.0 * h)
}

/// The corners' weights of the divergence: 1, or the ghost weights under
/// `ghost_orthogonal` (then D = G^T / h^2 with the same G as the force,
/// and the projection is orthogonal in the nodal masses).
pub(super) const UNWEIGHTED: [f64; 4] = [1.0; 4];

/// `s.nodal` = M'^-1 F G p for the cell values `value(s, k)` of the
/// unknowns: G p scattered on the corners, folded (walls, periodic
/// edges), divided by the mass, filled back to the ghosts.
pub(super) fn apply_g(grid: &Grid, s: &mut Scratch, value: impl Fn(&Scratch, usize) -> f64) {
    let half_h = 0.5 * grid.h;
    for &n in &grid.active {
        s.nodal[n as usize] = Vec2::zeros();
    }
    for k in 0..s.fluid.len() {
        let g = half_h * value(s, k);
        let corners = s.corners[k];
        let ghost = s.ghost[k];
        for ((&n, (_, _, sx, sy)), w) in corners.iter().zip(CORNERS).zip(ghost) {
            let g = g * w;
            s.nodal[n as usize] += Vec2::new(sx * g, sy * g);
        }
    }
    grid.fold(&mut s.nodal);
    for &n in &grid.inside {
        let n = n as usize;
        s.nodal[n] *= s.inv_mass[n];
    }
    grid.fill(&mut s.nodal);
}

/// The right-hand side, the diagonal terms and the Jacobi preconditioner.
pub(super) fn assemble(
    grid: &Grid,
    s: &mut Scratch,
    mat: &Material,
    set: &ProjectionSettings,
    dt: f64,
    full_mass: f64,
) {
    let h2 = grid.h * grid.h;
    let incompressible = mat.k == f64::INFINITY;
    let beta = set.checkerboard / mat.rho0;
    s.q.clear();
    s.q.resize(s.fluid.len(), 0.0);
    s.alpha.clear();
    s.target.clear();
    s.b.clear();
    s.diag.clear();
    s.x.clear();
    let (error_sum, error_cells) = assemble_rows(grid, s, mat, set, dt, full_mass);
    set_drift_target(s, set, dt, incompressible);
    for k in 0..s.fluid.len() {
        s.b[k] += h2 / dt * s.target[k];
    }
    for quad in &s.quads {
        for &u in quad {
            s.diag[u as usize] += beta;
        }
    }
    s.stats.packing_error = if error_cells > 0 {
        error_sum / error_cells as f64
    } else {
        0.0
    };
}

/// Each unknown's EOS coefficient alpha, raw packing error (NaN where it is
/// not read), right-hand side without the drift, diagonal and starting
/// pressure; returns the packing error's sum and count over the full cells.
fn assemble_rows(
    grid: &Grid,
    s: &mut Scratch,
    mat: &Material,
    set: &ProjectionSettings,
    dt: f64,
    full_mass: f64,
) -> (f64, usize) {
    let h = grid.h;
    let h2 = h * h;
    let incompressible = mat.k == f64::INFINITY;
    let full = FULL_NODE_SHARE * full_mass;
    let (mut error_sum, mut error_cells) = (0.0, 0usize);
    for (k, &c) in s.fluid.iter().enumerate() {
        let c = c as usize;
        let corners = s.corners[k];
        let j_cell = s.vol[c] / s.vol0[c];
        // The grid's packing: the corners' mass over a full node's.
        let masses = corners.map(|n| grid.mass[n as usize]);
        // The packing error where all four corners are full, reported
        // there; the correction reads it only `drift_depth` cells inside
        // the fluid (NaN elsewhere).
        let error = if masses.iter().all(|&m| m >= full) {
            let packing = masses.iter().sum::<f64>() / (4.0 * full_mass);
            let error = if incompressible {
                packing - 1.0
            } else {
                packing * j_cell - 1.0
            };
            error_sum += error;
            error_cells += 1;
            if set.drift_depth == 0 || s.deep(c, set.drift_depth as i64) {
                error
            } else {
                f64::NAN
            }
        } else {
            f64::NAN
        };
        let (alpha, p_eos) = if incompressible {
            (0.0, 0.0)
        } else {
            let state = mat.eos(j_cell);
            let kt = state.tangent_modulus.max(1e-300);
            (h2 / (kt * dt * dt), state.pressure)
        };
        let div_star = divergence(&corners, s.divergence_weights(k), &grid.vel_new, h);
        s.alpha.push(alpha);
        s.target.push(error);
        // The EOS and u* parts; the drift's is added below.
        s.b.push(alpha * p_eos - h2 / dt * div_star);
        // Diagonal of G^T M^-1 G without the walls' doubling (|g|^2 = h^2 / 2
        // per corner): a preconditioner only.
        let gmg: f64 = corners
            .iter()
            .zip(s.ghost[k])
            .zip(s.divergence_weights(k))
            .map(|((&n, w), v)| 0.5 * h2 * w * v * s.inv_mass[n as usize])
            .sum();
        s.diag.push(alpha + gmg);
        s.x.push(s.pressure[c]);
    }
    (error_sum, error_cells)
}

/// The drift target r from the raw packing errors in `s.target` (moved
/// to `s.shift` under the drift correction by position).
pub(super) fn set_drift_target(
    s: &mut Scratch,
    set: &ProjectionSettings,
    dt: f64,
    incompressible: bool,
) {
    // The drift target r = drift e~ / dt, e~ the packing error smoothed
    // with weights (1, 2, 1) x (1, 2, 1) over the full cells of the 3 x 3
    // block: the raw per-cell error alternates from cell to cell, and a
    // target that alternates drives the checkerboard the operator cannot
    // resist (measured, 3 s of the incompressible dam break at h = 1 cm:
    // the cell checkerboard 0.18 with the raw error, 0.05 without the drift
    // control, whose grid packing then ends 53 % above 1).
    const WEIGHT: [f64; 3] = [1.0, 2.0, 1.0];
    for k in 0..s.fluid.len() {
        let (mut sum, mut weight) = (0.0, 0.0);
        for (slot, &m) in s.neighbours[k].iter().enumerate() {
            if m == AIR {
                continue;
            }
            let e = s.target[m as usize];
            if e.is_finite() {
                let w = WEIGHT[slot % 3] * WEIGHT[slot / 3];
                sum += w * e;
                weight += w;
            }
        }
        // The rate lands in `q` first: `target` is still being read.
        s.q[k] = if s.target[k].is_finite() && weight > 0.0 {
            set.drift * sum / weight / dt
        } else {
            0.0
        };
    }
    for k in 0..s.fluid.len() {
        s.target[k] = s.q[k];
    }
    // Incompressible and no air cell: the solve drops the mean of the
    // right-hand side, so the target must have none (else every cell's J
    // rate e would be minus its mean).
    if incompressible && s.fluid.len() == s.unknown.len() {
        remove_mean(&mut s.target);
    }
    s.shift.clear();
    if set.drift_correction == DriftCorrection::Position {
        s.shift.extend_from_slice(&s.target);
        s.target.fill(0.0);
    }
}

/// y = A x for the unknowns (`s.nodal` is scratch).
pub(super) fn apply_a(grid: &Grid, s: &mut Scratch, beta: f64, from_d: bool) {
    let h = grid.h;
    if from_d {
        apply_g(grid, s, |s, k| s.d[k]);
    } else {
        apply_g(grid, s, |s, k| s.x[k]);
    }
    let h2 = h * h;
    for k in 0..s.fluid.len() {
        let v = if from_d { s.d[k] } else { s.x[k] };
        s.q[k] =
            s.alpha[k] * v + h2 * divergence(&s.corners[k], s.divergence_weights(k), &s.nodal, h);
    }
    let src = if from_d { &s.d } else { &s.x };
    add_checkerboard(&s.quads, src, beta, &mut s.q);
}

/// out += S p, S = beta C^T C over the nodes whose four cells are fluid
/// (the checkerboard control).
pub(super) fn add_checkerboard(quads: &[[u32; 4]], p: &[f64], beta: f64, out: &mut [f64]) {
    if beta == 0.0 {
        return;
    }
    for quad in quads {
        let c = beta * alternating(quad, p);
        for (u, sign) in quad.iter().zip(HOURGLASS) {
            out[*u as usize] += sign * c;
        }
    }
}
