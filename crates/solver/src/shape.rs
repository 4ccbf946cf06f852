//! Shape functions as one enum over the families; each family's 1D kernel lives
//! in its own `shape_*.rs`. 2D weights are tensor products.

use crate::config::ShapeKind;
use crate::{shape_bspline, shape_gimp, shape_linear};

/// Widest stencil (cubic B-spline) in nodes per axis.
pub const MAX_STENCIL: usize = 4;

/// A particle's place on the grid this step: its stencil's first node (padded
/// index, which is also its sort bin) and its offset past that node in cells.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Stencil {
    pub node: u32,
    pub frac: [f64; 2],
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
    /// GIMP particle half-width in cell units.
    gimp_half: f64,
}

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
            ShapeKind::Bspline3 => 4,
        }
    }

    /// First stencil node for a particle at `xr` (cell units from node 0).
    fn base(&self, xr: f64) -> i64 {
        let shift = match self.kind {
            ShapeKind::Linear => 0.0,
            ShapeKind::Gimp | ShapeKind::Bspline2 => 0.5,
            ShapeKind::Bspline3 => 1.0,
        };
        floor(xr - shift)
    }

    /// Kernel value and derivative at signed distance `r` (cell units).
    #[inline]
    pub fn kernel(&self, r: f64) -> (f64, f64) {
        match self.kind {
            ShapeKind::Linear => shape_linear::kernel(r),
            ShapeKind::Gimp => shape_gimp::kernel(r, self.gimp_half),
            ShapeKind::Bspline2 => shape_bspline::quadratic(r),
            ShapeKind::Bspline3 => shape_bspline::cubic(r),
        }
    }

    /// Weights on the stencil of a particle at `xr` (cell units), as the
    /// stages compute them with [`Shape::stencil_weights`].
    pub fn weights(&self, xr: f64) -> Weights1d {
        let (base, f) = self.locate(xr);
        let mut out = Weights1d {
            base,
            ..Default::default()
        };
        fn put<const W: usize>(out: &mut Weights1d, (w, dw): ([f64; W], [f64; W])) {
            out.w[..W].copy_from_slice(&w);
            out.dw[..W].copy_from_slice(&dw);
        }
        match self.width() {
            2 => put(&mut out, self.stencil_weights::<2>(f)),
            3 => put(&mut out, self.stencil_weights::<3>(f)),
            _ => put(&mut out, self.stencil_weights::<4>(f)),
        }
        out
    }

    /// Values and derivatives (per cell) on the `W` stencil nodes of a particle
    /// `f` cells past the first one. Linear and quadratic take closed forms in
    /// `f` (no branches); the others evaluate the kernel node by node. The
    /// stages call this on the fly rather than storing weights per particle.
    #[inline(always)]
    pub fn stencil_weights<const W: usize>(&self, f: f64) -> ([f64; W], [f64; W]) {
        let (mut w, mut dw) = ([0.0; W], [0.0; W]);
        match self.kind {
            ShapeKind::Linear if W == 2 => {
                (w[0], w[1]) = (1.0 - f, f);
                (dw[0], dw[1]) = (-1.0, 1.0);
            }
            ShapeKind::Bspline2 if W == 3 => {
                // f in [0.5, 1.5): node distances f, f - 1, f - 2.
                let (d0, d1, d2) = (1.5 - f, f - 1.0, f - 0.5);
                (w[0], w[1], w[2]) = (0.5 * d0 * d0, 0.75 - d1 * d1, 0.5 * d2 * d2);
                (dw[0], dw[1], dw[2]) = (-d0, -2.0 * d1, d2);
            }
            _ => {
                for k in 0..W.min(self.width()) {
                    (w[k], dw[k]) = self.kernel(f - k as f64);
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
            ShapeKind::Linear | ShapeKind::Gimp => None,
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
