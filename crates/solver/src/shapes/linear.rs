//! Linear hat: N(r) = 1 - |r| on |r| < 1. The derivative is taken one-sided
//! (intervals closed on the left) so a particle on a node line still has a
//! zero gradient sum over its stencil.

#[inline]
pub fn kernel(r: f64) -> (f64, f64) {
    if (-1.0..0.0).contains(&r) {
        (1.0 + r, 1.0)
    } else if (0.0..1.0).contains(&r) {
        (1.0 - r, -1.0)
    } else {
        (0.0, 0.0)
    }
}
