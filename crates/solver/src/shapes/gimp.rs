//! Undeformed GIMP (Bardenhagen & Kober 2004): the hat convolved with a particle
//! characteristic function of half-width `l` (cell units, l <= 1/2), and the
//! same convolution for any width (cpGIMP, whose particles stretch).

#[inline(always)]
pub fn kernel(r: f64, l: f64) -> (f64, f64) {
    let a = r.abs();
    let s = r.signum();
    if a < l {
        (1.0 - (r * r + l * l) / (2.0 * l), -r / l)
    } else if a < 1.0 - l {
        (1.0 - a, -s)
    } else if a < 1.0 + l {
        let d = 1.0 + l - a;
        (d * d / (4.0 * l), -s * d / (2.0 * l))
    } else {
        (0.0, 0.0)
    }
}

/// The hat convolved with a particle of any half-width `l > 0` (cell units):
/// (H(r + l) - H(r - l)) / (2 l), with H the hat's antiderivative; equal to
/// [`kernel`] for l <= 1/2 up to round-off.
#[inline]
pub fn kernel_any_width(r: f64, l: f64) -> (f64, f64) {
    let inv = 0.5 / l;
    (
        (hat_integral(r + l) - hat_integral(r - l)) * inv,
        (hat(r + l) - hat(r - l)) * inv,
    )
}

/// The hat max(0, 1 - |x|).
#[inline]
fn hat(x: f64) -> f64 {
    (1.0 - x.abs()).max(0.0)
}

/// The hat's integral from -infinity to x.
#[inline]
fn hat_integral(x: f64) -> f64 {
    if x <= -1.0 {
        0.0
    } else if x <= 0.0 {
        0.5 * (1.0 + x) * (1.0 + x)
    } else if x < 1.0 {
        1.0 - 0.5 * (1.0 - x) * (1.0 - x)
    } else {
        1.0
    }
}
