//! Shape functions as one enum over the families; each family's 1D kernel lives
//! in its own `shape_*.rs`. 2D weights are tensor products.

use crate::choices::ShapeKind;
pub(crate) mod bspline;
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

    /// Nodes per axis touched by one particle.
    pub fn width(&self) -> usize {
        match self.kind {
            ShapeKind::Linear => 2,
            ShapeKind::Gimp | ShapeKind::Bspline2 => 3,
            ShapeKind::Bspline3 | ShapeKind::Cpgimp => 4,
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
            ShapeKind::Linear => linear::kernel(r),
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
            ShapeKind::Linear | ShapeKind::Gimp | ShapeKind::Cpgimp => None,
        }
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
