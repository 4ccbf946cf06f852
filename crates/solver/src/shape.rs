//! Shape functions as one enum over the families; each family's 1D kernel lives
//! in its own `shape_*.rs`. 2D weights are tensor products.

use crate::config::ShapeKind;
use crate::{shape_bspline, shape_gimp, shape_linear};

/// Widest stencil (cubic B-spline) in nodes per axis.
pub const MAX_STENCIL: usize = 4;

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
        (xr - shift).floor() as i64
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

    /// Weights on the stencil of a particle at `xr` (cell units).
    #[inline]
    pub fn weights(&self, xr: f64) -> Weights1d {
        let base = self.base(xr);
        let mut out = Weights1d {
            base,
            ..Default::default()
        };
        for k in 0..self.width() {
            let (w, dw) = self.kernel(xr - (base + k as i64) as f64);
            out.w[k] = w;
            out.dw[k] = dw;
        }
        out
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
