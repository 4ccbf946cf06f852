//! Grid-to-particle transfer: particle velocity by PIC, FLIP blend or APIC,
//! position moved with the grid velocity, periodic wrap; and, for every
//! transfer, the force-driven acceleration sum N_i (v_i^new - v_i) / dt that
//! the monitor scores (docs/physics.md section 4b). Sums run row by row
//! of the stencil (x inner), so each node costs a few multiply-adds.

use crate::config::TransferKind;
use crate::grid::Grid;
use crate::par::Pieces;
use crate::particles::{Mat2, Particles, Vec2};
use crate::shapes::{Piece, Shape, Stencil};
use rayon::prelude::*;

pub struct Transfer {
    pub kind: TransferKind,
    pub flip_alpha: f64,
    /// Move the particles with the bilinear element's velocity (the
    /// pressure-implicit step's `advection = "bilinear"`), not the shapes'.
    pub bilinear_advection: bool,
    /// FLIP keeps the velocity gradient sum v_i grad N_i^T in `affine`
    /// for the next P2G (`Method::gradient_enhanced`).
    pub gradient_enhanced: bool,
}

/// How G2P sets particle velocities, fixed per run so the loop carries no branches.
const PIC: u8 = 0;
const FLIP: u8 = 1;
/// APIC with a B-spline (constant inertia D): C = B D^-1.
const APIC_SPLINE: u8 = 2;
/// APIC with multilinear/GIMP: C = sum v grad N^T (= B D^-1 for linear).
const APIC_GRADIENT: u8 = 3;
/// FLIP that keeps L = sum v grad N^T for a gradient-enhanced P2G.
const FLIP_GRADIENT: u8 = 4;

pub fn g2p(
    particles: &mut Particles,
    stencils: &[Stencil],
    grid: &Grid,
    shape: &Shape,
    transfer: &Transfer,
    dt: f64,
) {
    let mode = match transfer.kind {
        TransferKind::Pic => PIC,
        TransferKind::Flip if transfer.gradient_enhanced => FLIP_GRADIENT,
        TransferKind::Flip if transfer.flip_alpha > 0.0 => FLIP,
        TransferKind::Flip => PIC,
        // The particle velocity is S v* already: FLIP's increment on top.
        TransferKind::Xpic => FLIP,
        TransferKind::Apic if shape.apic_inverse_inertia().is_some() => APIC_SPLINE,
        TransferKind::Apic => APIC_GRADIENT,
    };
    crate::shapes::with_width!(shape, W => match mode {
        PIC => run::<W, PIC>(particles, stencils, grid, shape, transfer, dt),
        FLIP => run::<W, FLIP>(particles, stencils, grid, shape, transfer, dt),
        FLIP_GRADIENT => run::<W, FLIP_GRADIENT>(particles, stencils, grid, shape, transfer, dt),
        APIC_SPLINE => run::<W, APIC_SPLINE>(particles, stencils, grid, shape, transfer, dt),
        _ => run::<W, APIC_GRADIENT>(particles, stencils, grid, shape, transfer, dt),
    })
}

fn run<const W: usize, const MODE: u8>(
    particles: &mut Particles,
    stencils: &[Stencil],
    grid: &Grid,
    shape: &Shape,
    transfer: &Transfer,
    dt: f64,
) {
    let nx = grid.dims[0];
    let inv_h = 1.0 / grid.h;
    // B-splines: B is summed in cells, so C = B_cells h D^-1 = B_cells (D^-1 h^2) / h.
    let c_scale = shape.apic_inverse_inertia().unwrap_or(1.0) * inv_h;
    let alpha = transfer.flip_alpha;
    let inv_dt = 1.0 / dt;
    let lo = grid.origin;
    let size = Vec2::new(grid.cells[0] as f64 * grid.h, grid.cells[1] as f64 * grid.h);
    let (vel, vel_new) = (&grid.vel[..], &grid.vel_new[..]);
    (
        particles.x.par_iter_mut(),
        particles.v.par_iter_mut(),
        particles.affine.par_iter_mut(),
        particles.accel.par_iter_mut(),
        stencils.par_iter(),
    )
        .into_par_iter()
        .pieces(crate::par::piece_len(stencils.len()))
        .for_each(|(x, v, affine, accel, st)| {
            let Gathered { v_pic, dv, b0, b1 } = gather::<W, MODE>(shape, st, vel, vel_new, nx);
            *accel = dv * inv_dt;
            *v = if MODE == FLIP || MODE == FLIP_GRADIENT {
                alpha * (*v + dv) + (1.0 - alpha) * v_pic
            } else {
                v_pic
            };
            if MODE == APIC_SPLINE || MODE == APIC_GRADIENT {
                *affine = Mat2::from_columns(&[b0, b1]) * c_scale;
            } else if MODE == FLIP_GRADIENT {
                *affine = Mat2::from_columns(&[b0, b1]) * inv_h;
            }
            *x += dt
                * if transfer.bilinear_advection {
                    crate::transfers::serial::bilinear(vel_new, grid, *x)
                } else {
                    v_pic
                };
            for k in 0..2 {
                if grid.periodic[k] {
                    x[k] = lo[k] + (x[k] - lo[k]).rem_euclid(size[k]);
                }
            }
        });
}

/// What G2P gathers at a particle from its stencil: the PIC velocity, the
/// grid's velocity change, and the affine matrix's columns before scaling.
struct Gathered {
    v_pic: Vec2,
    dv: Vec2,
    b0: Vec2,
    b1: Vec2,
}

/// The stencil sums of G2P at one particle, row by row (x inner).
#[inline(always)]
fn gather<const W: usize, const MODE: u8>(
    shape: &Shape,
    st: &Stencil,
    vel: &[Vec2],
    vel_new: &[Vec2],
    nx: usize,
) -> Gathered {
    let mut sums = Gathered {
        v_pic: Vec2::zeros(),
        dv: Vec2::zeros(),
        b0: Vec2::zeros(),
        b1: Vec2::zeros(),
    };
    shape.each_piece::<W>(st, nx, |piece| {
        gather_piece::<W, MODE>(piece, vel, vel_new, nx, &mut sums)
    });
    sums
}

/// One piece's share of the G2P sums, added to `sums`.
#[inline(always)]
fn gather_piece<const W: usize, const MODE: u8>(
    piece: &Piece<W>,
    vel: &[Vec2],
    vel_new: &[Vec2],
    nx: usize,
    sums: &mut Gathered,
) {
    let [fx, fy] = piece.frac;
    let (wx, dwx, wy, dwy) = (piece.wx, piece.dwx, piece.wy, piece.dwy);
    let base = piece.node;
    let Gathered { v_pic, dv, b0, b1 } = sums;
    for c in 0..W {
        let row = base + c * nx;
        // s0 = sum N_x v; s1 = sum N_x a v (spline APIC) or sum dN_x v.
        let (mut s0, mut s1, mut sd) = (Vec2::zeros(), Vec2::zeros(), Vec2::zeros());
        for a in 0..W {
            let vn = vel_new[row + a];
            s0 += wx[a] * vn;
            sd += wx[a] * (vn - vel[row + a]);
            match MODE {
                APIC_SPLINE => s1 += (wx[a] * a as f64) * vn,
                APIC_GRADIENT | FLIP_GRADIENT => s1 += dwx[a] * vn,
                _ => {}
            }
        }
        *v_pic += wy[c] * s0;
        *dv += wy[c] * sd;
        match MODE {
            APIC_SPLINE => {
                *b0 += wy[c] * (s1 - fx * s0);
                *b1 += (wy[c] * (c as f64 - fy)) * s0;
            }
            APIC_GRADIENT | FLIP_GRADIENT => {
                *b0 += wy[c] * s1;
                *b1 += dwy[c] * s0;
            }
            _ => {}
        }
    }
}
