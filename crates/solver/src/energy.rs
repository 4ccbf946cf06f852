//! Energy accounting: kinetic, gravitational, stored (sum V0 U(J)) and the
//! accumulated viscous dissipation.

use serde::{Deserialize, Serialize};

#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Energy {
    pub kinetic: f64,
    /// sum m g (y - y_floor).
    pub gravitational: f64,
    pub stored: f64,
    /// Viscous work dissipated since t = 0.
    pub dissipated: f64,
}

impl Energy {
    /// Conserved total (kinetic + gravitational + stored + dissipated).
    pub fn total(&self) -> f64 {
        self.kinetic + self.gravitational + self.stored + self.dissipated
    }
}

/// Energy that explicit (symplectic Euler) stepping may add without any
/// instability: about M g dt |dv_y| / 2 when fluid decelerates (docs/physics.md),
/// with |dv_y| bounded by the free-fall speed sqrt(2 g H) over the box height H.
pub fn injection_noise_floor(total_mass: f64, gravity: f64, height: f64, dt: f64) -> f64 {
    0.5 * total_mass * gravity * dt * (2.0 * gravity * height).sqrt()
}
