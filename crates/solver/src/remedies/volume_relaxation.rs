//! Volume consistency (`[method.volume_relaxation] time`): J relaxes over
//! `time` towards J_geo = rho0 / sum N rho_i, with the grid density
//! rho_i = m_i / h^2 of the folded nodal mass (mirror images at walls
//! included), where the particle's stencil is inside the material (every
//! node it weighs holds at least `FULL_NODE_SHARE` of a full node's mass):
//! each step J_p <- (1 - b) J_p + b J_geo with b = min(dt / time, 1). The
//! particles' J then follows how closely they actually pack, so particles
//! that crowd are pressed apart by the pressure.
//!
//! Energy: the stored energy its J change makes.

use super::averaging::{each_node, set_j_booked};
use super::{Descriptor, EnergyChange, Remedy, Setup, Step, Supports};
use super::Check;
use crate::grid::FULL_NODE_SHARE;
use crate::shapes::with_width;
use crate::config_error::ConfigError;
use serde::{Deserialize, Serialize};

pub static DESCRIPTOR: Descriptor = Descriptor {
    key: "volume_relaxation",
    main: Some(("time", 0.16)),
    old_keys: &[("time", "volume_relaxation_time")],
};

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Settings {
    /// The relaxation time (s).
    pub time: f64,
}

impl Default for Settings {
    fn default() -> Self {
        Settings { time: 0.16 }
    }
}

impl super::Settings for Settings {
    fn descriptor(&self) -> &'static Descriptor {
        &DESCRIPTOR
    }
    fn supports(&self) -> Supports {
        Supports {
            mixtures: false,
            solids: false,
            // It reads per-axis weights.
            shapes: crate::shapes::TENSOR_PRODUCT,
            ..Supports::ALL
        }
    }
    fn validate(&self, cfg: &Check) -> Result<(), ConfigError> {
        super::positive_up_to(self.time, 1e3, "method.volume_relaxation.time")?;
        let r = cfg.remedies;
        let not_carried = r.j_bar.as_ref().is_some_and(|s| !s.carry)
            || r.cell_dilatation.as_ref().is_some_and(|s| !s.carry);
        if not_carried {
            return Err(ConfigError {
                key: "method.volume_relaxation".into(),
                message: "cannot be combined with an averaged J that is not carried (carry = false would undo the relaxation)".into(),
            });
        }
        Ok(())
    }
    fn build(&self, setup: &Setup) -> Box<dyn Remedy> {
        Box::new(VolumeRelaxation {
            time: self.time,
            node_mass: vec![0.0; setup.grid.mass.len()],
        })
    }
}

#[derive(Clone)]
struct VolumeRelaxation {
    time: f64,
    /// The folded nodal mass, ghosts filled.
    node_mass: Vec<f64>,
}

impl Remedy for VolumeRelaxation {
    fn key(&self) -> &'static str {
        DESCRIPTOR.key
    }

    fn after_stress(&mut self, s: &mut Step) -> (EnergyChange, bool) {
        let blend = (s.dt / self.time).min(1.0);
        let stored = with_width!(s.shape, W => self.relax::<W>(s, blend));
        (
            EnergyChange {
                stored,
                ..EnergyChange::default()
            },
            true,
        )
    }
}

impl VolumeRelaxation {
    fn relax<const W: usize>(&mut self, s: &mut Step, b: f64) -> f64 {
        let (ps, grid) = (&mut *s.particles, s.grid);
        self.node_mass.copy_from_slice(&grid.mass);
        grid.fill(&mut self.node_mass);
        let nx = grid.dims[0];
        let area = grid.h * grid.h;
        let mut stored = 0.0;
        for p in 0..ps.len() {
            let rho0 = ps.mass[p] / ps.vol0[p];
            let full = FULL_NODE_SHARE * rho0 * area;
            let (mut sum, mut inside) = (0.0, true);
            each_node::<W>(&s.stencils[p], s.shape, nx, |n, w, _, _| {
                if w != 0.0 {
                    let m = self.node_mass[n];
                    inside &= m >= full;
                    sum += w * m;
                }
            });
            if inside {
                let j_geo = rho0 * area / sum;
                stored += set_j_booked(ps, s.materials, p, (1.0 - b) * ps.j[p] + b * j_geo);
            }
        }
        stored
    }
}
