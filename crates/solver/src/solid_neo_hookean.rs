//! Compressible neo-Hookean solid, decoupled: W = G(xi)/2 (tr b_bar - 3) +
//! U(J), b_bar = J^(-2/3) F F^T in 3D with F_zz = 1 (plane strain). The
//! volumetric part U(J) is the material's EOS, so with the Newtonian
//! viscosity (2 mu dev D) this is the slides' unified model: history part
//! psi(dev e, xi) + U(tr e) plus rate part. G = 0 is the fluid, G > 0 a
//! solid, and with `softening_strain` the history variable xi (accumulated
//! equivalent shear strain) takes a solid's shear modulus to the fluid's 0.

use crate::config::Material;
use crate::particles::Mat2;

/// The isochoric (shear) part of a particle's state.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Shear {
    /// In-plane Cauchy stress (G / J) dev(b_bar) (trace-free in 3D, so its
    /// in-plane trace is -sigma_zz).
    pub stress: Mat2,
    /// Stored energy per reference volume, G/2 (tr b_bar - 3).
    pub energy: f64,
    /// The same per unit shear modulus, (tr b_bar - 3) / 2: the energy a
    /// drop of G releases at fixed F.
    pub energy_per_modulus: f64,
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
    let per_modulus = 0.5 * (scale * tr3 - 3.0);
    Shear {
        stress: (b - Mat2::identity() * (tr3 / 3.0)) * (g * scale / j),
        // g (x / 2) is (g x) / 2 bit for bit (a power of two).
        energy: g * per_modulus,
        energy_per_modulus: per_modulus,
    }
}

/// Increment of the history variable xi over `dt` for rate of deformation
/// `d` (plane strain, D_zz = 0): sqrt(2 dev D : dev D) dt with the 3D
/// deviator, so simple shear at rate gamma' adds gamma' dt.
#[inline]
pub fn history_increment(d: &Mat2, dt: f64) -> f64 {
    (2.0 * crate::viscosity::deviator_3d(d).1).sqrt() * dt
}

impl Material {
    /// Shear modulus at history xi: G exp(-xi / softening_strain), or G.
    #[inline]
    pub fn shear_modulus_at(&self, xi: f64) -> f64 {
        if self.softening_strain > 0.0 {
            self.shear_modulus * (-xi / self.softening_strain).exp()
        } else {
            self.shear_modulus
        }
    }
}

/// Squared shear-wave contribution to the p-wave speed, 4 G J / (3 rho0)
/// (4/3 G over the current density).
#[inline]
pub fn wave_speed_squared(g: f64, j: f64, rho0: f64) -> f64 {
    4.0 * g * j / (3.0 * rho0)
}

/// Adds material `m`'s shear part (if it is a solid) at history `xi` to a
/// particle's stress, cached wave speed and stored energy (V0 W). Returns
/// the energy the softening from `xi_before` to `xi` released at this F,
/// V0 (G(xi_before) - G(xi)) (tr b_bar - 3) / 2 >= 0: it leaves the stored
/// energy for the dissipated. A particle with det F <= 0 gets none: the
/// inversion checks see it, not a NaN.
#[allow(clippy::too_many_arguments)]
#[inline]
pub fn add_to(
    m: &Material,
    f: &Mat2,
    vol0: f64,
    xi_before: f64,
    xi: f64,
    stress: &mut Mat2,
    wave: &mut f64,
    stored: &mut f64,
) -> f64 {
    let g = m.shear_modulus_at(xi);
    let j = f.determinant();
    if m.shear_modulus == 0.0 || j.is_nan() || j <= 0.0 {
        return 0.0;
    }
    let s = shear(f, g);
    *stress += s.stress;
    *stored += vol0 * s.energy;
    *wave = (*wave * *wave + wave_speed_squared(g, j, m.rho0)).sqrt();
    if xi_before == xi {
        return 0.0;
    }
    vol0 * (m.shear_modulus_at(xi_before) - g) * s.energy_per_modulus
}
