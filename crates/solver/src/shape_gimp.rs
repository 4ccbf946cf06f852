//! Undeformed GIMP (Bardenhagen & Kober 2004): the hat convolved with a particle
//! characteristic function of half-width `l` (cell units, l <= 1/2).

#[inline]
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
