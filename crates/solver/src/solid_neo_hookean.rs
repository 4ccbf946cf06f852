//! Compressible neo-Hookean solid, decoupled: W = G/2 (tr b_bar - 3) + U(J),
//! b_bar = J^(-2/3) F F^T in 3D with F_zz = 1 (plane strain). The volumetric
//! part U(J) is the material's EOS, so with the Newtonian viscosity
//! (2 mu dev D) this is the slides' unified model, history part psi(dev e) +
//! U(tr e) plus rate part: G = 0 is the fluid, G > 0 a solid.

use crate::particles::Mat2;

/// The isochoric (shear) part of a particle's state.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Shear {
    /// In-plane Cauchy stress (G / J) dev(b_bar) (trace-free in 3D, so its
    /// in-plane trace is -sigma_zz).
    pub stress: Mat2,
    /// Stored energy per reference volume, G/2 (tr b_bar - 3).
    pub energy: f64,
}

/// Shear stress and energy of deformation gradient `f` (plane strain) for
/// shear modulus `g`; J = det F must be positive.
#[inline]
pub fn shear(f: &Mat2, g: f64) -> Shear {
    let j = f.determinant();
    let b = f * f.transpose();
    let scale = j.powf(-2.0 / 3.0);
    // tr b in 3D: the in-plane trace plus F_zz^2 = 1.
    let tr3 = b.trace() + 1.0;
    Shear {
        stress: (b - Mat2::identity() * (tr3 / 3.0)) * (g * scale / j),
        energy: 0.5 * g * (scale * tr3 - 3.0),
    }
}

/// Squared shear-wave contribution to the p-wave speed, 4 G J / (3 rho0)
/// (4/3 G over the current density).
#[inline]
pub fn wave_speed_squared(g: f64, j: f64, rho0: f64) -> f64 {
    4.0 * g * j / (3.0 * rho0)
}

/// Adds material `m`'s shear part (if it is a solid) to a particle's stress,
/// cached wave speed and stored energy (V0 W). A particle with det F <= 0
/// gets none: the inversion checks see it, not a NaN.
#[inline]
pub fn add_to(
    m: &crate::config::Material,
    f: &Mat2,
    vol0: f64,
    stress: &mut Mat2,
    wave: &mut f64,
    stored: &mut f64,
) {
    let g = m.shear_modulus;
    let j = f.determinant();
    if g == 0.0 || j.is_nan() || j <= 0.0 {
        return;
    }
    let s = shear(f, g);
    *stress += s.stress;
    *stored += vol0 * s.energy;
    *wave = (*wave * *wave + wave_speed_squared(g, j, m.rho0)).sqrt();
}
