//! CPDI (Sadeghirad, Brannon & Burghardt 2011), in 2D: a particle's domain
//! is the parallelogram x_p + xi r1 + eta r2 (xi, eta in [-1, 1]), with r1
//! and r2 the columns of F times the undeformed half-width. Its weight on
//! node i is the mean of the hat N_i over the four corners; its gradient is
//! the domain mean of the gradient of N_i's bilinear interpolation between
//! the corners: sum over corners of N_i(x_c) G_c, with
//! G_c = (xi_c (r2y, -r2x) + eta_c (-r1y, r1x)) / (4 det[r1 r2]).
//! Neither is a tensor product, but each corner's share is: the stages run
//! one linear-hat piece per corner (`Piece`), whose per-axis arrays carry
//! the 1/4 and G_c.

use super::{Piece, Stencil};

/// Corner coordinates (xi, eta), counter-clockwise from (-1, -1).
pub const CORNERS: [[f64; 2]; 4] = [[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]];

/// A corner lies at most this many cells from its particle along each axis,
/// so the support fits the 4-node stencil (Uintah's `cpdi_lcrit` caps the
/// domain vectors' lengths instead, by default not at all). A larger domain
/// is scaled down whole, which keeps its shape.
pub const CORNER_REACH: f64 = CORNER_REACH_CELLS as f64;
pub const CORNER_REACH_CELLS: usize = 1;

/// Nodes per axis a particle's corners can touch from its stencil's first
/// node, `floor(x_p - CORNER_REACH)`.
pub const REACH_NODES: usize = 2 * CORNER_REACH_CELLS + 2;

// The ghost layers hold a corner past a wall; colours keep two tiles of
// particles apart (`sort::TILE`).
const _: () = assert!(CORNER_REACH_CELLS <= crate::grid::PAD);
const _: () = assert!(REACH_NODES <= crate::stages::sort::TILE + 1);

/// A domain whose area has fallen below this share of the undeformed one
/// (an inverted or collapsed particle kept by `on_inversion = "keep"`)
/// takes the undeformed square: 1/det would not be finite.
pub const AREA_FLOOR: f64 = 1e-12;

/// The domain's vectors [r1x, r1y, r2x, r2y] in cells for deformation
/// gradient `f` and undeformed half-width `half` (cells).
pub fn domain(f: &crate::particles::Mat2, half: f64) -> [f64; 4] {
    let r = [f[(0, 0)], f[(1, 0)], f[(0, 1)], f[(1, 1)]].map(|v| v * half);
    let det = r[0] * r[3] - r[1] * r[2];
    if !det.is_finite() || det.abs() <= AREA_FLOOR * half * half {
        return [half, 0.0, 0.0, half];
    }
    let reach = (r[0].abs() + r[2].abs()).max(r[1].abs() + r[3].abs());
    if reach > CORNER_REACH {
        let s = CORNER_REACH / reach;
        return r.map(|v| v * s);
    }
    r
}

/// Corner `k`'s piece (`CORNERS[k]`) of a particle with stencil `st` (its
/// first node `CORNER_REACH` cells below and left of the particle's cell,
/// `st.frac` in [CORNER_REACH, CORNER_REACH + 1)). Only the first two
/// entries of each array are used (`W` >= 2).
#[inline(always)]
pub fn corner_piece<const W: usize>(st: &Stencil, nx: usize, k: usize) -> Piece<W> {
    let [r1x, r1y, r2x, r2y] = st.domain;
    let [xi, eta] = CORNERS[k];
    let quarter_inv_det = 0.25 / (r1x * r2y - r1y * r2x);
    let corner = [
        st.frac[0] + xi * r1x + eta * r2x,
        st.frac[1] + xi * r1y + eta * r2y,
    ];
    // G_c per cell; x carries the corner's 1/4, y the 4 that undoes it in dN_y.
    let scale = [0.25, 1.0];
    let grad = [
        (xi * r2y - eta * r1y) * quarter_inv_det,
        4.0 * (eta * r1x - xi * r2x) * quarter_inv_det,
    ];
    let mut piece = Piece {
        node: st.node as usize,
        frac: st.frac,
        wx: [0.0; W],
        dwx: [0.0; W],
        wy: [0.0; W],
        dwy: [0.0; W],
    };
    let mut offset = [0usize; 2];
    for a in 0..2 {
        // The corner lies within the reach past the stencil's first node.
        let c = corner[a].clamp(0.0, (REACH_NODES - 1) as f64);
        let first = (c.floor() as usize).min(REACH_NODES - 2);
        let t = c - first as f64;
        offset[a] = first;
        piece.frac[a] = st.frac[a] - first as f64;
        let (w, dw) = if a == 0 {
            (&mut piece.wx, &mut piece.dwx)
        } else {
            (&mut piece.wy, &mut piece.dwy)
        };
        (w[0], w[1]) = (scale[a] * (1.0 - t), scale[a] * t);
        (dw[0], dw[1]) = (grad[a] * (1.0 - t), grad[a] * t);
    }
    piece.node += offset[0] + offset[1] * nx;
    piece
}
