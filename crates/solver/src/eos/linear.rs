//! Linear: p = K (1 - J), as in the 88-line MLS-MPM fluid.

/// (p, K_t, U) at J.
#[inline]
pub fn eval(k: f64, j: f64) -> (f64, f64, f64) {
    let p = k * (1.0 - j);
    (p, k * j, 0.5 * k * (1.0 - j) * (1.0 - j))
}

pub fn j_at(k: f64, p: f64) -> f64 {
    1.0 - p / k
}
