//! Newtonian viscosity in plane strain: sigma_v = 2 mu dev(D), with the 3D
//! deviator (D_zz = 0, so dev D_zz = -tr D / 3).

use crate::particles::Mat2;

pub struct Viscous {
    /// In-plane viscous stress 2 mu dev(D).
    pub stress: Mat2,
    /// |dev D| including the out-of-plane component.
    pub dev_rate: f64,
    /// Dissipated power per current volume, 2 mu dev(D) : dev(D).
    pub power: f64,
}

#[inline]
pub fn newtonian(mu: f64, d: &Mat2) -> Viscous {
    let third = (d[(0, 0)] + d[(1, 1)]) / 3.0;
    let dev = d - third * Mat2::identity();
    let norm2 = dev.norm_squared() + third * third;
    Viscous {
        stress: 2.0 * mu * dev,
        dev_rate: norm2.sqrt(),
        power: 2.0 * mu * norm2,
    }
}
