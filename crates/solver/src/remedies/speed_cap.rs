//! A particle speed ceiling (Uintah's `maximum_particle_velocity`, removed
//! from Uintah in 2022; `[method.speed_cap] speed = V` in m/s), as the
//! default (USL) update of 2014 applied it ("speed ceiling #1" in
//! interpolateToParticlesAndUpdate, SerialMPM.cc of 2014-07-01): after G2P
//! a particle faster than V whose speed did not fall in the step is slowed
//! to 0.9 V along its own direction; one above V that slowed keeps its
//! speed. (The momentum form's update, ceiling #2, set V itself; it is not
//! modelled.) Its default was 3e105 (off). The affine matrix and the
//! position are left as G2P made them.
//!
//! Energy: the kinetic energy it removes, sum 1/2 m ((0.9 V)^2 - |v|^2)
//! over the capped particles.

use super::Check;
use super::{Descriptor, EnergyChange, GridStep, Remedy, Setup, Step};
use crate::config_error::ConfigError;
use serde::{Deserialize, Serialize};

/// The share of the ceiling a capped particle is slowed to.
const SLOWED_TO: f64 = 0.9;

pub static DESCRIPTOR: Descriptor = Descriptor {
    key: "speed_cap",
    main: Some(("speed", 10.0)),
    old_keys: &[],
};

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Settings {
    /// The ceiling V (m/s, 0 < V <= 1e6).
    pub speed: f64,
}

impl Default for Settings {
    fn default() -> Self {
        Settings { speed: 10.0 }
    }
}

impl super::Settings for Settings {
    fn descriptor(&self) -> &'static Descriptor {
        &DESCRIPTOR
    }
    fn validate(&self, _cfg: &Check) -> Result<(), ConfigError> {
        super::positive_up_to(self.speed, 1e6, "method.speed_cap.speed")
    }
    fn build(&self, setup: &Setup) -> Box<dyn Remedy> {
        Box::new(SpeedCap {
            speed: self.speed,
            before: vec![0.0; setup.particles],
        })
    }
}

#[derive(Clone)]
struct SpeedCap {
    speed: f64,
    /// Per particle: its speed at the step's start (before G2P).
    before: Vec<f64>,
}

impl Remedy for SpeedCap {
    fn key(&self) -> &'static str {
        DESCRIPTOR.key
    }

    fn fit_particles(&mut self, n: usize) {
        if self.before.len() < n {
            self.before.resize(n, 0.0);
        }
    }

    fn after_grid_update(&mut self, g: &mut GridStep) -> EnergyChange {
        for (b, v) in self.before.iter_mut().zip(&g.particles.v) {
            *b = v.norm();
        }
        EnergyChange::default()
    }

    fn after_g2p(&mut self, s: &mut Step) -> EnergyChange {
        let ps = &mut *s.particles;
        let slowed = SLOWED_TO * self.speed;
        let mut kinetic = 0.0;
        for p in 0..ps.v.len() {
            let speed = ps.v[p].norm();
            // Not-a-number speeds are left for the monitor to see.
            if speed > self.speed && speed >= self.before[p] {
                kinetic += 0.5 * ps.mass[p] * (slowed * slowed - speed * speed);
                ps.v[p] *= slowed / speed;
            }
        }
        EnergyChange {
            kinetic,
            ..EnergyChange::default()
        }
    }
}
