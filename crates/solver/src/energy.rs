//! Energy accounting: kinetic (with APIC's affine part), gravitational,
//! stored (sum V0 U(J)) and the accumulated viscous dissipation.

use serde::{Deserialize, Serialize};

#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Energy {
    pub kinetic: f64,
    /// Kinetic energy of the APIC affine velocity, sum 1/2 m tr(C D C^T):
    /// what the particles deposit on the grid beyond 1/2 m |v|^2. Counted
    /// where D is constant (B-splines); 0 for every other transfer and shape.
    #[serde(default)]
    pub affine: f64,
    /// sum m g (y - y_floor).
    pub gravitational: f64,
    pub stored: f64,
    /// Viscous work dissipated since t = 0.
    pub dissipated: f64,
}

impl Energy {
    /// Total of the particles' velocities (kinetic + gravitational + stored
    /// + dissipated): what the injection test watches.
    pub fn total(&self) -> f64 {
        self.kinetic + self.gravitational + self.stored + self.dissipated
    }

    /// The total with APIC's affine kinetic energy: what B-spline APIC's
    /// budget conserves (with its transfer loss).
    pub fn total_with_affine(&self) -> f64 {
        self.total() + self.affine
    }

    /// Particle kinetic energy with the affine part.
    pub fn kinetic_with_affine(&self) -> f64 {
        self.kinetic + self.affine
    }
}

/// Energy that explicit (symplectic Euler) stepping may add without any
/// instability: about M g dt |dv_y| / 2 when fluid decelerates (docs/physics.md),
/// with |dv_y| bounded by the free-fall speed sqrt(2 g H) over the box height H.
pub fn injection_noise_floor(total_mass: f64, gravity: f64, height: f64, dt: f64) -> f64 {
    0.5 * total_mass * gravity * dt * (2.0 * gravity * height).sqrt()
}
