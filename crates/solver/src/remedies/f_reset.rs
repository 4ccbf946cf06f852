//! F reset for fluids (`[method.f_reset]`): F <- J^(1/2) I after each update
//! (in 2D), so that no distortion accumulates in F. Pressure depends on J
//! and the viscous stress on D only, so this changes nothing but round-off
//! for shapes that ignore F; it blinds the distortion flag (not the
//! strain-rate hallmark).
//!
//! Energy: none. J is kept, and a fluid's stored energy is V0 U(J).

use super::{Descriptor, PointRule, Remedy, Setup, Supports};
use crate::choices::ShapeKind;
use crate::particles::Mat2;
use serde::{Deserialize, Serialize};
use std::sync::Arc;

pub static DESCRIPTOR: Descriptor = Descriptor {
    key: "f_reset",
    main: None,
    old_keys: &[],
};

#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Settings {}

impl super::Settings for Settings {
    fn descriptor(&self) -> &'static Descriptor {
        &DESCRIPTOR
    }
    fn supports(&self) -> Supports {
        Supports {
            // A solid's shear stress is F's; cpGIMP's and CPDI's domains follow F.
            solids: false,
            shapes: &[
                ShapeKind::Linear,
                ShapeKind::Gimp,
                ShapeKind::Bspline2,
                ShapeKind::Bspline3,
            ],
            ..Supports::ALL
        }
    }
    fn build(&self, _setup: &Setup) -> Box<dyn Remedy> {
        Box::new(FReset)
    }
}

#[derive(Clone)]
struct FReset;

impl PointRule for FReset {
    /// An inverted F is kept as it is, for the inversion checks to see.
    #[inline]
    fn deformation(&self, f_next: Mat2, j_next: f64) -> Mat2 {
        if j_next > 0.0 {
            Mat2::identity() * j_next.sqrt()
        } else {
            f_next
        }
    }
}

impl Remedy for FReset {
    fn key(&self) -> &'static str {
        DESCRIPTOR.key
    }
    fn point_rule(&self) -> Option<Arc<dyn PointRule>> {
        Some(Arc::new(FReset))
    }
}
