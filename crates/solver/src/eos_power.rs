//! Power law (Cueto-Felgueroso et al. 2004, eq. 64, density form): p = K (J^-gamma - 1).

/// (p, K_t, U) at J.
#[inline]
pub fn eval(k: f64, gamma: f64, j: f64) -> (f64, f64, f64) {
    // Integer exponents (gamma 7 is the usual water figure) by multiplication:
    // several times cheaper than pow, within an ulp or two.
    let jg = if gamma == gamma.trunc() && (1.0..=16.0).contains(&gamma) {
        1.0 / powi(j, gamma as u32)
    } else {
        j.powf(-gamma)
    };
    let p = k * (jg - 1.0);
    let kt = gamma * k * jg;
    let u = if (gamma - 1.0).abs() < 1e-12 {
        k * (j - 1.0 - j.ln())
    } else {
        k * ((j * jg - 1.0) / (gamma - 1.0) + j - 1.0)
    };
    (p, kt, u)
}

pub fn j_at(k: f64, gamma: f64, p: f64) -> f64 {
    (1.0 + p / k).powf(-1.0 / gamma)
}

/// x^n by squaring, inlined (std's powi is a library call here).
#[inline(always)]
fn powi(x: f64, mut n: u32) -> f64 {
    let (mut base, mut acc) = (x, 1.0);
    while n > 0 {
        if n & 1 == 1 {
            acc *= base;
        }
        base *= base;
        n >>= 1;
    }
    acc
}
