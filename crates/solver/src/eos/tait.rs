//! Tait: p = C K [exp((1 - J)/C) - 1], C = 0.0894.

pub const TAIT_C: f64 = 0.0894;

/// (p, K_t, U) at J.
#[inline]
pub fn eval(k: f64, j: f64) -> (f64, f64, f64) {
    let c = TAIT_C;
    let e = ((1.0 - j) / c).exp();
    let p = c * k * (e - 1.0);
    let kt = j * k * e;
    let u = c * k * (c * (e - 1.0) + j - 1.0);
    (p, kt, u)
}

pub fn j_at(k: f64, p: f64) -> f64 {
    1.0 - TAIT_C * (1.0 + p / (TAIT_C * k)).ln()
}
