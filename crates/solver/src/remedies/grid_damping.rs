//! Grid-velocity damping (Uintah's `artificial_damping_coeff`,
//! `[method.grid_damping] coefficient = c` in 1/s): every node's
//! acceleration loses c v_i^n, with v_i^n the velocity P2G gave it, so
//! v_i^{n+1} = v_i^n + dt (f_i / m_i - c v_i^n). Uintah's own water-statics
//! input (`hydrostatic.ups`) sets c = 5; its default is 0 (off). The
//! damping is explicit: c dt must stay below 1 (below 2 for stability);
//! the time step does not see it, as in Uintah.
//!
//! Energy: its work, dt sum_i m_i (-c v_i^n) . (v_i^n + v_i^{n+1}) / 2 over
//! every active node with its own P2G mass (the ghosts' images included,
//! as the grid's kinetic energy is measured; a wall node's folded mass
//! counts its image twice): never positive while c dt < 2. Nodes the
//! minimum nodal mass guard holds are damped too.

use super::Check;
use super::{Descriptor, EnergyChange, GridStep, Remedy, Setup};
use crate::config_error::ConfigError;
use crate::particles::Vec2;
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
    fn build(&self, setup: &Setup) -> Box<dyn Remedy> {
        let g = setup.grid;
        Box::new(GridDamping {
            rate: self.coefficient,
            damping: vec![Vec2::zeros(); g.dims[0] * g.dims[1]],
        })
    }
}

#[derive(Clone)]
struct GridDamping {
    /// c (1/s).
    rate: f64,
    /// Per padded node: this step's damping acceleration (ghosts filled).
    damping: Vec<Vec2>,
}

impl Remedy for GridDamping {
    fn key(&self) -> &'static str {
        DESCRIPTOR.key
    }

    fn after_grid_update(&mut self, g: &mut GridStep) -> EnergyChange {
        let grid = &mut *g.grid;
        // A ghost may be filled from a partner outside this step's list.
        self.damping.fill(Vec2::zeros());
        for k in 0..grid.inside.len() {
            let n = grid.inside[k] as usize;
            let a = if grid.mass[n] > 0.0 {
                grid.project_walls(n, -self.rate * grid.vel[n])
            } else {
                Vec2::zeros()
            };
            self.damping[n] = a;
            grid.accel[n] += a;
            grid.vel_new[n] += a * g.dt;
        }
        grid.fill_vel_new(true);
        grid.fill(&mut self.damping);
        let mut work = 0.0;
        for &n in &grid.active {
            let n = n as usize;
            let half = 0.5 * (grid.vel[n] + grid.vel_new[n]);
            work += g.dt * grid.mass_raw[n] * self.damping[n].dot(&half);
        }
        EnergyChange {
            work,
            ..EnergyChange::default()
        }
    }
}
