//! Grid-velocity damping (Uintah's `artificial_damping_coeff`,
//! `[method.grid_damping] coefficient = c` in 1/s): every node's
//! acceleration loses c v_i^n, with v_i^n the velocity P2G gave it, so
//! v_i^{n+1} = v_i^n + dt (f_i / m_i - c v_i^n). Uintah's own water-statics
//! input (`hydrostatic.ups`) sets c = 5; its default is 0 (off). The
//! damping is explicit: c dt must stay below 1 (below 2 for stability);
//! the time step does not see it, as in Uintah.
//!
//! Energy: its work, dt sum_i m_i (-c v_i^n) . (v_i^n + v_i^{n+1}) / 2 over
//! the inside nodes (never positive while c dt < 2).

use super::Check;
use super::{Descriptor, EnergyChange, GridStep, Remedy, Setup};
use crate::config_error::ConfigError;
use serde::{Deserialize, Serialize};

pub static DESCRIPTOR: Descriptor = Descriptor {
    key: "grid_damping",
    main: Some(("coefficient", 5.0)),
    old_keys: &[],
};

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Settings {
    /// The damping rate c (1/s, 0 < c <= 1e4).
    pub coefficient: f64,
}

impl Default for Settings {
    fn default() -> Self {
        Settings { coefficient: 5.0 }
    }
}

impl super::Settings for Settings {
    fn descriptor(&self) -> &'static Descriptor {
        &DESCRIPTOR
    }
    fn validate(&self, _cfg: &Check) -> Result<(), ConfigError> {
        super::positive_up_to(self.coefficient, 1e4, "method.grid_damping.coefficient")
    }
    fn build(&self, _setup: &Setup) -> Box<dyn Remedy> {
        Box::new(GridDamping {
            rate: self.coefficient,
        })
    }
}

#[derive(Clone)]
struct GridDamping {
    /// c (1/s).
    rate: f64,
}

impl Remedy for GridDamping {
    fn key(&self) -> &'static str {
        DESCRIPTOR.key
    }

    fn after_grid_update(&mut self, g: &mut GridStep) -> EnergyChange {
        let grid = &mut *g.grid;
        let mut work = 0.0;
        for k in 0..grid.inside.len() {
            let n = grid.inside[k] as usize;
            let m = grid.mass[n];
            if m <= 0.0 {
                continue;
            }
            let a = grid.project_walls(n, -self.rate * grid.vel[n]);
            let v_new = grid.vel_new[n] + a * g.dt;
            let half = 0.5 * (grid.vel[n] + v_new);
            work += g.dt * m * a.dot(&half);
            grid.accel[n] += a;
            grid.vel_new[n] = v_new;
        }
        grid.fill_vel_new(true);
        EnergyChange {
            work,
            ..EnergyChange::default()
        }
    }
}
