//! Particle-to-grid transfer as a coloured scatter. Particles are walked tile
//! by tile (`sort::TILE` bins a side); tiles of one colour never share a
//! node, so they scatter in parallel straight into the grid, and the colours
//! run one after the other. Every node therefore sums its particles in the same
//! order (colour, then bin, then particle index) for any thread count.

use crate::grid::Grid;
use crate::par::Pieces;
use crate::particles::{Mat2, Particles, Vec2};
use crate::shapes::{Piece, Shape, Stencil};
use crate::stages::sort::{Bins, TILE};
use rayon::prelude::*;

/// Which nodal sums a P2G pass computes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Terms {
    pub mass: bool,
    pub momentum: bool,
    /// Internal force -sum V sigma grad N plus gravity (m_i g, with the mass).
    pub force: bool,
}

/// Read-only inputs of a P2G pass.
pub struct Inputs<'a> {
    pub particles: &'a Particles,
    pub stencils: &'a [Stencil],
    pub shape: &'a Shape,
    pub bins: &'a Bins,
    /// Include the APIC affine term in the momentum.
    pub affine: bool,
    /// MLS force: D^-1 h^2 of the B-spline (4 quadratic, 3 cubic); None =
    /// the gradient force.
    pub mls: Option<f64>,
    pub gravity: Vec2,
    /// The pressure-implicit step: the internal force leaves the particle
    /// pressure out (the cell pressure is solved for on the grid).
    pub pressure_free: bool,
}

/// One scatter pass: its inputs and the grid fields it writes, shared by the
/// tiles of one colour.
struct Pass<'a> {
    inputs: &'a Inputs<'a>,
    mass: *mut f64,
    momentum: *mut Vec2,
    force: *mut Vec2,
    len: usize,
    dims: [usize; 2],
    h: f64,
    inv_h: f64,
}

// SAFETY: tiles of one colour write disjoint node sets (see `TILE`), and the
// colours are separated by the join at the end of each parallel loop.
unsafe impl Sync for Pass<'_> {}

pub fn p2g(inputs: &Inputs, terms: Terms, grid: &mut Grid) {
    let pass = Pass {
        inputs,
        mass: grid.mass_raw.as_mut_ptr(),
        momentum: grid.momentum.as_mut_ptr(),
        force: grid.force.as_mut_ptr(),
        len: grid.mass_raw.len(),
        dims: grid.dims,
        h: grid.h,
        inv_h: 1.0 / grid.h,
    };
    let (pass, active) = (&pass, &grid.active[..]);
    // SAFETY (both node loops): active nodes are distinct and below `len`.
    each_node(active, |n| unsafe {
        debug_assert!(n < pass.len);
        if terms.mass {
            *pass.mass.add(n) = 0.0;
        }
        if terms.momentum {
            *pass.momentum.add(n) = Vec2::zeros();
        }
        if terms.force {
            *pass.force.add(n) = Vec2::zeros();
        }
    });
    crate::shapes::with_width!(inputs.shape, W => scatter_colours::<W>(pass, terms));
    if terms.force {
        // sum_p N m g = m_i g: gravity once per node rather than per particle.
        let g = inputs.gravity;
        each_node(active, |n| unsafe {
            *pass.force.add(n) += g * *pass.mass.add(n)
        });
    }
}

/// Runs `f` on every active node, in parallel pieces of `NODE_CHUNK` nodes.
fn each_node(active: &[u32], f: impl Fn(usize) + Sync) {
    let piece = crate::par::piece_len(active.len()).div_ceil(NODE_CHUNK);
    active
        .par_chunks(NODE_CHUNK)
        .pieces(piece)
        .for_each(|nodes| {
            for &n in nodes {
                f(n as usize);
            }
        });
}

/// Tiles per parallel work item (a tile holds up to a few hundred
/// particles; see `par::piece_len`).
const TILES_PER_PIECE: usize = 1;

/// Active nodes per parallel work item in the node loops.
const NODE_CHUNK: usize = 2048;

fn scatter_colours<const W: usize>(pass: &Pass, terms: Terms) {
    // Four joins per pass cost more than they save on a small scene.
    let parallel = crate::par::parallel(pass.inputs.particles.len());
    macro_rules! go {
        ($m:literal, $p:literal, $f:literal) => {
            for tiles in &pass.inputs.bins.by_colour {
                if parallel {
                    tiles
                        .par_iter()
                        .pieces(TILES_PER_PIECE)
                        .for_each(|&tile| scatter_tile::<W, $m, $p, $f>(pass, tile as usize));
                } else {
                    for &tile in tiles {
                        scatter_tile::<W, $m, $p, $f>(pass, tile as usize);
                    }
                }
            }
        };
    }
    match (terms.mass, terms.momentum, terms.force) {
        (true, true, true) => go!(true, true, true),
        (true, true, false) => go!(true, true, false),
        (true, false, true) => go!(true, false, true),
        (true, false, false) => go!(true, false, false),
        (false, true, true) => go!(false, true, true),
        (false, true, false) => go!(false, true, false),
        (false, false, true) => go!(false, false, true),
        (false, false, false) => {}
    }
}

fn scatter_tile<const W: usize, const MASS: bool, const MOMENTUM: bool, const FORCE: bool>(
    pass: &Pass,
    tile: usize,
) {
    let (bins, dims) = (pass.inputs.bins, pass.dims);
    let (tx, ty) = (tile % bins.tiles[0], tile / bins.tiles[0]);
    let (x0, x1) = (tx * TILE, ((tx + 1) * TILE).min(dims[0]));
    for bj in ty * TILE..((ty + 1) * TILE).min(dims[1]) {
        let row = bj * dims[0];
        for &p in bins.of_range(row + x0, row + x1) {
            scatter_particle::<W, MASS, MOMENTUM, FORCE>(pass, p as usize);
        }
    }
}

#[inline(always)]
fn scatter_particle<const W: usize, const MASS: bool, const MOMENTUM: bool, const FORCE: bool>(
    pass: &Pass,
    p: usize,
) {
    let st = &pass.inputs.stencils[p];
    pass.inputs
        .shape
        .each_piece::<W>(st, pass.dims[0], |piece| {
            scatter_piece::<W, MASS, MOMENTUM, FORCE>(pass, p, piece)
        });
}

/// Particle `p`'s sums on the nodes of one of its pieces.
#[inline(always)]
fn scatter_piece<const W: usize, const MASS: bool, const MOMENTUM: bool, const FORCE: bool>(
    pass: &Pass,
    p: usize,
    piece: &Piece<W>,
) {
    let (inputs, dims) = (pass.inputs, pass.dims);
    let ps = inputs.particles;
    let [fx, fy] = piece.frac;
    let (wx, dwx, wy, dwy) = (piece.wx, piece.dwx, piece.wy, piece.dwy);
    let base = piece.node;
    let m = ps.mass[p];
    // Momentum at node (a, c): N m (v + C h (a - fx, c - fy)), split into a
    // per-particle constant and a slope per node step (cell units).
    let (mv0, slope) = if MOMENTUM {
        if inputs.affine {
            let mc = ps.affine[p] * (m * pass.h);
            (m * ps.v[p] - mc * Vec2::new(fx, fy), mc)
        } else {
            (m * ps.v[p], Mat2::zeros())
        }
    } else {
        (Vec2::zeros(), Mat2::zeros())
    };
    // Internal force at node (a, c): A (dNx wy, wx dNy) with A = -V sigma / h.
    // MLS: -V sigma D^-1 (x_i - x_p) N, the same form with dN_x -> N_x (a - fx),
    // dN_y -> N_y (c - fy) and A = -V sigma (D^-1 h^2) / h.
    let sigma = if FORCE && inputs.pressure_free {
        ps.stress[p] + ps.pressure[p] * Mat2::identity()
    } else {
        ps.stress[p]
    };
    let (a_mat, dwx, dwy) = match inputs.mls {
        Some(inertia) if FORCE => (
            sigma * (-ps.vol[p] * inertia * pass.inv_h),
            std::array::from_fn::<f64, W, _>(|a| wx[a] * (a as f64 - fx)),
            std::array::from_fn::<f64, W, _>(|c| wy[c] * (c as f64 - fy)),
        ),
        _ if FORCE => (sigma * (-ps.vol[p] * pass.inv_h), dwx, dwy),
        _ => (Mat2::zeros(), dwx, dwy),
    };
    debug_assert!(base + (W - 1) * (dims[0] + 1) < pass.len);
    for c in 0..W {
        let (wyc, dwyc) = (wy[c], dwy[c]);
        let row = base + c * dims[0];
        let mass_row = m * wyc;
        let mom_row = wyc * (mv0 + slope.column(1) * c as f64);
        let mom_slope = wyc * slope.column(0);
        let force_w = a_mat.column(0) * wyc;
        let force_dw = a_mat.column(1) * dwyc;
        for a in 0..W {
            let n = row + a;
            let wxa = wx[a];
            // SAFETY: `n` lies in the particle's stencil, inside the padded
            // grid (checked by the sort), and no other thread writes it now.
            unsafe {
                if MASS {
                    *pass.mass.add(n) += wxa * mass_row;
                }
                if MOMENTUM {
                    *pass.momentum.add(n) += wxa * mom_row + (wxa * a as f64) * mom_slope;
                }
                if FORCE {
                    *pass.force.add(n) += dwx[a] * force_w + wxa * force_dw;
                }
            }
        }
    }
}
