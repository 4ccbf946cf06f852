//! Shape functions as one enum over the families; each family's 1D kernel lives
//! in its own `shape_*.rs`. 2D weights are tensor products, or (CPDI) sums
//! of four: the stages walk a particle's weights as `Piece`s.

use crate::choices::ShapeKind;
pub(crate) mod bspline;
pub mod cpdi;
mod gimp;
pub(crate) mod linear;

/// Runs `$body` with the constant `$w` set to the shape's stencil width in
/// nodes per axis (2, 3 or 4): the one place the width is matched, so every
/// particle loop is monomorphised on it.
macro_rules! with_width {
    ($shape:expr, $w:ident => $body:expr) => {
        match $shape.width() {
            2 => {
                const $w: usize = 2;
                $body
            }
            3 => {
                const $w: usize = 3;
                $body
            }
            _ => {
                const $w: usize = 4;
                $body
            }
        }
    };
}
pub(crate) use with_width;

/// The families whose weights are one tensor product: what the paths that
/// read per-axis weights (most remedies, mixtures, the projection) take.
pub const TENSOR_PRODUCT: &[ShapeKind] = &[
    ShapeKind::Linear,
    ShapeKind::Gimp,
    ShapeKind::Cpgimp,
    ShapeKind::Bspline2,
    ShapeKind::Bspline3,
];

/// Widest stencil (cubic B-spline) in nodes per axis.
pub const MAX_STENCIL: usize = 4;

/// A particle's place on the grid this step: its stencil's first node (padded
/// index, which is also its sort bin) and its offset past that node in cells.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Stencil {
    pub node: u32,
    pub frac: [f64; 2],
    /// GIMP particle half-width per axis in cell units (uGIMP: constant;
    /// cpGIMP: follows F's diagonal); unused by the other families.
    pub half: [f64; 2],
    /// CPDI's domain vectors [r1x, r1y, r2x, r2y] in cells
    /// (`cpdi::domain`); unused by the other families.
    pub domain: [f64; 4],
}

/// One tensor-product share of a particle's weights: the node (a, c) past
/// `node` takes weight `wx[a] wy[c]` and gradient (`dwx[a] wy[c]`,
/// `wx[a] dwy[c]`) per cell. A tensor-product shape has one piece, its
/// stencil; CPDI has one per domain corner (`cpdi::corner_piece`).
#[derive(Clone, Copy, Debug)]
pub struct Piece<const W: usize> {
    /// The piece's first node (padded index).
    pub node: usize,
    /// The particle's offset past that node, in cells.
    pub frac: [f64; 2],
    pub wx: [f64; W],
    pub dwx: [f64; W],
    pub wy: [f64; W],
    pub dwy: [f64; W],
}

impl<const W: usize> Piece<W> {
    /// Each node of the piece, rows of y outer: its padded index (rows
    /// `nx` long), its offset (a, c) past the piece's first node, its
    /// weight and its gradient per cell.
    #[inline(always)]
    pub fn each_node(&self, nx: usize, mut visit: impl FnMut(usize, [usize; 2], f64, [f64; 2])) {
        for c in 0..W {
            for a in 0..W {
                let grad = [self.dwx[a] * self.wy[c], self.wx[a] * self.dwy[c]];
                visit(
                    self.node + a + c * nx,
                    [a, c],
                    self.wx[a] * self.wy[c],
                    grad,
                );
            }
        }
    }
}

/// 1D weights of one particle on its stencil nodes `base .. base + width`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Weights1d {
    pub base: i64,
    pub w: [f64; MAX_STENCIL],
    /// dN/dx in units of 1/cell (divide by h for 1/m).
    pub dw: [f64; MAX_STENCIL],
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Shape {
    pub kind: ShapeKind,
    /// Undeformed GIMP particle half-width in cell units.
    gimp_half: f64,
}

/// cpGIMP half-widths stay within these bounds (cell units): above 1 the
/// support would outgrow the 4-node stencil; the floor keeps the kernel's
/// 1/(2l) well conditioned.
pub const CPGIMP_HALF_MIN: f64 = 0.01;
pub const CPGIMP_HALF_MAX: f64 = 1.0;

impl Shape {
    pub fn new(kind: ShapeKind, ppc: usize) -> Self {
        Shape {
            kind,
            gimp_half: 0.5 / ppc as f64,
        }
    }

    /// Nodes per axis of one piece (`Piece`): the stages' loop width.
    pub fn width(&self) -> usize {
        match self.kind {
            ShapeKind::Linear | ShapeKind::Cpdi => 2,
            ShapeKind::Gimp | ShapeKind::Bspline2 => 3,
            ShapeKind::Bspline3 | ShapeKind::Cpgimp => 4,
        }
    }

    /// Nodes per axis that one particle's pieces can touch, from its
    /// stencil's first node (`Stencil::node`).
    pub fn reach(&self) -> usize {
        match self.kind {
            ShapeKind::Cpdi => cpdi::REACH_NODES,
            _ => self.width(),
        }
    }

    /// A particle's CPDI domain for deformation gradient `f`
    /// (`Stencil::domain`); zeros for the other families.
    #[inline]
    pub fn domain(&self, f: &crate::particles::Mat2) -> [f64; 4] {
        match self.kind {
            ShapeKind::Cpdi => cpdi::domain(f, self.gimp_half),
            _ => [0.0; 4],
        }
    }

    /// A particle's GIMP half-widths (cell units) for deformation gradient
    /// `f`: cpGIMP scales the undeformed half-width by F's diagonal (F starts
    /// at I, so this is the product of l_ii F_ii(new) / F_ii(old) over the
    /// steps), clamped to [`CPGIMP_HALF_MIN`], [`CPGIMP_HALF_MAX`].
    #[inline]
    pub fn half_widths(&self, f: &crate::particles::Mat2) -> [f64; 2] {
        match self.kind {
            ShapeKind::Cpgimp => {
                [0, 1].map(|a| (self.gimp_half * f[(a, a)]).clamp(CPGIMP_HALF_MIN, CPGIMP_HALF_MAX))
            }
            _ => [self.gimp_half; 2],
        }
    }

    /// First stencil node for a particle at `xr` (cell units from node 0).
    fn base(&self, xr: f64) -> i64 {
        let shift = match self.kind {
            ShapeKind::Linear => 0.0,
            ShapeKind::Gimp | ShapeKind::Bspline2 => 0.5,
            ShapeKind::Bspline3 | ShapeKind::Cpgimp => 1.0,
            ShapeKind::Cpdi => cpdi::CORNER_REACH,
        };
        floor(xr - shift)
    }

    /// Kernel value and derivative at signed distance `r` (cell units), for
    /// an undeformed particle.
    #[inline]
    pub fn kernel(&self, r: f64) -> (f64, f64) {
        self.kernel_with_half(r, self.gimp_half)
    }

    /// Kernel value and derivative at signed distance `r` (cell units) for a
    /// GIMP half-width `half` (used by cpGIMP only).
    #[inline]
    pub fn kernel_with_half(&self, r: f64, half: f64) -> (f64, f64) {
        match self.kind {
            // CPDI: the hat each corner takes.
            ShapeKind::Linear | ShapeKind::Cpdi => linear::kernel(r),
            ShapeKind::Gimp => gimp::kernel(r, self.gimp_half),
            ShapeKind::Cpgimp => gimp::kernel_any_width(r, half),
            ShapeKind::Bspline2 => bspline::quadratic(r),
            ShapeKind::Bspline3 => bspline::cubic(r),
        }
    }

    /// Weights on the stencil of an undeformed particle at `xr` (cell units),
    /// as the stages compute them with [`Shape::stencil_weights`].
    pub fn weights(&self, xr: f64) -> Weights1d {
        self.weights_with_half(xr, self.gimp_half)
    }

    /// As [`Shape::weights`] for a GIMP half-width `half` (cpGIMP).
    pub fn weights_with_half(&self, xr: f64, half: f64) -> Weights1d {
        let (base, f) = self.locate(xr);
        let mut out = Weights1d {
            base,
            ..Default::default()
        };
        fn put<const W: usize>(out: &mut Weights1d, (w, dw): ([f64; W], [f64; W])) {
            out.w[..W].copy_from_slice(&w);
            out.dw[..W].copy_from_slice(&dw);
        }
        crate::shapes::with_width!(self, W => put(&mut out, self.stencil_weights::<W>(f, half)));
        out
    }

    /// Values and derivatives (per cell) on the `W` stencil nodes of a particle
    /// `f` cells past the first one. Linear and quadratic take closed forms in
    /// `f` (no branches); the others evaluate the kernel node by node. The
    /// stages call this on the fly rather than storing weights per particle.
    /// `half` is the particle's GIMP half-width on this axis (`Stencil::half`),
    /// read by cpGIMP only.
    #[inline(always)]
    pub fn stencil_weights<const W: usize>(&self, f: f64, half: f64) -> ([f64; W], [f64; W]) {
        let (mut w, mut dw) = ([0.0; W], [0.0; W]);
        match self.kind {
            ShapeKind::Linear if W == 2 => {
                (w[0], w[1]) = (1.0 - f, f);
                (dw[0], dw[1]) = (-1.0, 1.0);
            }
            ShapeKind::Bspline2 if W == 3 => {
                let (w3, dw3) = bspline::quadratic_stencil(f);
                w.copy_from_slice(&w3);
                dw.copy_from_slice(&dw3);
            }
            // uGIMP's half-width is fixed: call its kernel directly (the
            // general arm's dispatch per node kept it out of line).
            ShapeKind::Gimp if W == 3 => {
                for k in 0..3 {
                    (w[k], dw[k]) = gimp::kernel(f - k as f64, self.gimp_half);
                }
            }
            _ => {
                for k in 0..W.min(self.width()) {
                    (w[k], dw[k]) = self.kernel_with_half(f - k as f64, half);
                }
            }
        }
        (w, dw)
    }

    /// Where a particle at `xr` (cell units) sits on one axis: its first
    /// stencil node and the offset past it.
    #[inline]
    pub fn locate(&self, xr: f64) -> (i64, f64) {
        let base = self.base(xr);
        (base, xr - base as f64)
    }

    /// APIC inertia D^-1 h^2 where it is a constant (B-splines); None otherwise.
    pub fn apic_inverse_inertia(&self) -> Option<f64> {
        match self.kind {
            ShapeKind::Bspline2 => Some(4.0),
            ShapeKind::Bspline3 => Some(3.0),
            ShapeKind::Linear | ShapeKind::Gimp | ShapeKind::Cpgimp | ShapeKind::Cpdi => None,
        }
    }

    /// The particle's one piece under a tensor-product shape.
    #[inline(always)]
    pub fn tensor_piece<const W: usize>(&self, st: &Stencil) -> Piece<W> {
        let (wx, dwx) = self.stencil_weights::<W>(st.frac[0], st.half[0]);
        let (wy, dwy) = self.stencil_weights::<W>(st.frac[1], st.half[1]);
        Piece {
            node: st.node as usize,
            frac: st.frac,
            wx,
            dwx,
            wy,
            dwy,
        }
    }

    /// Runs `visit` on each of a particle's pieces: its stencil under a
    /// tensor-product shape, its four corners under CPDI. `nx` is the
    /// padded grid's row length. `visit` has one call site, so that it is
    /// inlined whole (a second one cost B-spline P2G 60 %).
    #[inline(always)]
    pub fn each_piece<const W: usize>(
        &self,
        st: &Stencil,
        nx: usize,
        mut visit: impl FnMut(&Piece<W>),
    ) {
        // CPDI's pieces are 2 wide: wider stencils never take them.
        let cpdi = W == 2 && self.kind == ShapeKind::Cpdi;
        let pieces = if cpdi { cpdi::CORNERS.len() } else { 1 };
        for k in 0..pieces {
            let piece = if cpdi {
                cpdi::corner_piece::<W>(st, nx, k)
            } else {
                self.tensor_piece::<W>(st)
            };
            visit(&piece);
        }
    }

    /// Each (node, weight, gradient per cell) of a particle at `xr` (cells
    /// from node 0) with deformation gradient `f`, node by node of each
    /// piece (rows of y outer), the node as its (x, y) index: for the paths
    /// off the step loop (the monitor, tests). A node can come more than
    /// once under CPDI; its shares add.
    pub fn each_weight(
        &self,
        xr: [f64; 2],
        f: &crate::particles::Mat2,
        mut visit: impl FnMut([i64; 2], f64, [f64; 2]),
    ) {
        let ((bx, fx), (by, fy)) = (self.locate(xr[0]), self.locate(xr[1]));
        // Nodes numbered in a reach x reach frame from the stencil's first.
        let nx = self.reach();
        let st = Stencil {
            node: 0,
            frac: [fx, fy],
            half: self.half_widths(f),
            domain: self.domain(f),
        };
        fn walk<const W: usize>(
            shape: &Shape,
            st: &Stencil,
            nx: usize,
            visit: &mut impl FnMut(usize, f64, [f64; 2]),
        ) {
            shape.each_piece::<W>(st, nx, |p| {
                p.each_node(nx, |n, _, w, grad| visit(n, w, grad))
            });
        }
        let mut local = |n: usize, w: f64, grad: [f64; 2]| {
            visit([bx + (n % nx) as i64, by + (n / nx) as i64], w, grad)
        };
        with_width!(self, W => walk::<W>(self, &st, nx, &mut local))
    }
}

/// floor(x) as an integer (exact for |x| < 2^53; a NaN maps to 0 and is
/// caught by the caller's finiteness check). With SSE4.1 `floor` is one
/// instruction; without it, it would be a libm call, so compare instead.
#[inline]
fn floor(x: f64) -> i64 {
    if cfg!(target_feature = "sse4.1") {
        return x.floor() as i64;
    }
    let t = x as i64;
    if (t as f64) > x {
        t - 1
    } else {
        t
    }
}
