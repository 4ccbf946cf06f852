//! Newtonian viscosity in plane strain: sigma_v = 2 mu dev(D), with the 3D
//! deviator (D_zz = 0, so dev D_zz = -tr D / 3).

use crate::particles::Mat2;

pub struct Viscous {
    /// In-plane viscous stress 2 mu dev(D).
    pub stress: Mat2,
    /// In-plane |dev D| = |D - tr(D)/2 I| (Frobenius), the monitor's
    /// deformation-rate signal: zero for in-plane isotropic compression, where
    /// the 3D deviator would read 0.82 d for D = diag(d, d).
    pub dev_rate: f64,
    /// Dissipated power per current volume, 2 mu dev(D) : dev(D).
    pub power: f64,
}

/// The 3D deviator of an in-plane rate of deformation (D_zz = 0): its
/// in-plane block D - tr(D)/3 I and dev D : dev D (the zz entry -tr(D)/3
/// included).
#[inline]
pub fn deviator_3d(d: &Mat2) -> (Mat2, f64) {
    let third = (d[(0, 0)] + d[(1, 1)]) / 3.0;
    let dev = d - third * Mat2::identity();
    (dev, dev.norm_squared() + third * third)
}

#[inline]
pub fn newtonian(mu: f64, d: &Mat2) -> Viscous {
    let (dev, norm2) = deviator_3d(d);
    Viscous {
        stress: 2.0 * mu * dev,
        dev_rate: in_plane_dev_rate(d),
        power: 2.0 * mu * norm2,
    }
}

/// |D - tr(D)/2 I| of an in-plane rate of deformation (Frobenius norm).
#[inline]
pub fn in_plane_dev_rate(d: &Mat2) -> f64 {
    let half_diff = 0.5 * (d[(0, 0)] - d[(1, 1)]);
    let shear = 0.5 * (d[(0, 1)] + d[(1, 0)]);
    (2.0 * (half_diff * half_diff + shear * shear)).sqrt()
}

/// Artificial bulk viscosity (`method.bulk_damping = b`): sigma_q = zeta tr(D) I
/// with zeta = b rho0 c h, the linear bulk viscosity of explicit codes. It
/// damps acoustic ringing at a rate that vanishes as h -> 0. Returns the
/// stress and the dissipated power per current volume, zeta tr(D)^2.
#[inline]
pub fn bulk(zeta: f64, d: &Mat2) -> (Mat2, f64) {
    let tr = d.trace();
    (Mat2::identity() * (zeta * tr), zeta * tr * tr)
}
