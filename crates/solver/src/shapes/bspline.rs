//! Quadratic and cubic B-splines (cell units).

#[inline]
pub fn quadratic(r: f64) -> (f64, f64) {
    let a = r.abs();
    if a < 0.5 {
        (0.75 - r * r, -2.0 * r)
    } else if a < 1.5 {
        let d = 1.5 - a;
        (0.5 * d * d, -r.signum() * d)
    } else {
        (0.0, 0.0)
    }
}

/// The quadratic B-spline's values and derivatives (per cell) on the three
/// nodes of a particle `f` cells past the first one, f in [0.5, 1.5): the
/// node distances f, f - 1, f - 2 in closed form, no branches.
#[inline(always)]
pub fn quadratic_stencil(f: f64) -> ([f64; 3], [f64; 3]) {
    let (d0, d1, d2) = (1.5 - f, f - 1.0, f - 0.5);
    (
        [0.5 * d0 * d0, 0.75 - d1 * d1, 0.5 * d2 * d2],
        [-d0, -2.0 * d1, d2],
    )
}

#[inline]
pub fn cubic(r: f64) -> (f64, f64) {
    let a = r.abs();
    let s = r.signum();
    if a < 1.0 {
        (
            0.5 * a * a * a - a * a + 2.0 / 3.0,
            s * (1.5 * a * a - 2.0 * a),
        )
    } else if a < 2.0 {
        let d = 2.0 - a;
        (d * d * d / 6.0, -s * 0.5 * d * d)
    } else {
        (0.0, 0.0)
    }
}
