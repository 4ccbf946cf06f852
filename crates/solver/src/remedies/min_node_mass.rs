//! Minimum nodal mass for acceleration (Uintah's `minimum_mass_for_acc`,
//! `[method.min_node_mass] share`): a node whose folded mass `grid.mass`
//! (mirror images included: the mass its force is divided by) satisfies
//! 0 < m <= share x rho0 h^2 of the first material ignores its force (stress
//! and the folded gravity force) and gets a = g, with the symmetry-wall
//! condition applied as usual. The test is strict: m > threshold keeps its
//! force. Zero-mass nodes are left as they were.
//!
//! Energy: the work of the force it replaced, dt sum_i m_i (a_i - f_i / m_i)
//! . (v_i^n + v_i^{n+1}) / 2 over the guarded nodes.

use super::{Descriptor, EnergyChange, GridStep, Remedy, Setup};
use super::Check;
use crate::config_error::ConfigError;
use serde::{Deserialize, Serialize};

pub static DESCRIPTOR: Descriptor = Descriptor {
    key: "min_node_mass",
    main: Some(("share", 0.01)),
    old_keys: &[("share", "min_node_mass")],
};

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Settings {
    /// The threshold as a share of a full cell's mass rho0 h^2 (0 < share <= 1).
    pub share: f64,
}

impl Default for Settings {
    fn default() -> Self {
        Settings { share: 0.01 }
    }
}

impl super::Settings for Settings {
    fn descriptor(&self) -> &'static Descriptor {
        &DESCRIPTOR
    }
    fn validate(&self, _cfg: &Check) -> Result<(), ConfigError> {
        super::positive_up_to(self.share, 1.0, "method.min_node_mass.share")
    }
    fn build(&self, setup: &Setup) -> Box<dyn Remedy> {
        let rho0 = setup.rho0;
        let h = setup.grid.h;
        Box::new(MinNodeMass {
            min_mass: self.share * (rho0 * h * h),
        })
    }
}

#[derive(Clone)]
struct MinNodeMass {
    /// Folded nodal mass threshold (kg per metre of thickness).
    min_mass: f64,
}

impl Remedy for MinNodeMass {
    fn key(&self) -> &'static str {
        DESCRIPTOR.key
    }

    fn after_grid_update(&mut self, g: &mut GridStep) -> EnergyChange {
        let grid = &mut *g.grid;
        let mut work = 0.0;
        let mut guarded = false;
        for k in 0..grid.inside.len() {
            let n = grid.inside[k] as usize;
            let m = grid.mass[n];
            if m > 0.0 && m <= self.min_mass {
                let a = grid.project_walls(n, g.gravity);
                let v_new = grid.vel[n] + a * g.dt;
                let half = 0.5 * (grid.vel[n] + v_new);
                work += g.dt * (m * a - grid.force[n]).dot(&half);
                grid.accel[n] = a;
                grid.vel_new[n] = v_new;
                guarded = true;
            }
        }
        if guarded {
            grid.fill_vel_new(true);
        }
        EnergyChange {
            work,
            ..EnergyChange::default()
        }
    }
}
