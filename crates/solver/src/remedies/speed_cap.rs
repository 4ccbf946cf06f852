//! A particle speed ceiling (Uintah's `maximum_particle_velocity`, removed
//! from Uintah in 2022; `[method.speed_cap] speed = V` in m/s): after G2P a
//! particle faster than V is slowed to V along its own direction, as
//! Uintah's interpolateToParticlesAndUpdate did ("hit speed ceiling #2",
//! SerialMPM.cc of 2014-07-01). Its default was 3e105 (off). The affine
//! matrix and the position are left as G2P made them.
//!
//! Energy: the kinetic energy it removes, sum 1/2 m (V^2 - |v|^2) over the
//! capped particles.

use super::Check;
use super::{Descriptor, EnergyChange, Remedy, Setup, Step};
use crate::config_error::ConfigError;
use serde::{Deserialize, Serialize};

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
    fn build(&self, _setup: &Setup) -> Box<dyn Remedy> {
        Box::new(SpeedCap { speed: self.speed })
    }
}

#[derive(Clone)]
struct SpeedCap {
    speed: f64,
}

impl Remedy for SpeedCap {
    fn key(&self) -> &'static str {
        DESCRIPTOR.key
    }

    fn after_g2p(&mut self, s: &mut Step) -> EnergyChange {
        let ps = &mut *s.particles;
        let mut kinetic = 0.0;
        for p in 0..ps.v.len() {
            let speed = ps.v[p].norm();
            // Not-a-number speeds are left for the monitor to see.
            if speed > self.speed {
                kinetic += 0.5 * ps.mass[p] * (self.speed * self.speed - speed * speed);
                ps.v[p] *= self.speed / speed;
            }
        }
        EnergyChange {
            kinetic,
            ..EnergyChange::default()
        }
    }
}
