//! Power law (Cueto-Felgueroso et al. 2004, eq. 64, density form): p = K (J^-gamma - 1).

/// (p, K_t, U) at J.
#[inline]
pub fn eval(k: f64, gamma: f64, j: f64) -> (f64, f64, f64) {
    // Integer exponents (gamma 7 is the usual water figure) by multiplication:
    // several times cheaper than pow, within an ulp or two.
    let jg = match integer_exponent(gamma) {
        Some(n) => 1.0 / powi(j, n),
        None => j.powf(-gamma),
    };
    let u = if (gamma - 1.0).abs() < 1e-12 {
        k * (j - 1.0 - j.ln())
    } else {
        energy(k, gamma, j, jg)
    };
    let (p, kt) = pressure_modulus(k, gamma, jg);
    (p, kt, u)
}

/// `eval` for an integer gamma other than 1 (`n` = gamma): no branch, so a
/// loop over particles vectorises. Same bits as `eval`.
#[inline(always)]
pub fn eval_integer(k: f64, gamma: f64, n: u32, j: f64) -> (f64, f64, f64) {
    let jg = 1.0 / powi(j, n);
    let (p, kt) = pressure_modulus(k, gamma, jg);
    (p, kt, energy(k, gamma, j, jg))
}

/// gamma as an exponent for `powi` when it is a whole number in 1..=16.
pub fn integer_exponent(gamma: f64) -> Option<u32> {
    (gamma == gamma.trunc() && (1.0..=16.0).contains(&gamma)).then_some(gamma as u32)
}

/// (p, K_t) from jg = J^-gamma.
#[inline(always)]
fn pressure_modulus(k: f64, gamma: f64, jg: f64) -> (f64, f64) {
    (k * (jg - 1.0), gamma * k * jg)
}

/// U for gamma != 1, from jg = J^-gamma.
#[inline(always)]
fn energy(k: f64, gamma: f64, j: f64, jg: f64) -> f64 {
    k * ((j * jg - 1.0) / (gamma - 1.0) + j - 1.0)
}

pub fn j_at(k: f64, gamma: f64, p: f64) -> f64 {
    (1.0 + p / k).powf(-1.0 / gamma)
}

/// x^n for n < 32 by squaring, inlined and branch-free (std's powi is a
/// library call here). Multiplying by 1.0 for a zero bit is exact, so this
/// gives the bits of the usual square-and-multiply loop.
#[inline(always)]
fn powi(x: f64, n: u32) -> f64 {
    debug_assert!(n < 32);
    let (mut base, mut acc) = (x, 1.0);
    for bit in 0..5 {
        acc *= if (n >> bit) & 1 == 1 { base } else { 1.0 };
        base *= base;
    }
    acc
}
