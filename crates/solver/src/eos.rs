//! Equations of state (PHYSICS.md section 2): pressure positive in compression,
//! U' = -p, K_t = -J dp/dJ. The thermal option evaluates them at J / j_res.

use crate::config::{EosKind, Material};
use crate::{eos_linear, eos_power, eos_tait};

/// Pressure, tangent bulk modulus and stored energy per reference volume.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EosState {
    pub pressure: f64,
    pub tangent_modulus: f64,
    pub energy: f64,
}

impl Material {
    /// Unclamped EOS at the mechanical J (thermal J_res applied here).
    #[inline]
    pub fn eos(&self, j: f64) -> EosState {
        // j / 1 is j exactly: skip the division in the usual case.
        let je = if self.j_res == 1.0 { j } else { j / self.j_res };
        let (p, kt, u) = match self.eos {
            EosKind::Power => eos_power::eval(self.k, self.gamma, je),
            EosKind::Tait => eos_tait::eval(self.k, je),
            EosKind::Linear => eos_linear::eval(self.k, je),
        };
        EosState {
            pressure: p,
            tangent_modulus: kt,
            energy: u,
        }
    }

    /// Pressure with the optional tension cutoff.
    #[inline]
    pub fn pressure(&self, j: f64) -> f64 {
        self.cut(self.eos(j).pressure)
    }

    /// Longitudinal wave speed c = sqrt(K_t J / rho0).
    #[inline]
    pub fn wave_speed(&self, j: f64) -> f64 {
        self.wave_speed_of(&self.eos(j), j)
    }

    #[inline]
    pub fn wave_speed_of(&self, state: &EosState, j: f64) -> f64 {
        (state.tangent_modulus * j / self.rho0).max(0.0).sqrt()
    }

    /// The tension cutoff applied to an EOS pressure.
    #[inline]
    pub fn cut(&self, p: f64) -> f64 {
        match self.pressure_floor {
            Some(floor) => p.max(floor),
            None => p,
        }
    }

    /// J at which the (uncut) pressure equals `p`: the inverse EOS.
    pub fn j_at_pressure(&self, p: f64) -> f64 {
        let je = match self.eos {
            EosKind::Power => eos_power::j_at(self.k, self.gamma, p),
            EosKind::Tait => eos_tait::j_at(self.k, p),
            EosKind::Linear => eos_linear::j_at(self.k, p),
        };
        je * self.j_res
    }
}
